#pragma once
/// @file The comparison of several coarsening methods on one scene (`coarsegrain demo`,
/// `coarsegrain coarsen --method a,b,...`): its table and its report (report.md with pictures).
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

/// The folder of `coarsegrain demo`'s dynamic run inside its output folder.
inline constexpr const char* kDemoDynamicsFolder = "dynamics";

/// The fine side of a comparison, computed once for every method (coarsen::solve_fine).
using FineRun = coarsen::FineRun;

/// One method's run against the fine run.
struct MethodResult {
    std::string method;
    /// Why the method could not run (its error message); empty if it ran. A failed method has
    /// no figures, only this.
    std::string failure;
    Index dofs = 0;                  ///< coarse DOFs
    double build_seconds = 0;        ///< sum of the build phases
    double factorize_and_solve = 0;  ///< coarse factorization + solve, seconds
    double speedup = 0;  ///< fine factorize + solve over coarse, measured in the same run
    coarsen::Errors errors;
    Vector u_fine;           ///< the coarse solution carried to the fine DOFs
    nlohmann::json summary;  ///< the method's summary.json
    /// The coarse model, if the comparison keeps its models for a run that follows (the demo's
    /// dynamics), without its files and fine comparison (written already).
    std::optional<coarsen::CoarseModel> model;
};

/// Writes the comparison's report into `dir` (method i's files are in dir/<method i>/; failed
/// methods appear in the table with their reason and nowhere else):
/// - report_data.json: the pictures' input (every method's row and its displacement on the
///   fine mesh's surface: boundary facets in 3D, all elements in 2D);
/// - deformed.png (the deformed fine surface of the fine solution beside each method's, one
///   camera and one colour scale of |u|) and methods.png (errors and speedup per method), made
///   by scripts/plot_report.py; mra_levels.png (error per level, Chen 2019 Fig. 9) by
///   scripts/plot_mra.py when a method wrote mra_levels.csv;
/// - report.md: the table, the pictures made and how to read them, the files; with `dynamics`
///   (the demo's dynamic run, simulate_overview) also its table and pictures.
/// Pictures need Python 3 with matplotlib; without, report.md says how to make them (make_plot).
/// Returns the pictures made (file names).
nlohmann::json write_report(const scene::Scene& scene, const std::string& command,
                            const FineRun& fine, const std::vector<MethodResult>& results,
                            const std::filesystem::path& dir,
                            const nlohmann::json* dynamics = nullptr);

/// Prints the comparison table on stdout: a row per method with coarse DOFs, build and solve
/// seconds, speedup over the fine solve and the errors.
void print_comparison_table(const scene::Scene& scene, const std::string& command,
                            const FineRun& fine, const std::vector<MethodResult>& results);

}  // namespace coarsegrain::app
