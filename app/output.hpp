#pragma once
/// Pieces shared by the commands' outputs: summary.json figures and the solution VTU fields.
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/summary_json.hpp"
#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

using coarsen::fine_sizes;
using coarsen::timings_json;
using coarsen::to_std;

/// Per-node |u| of an interleaved displacement.
Vector nodal_magnitude(const Vector& u, int dim);

/// Displacement, its magnitude, E, stress and strain (physical components: xx yy zz yz xz xy,
/// or xx yy xy in 2D) and von Mises stress of a fine-mesh displacement.
io::VtuFields solution_fields(const scene::FineModel& model, const Vector& u);

/// The corotated solve's figures for summary.json "newton": the frame, tolerance, iterations,
/// increments, bisections, final residual and each iteration's load factor, residual and step.
nlohmann::json newton_json(const sim::NewtonReport& report, const sim::CorotationOptions& options);

/// One "warning: ..." line on stderr per warning (also under --quiet: they are not progress).
void print_warnings(const std::vector<std::string>& warnings);

/// [{"point": [...], "u": [...]}, ...]; with `fine` given, also "u_fine" beside each "u".
nlohmann::json probes_json(const scene::Scene& scene, const std::vector<Eigen::VectorXd>& u,
                           const std::vector<Eigen::VectorXd>* fine = nullptr);

/// An output folder for one command's run. Opening it makes the folder (or checks that it is
/// writable) and removes what the previous run listed in DIR/.coarsegrain_outputs; closing it
/// (at the end of the run, also when it fails) lists there every entry of DIR the run created.
/// So a folder never mixes two runs' outputs (a single-method summary.json beside an earlier
/// comparison's report.md and method folders), and files a user put there are never touched.
class OutputFolder {
  public:
    /// @throws Error if the folder cannot be made or written, or a listed entry not removed
    explicit OutputFolder(std::string dir);
    ~OutputFolder();
    OutputFolder(const OutputFolder&) = delete;
    OutputFolder& operator=(const OutputFolder&) = delete;

  private:
    std::string dir_;
    std::set<std::string> before_;  ///< entries of the folder once the previous run's are gone
};

/// Checks before any work that the methods can run on the scene (coarsen::validate_method): the
/// only method must; of several, at least one (the others are reported as failed when their
/// turn comes, so a comparison runs what it can). No method (the fine model alone) passes.
/// @throws Error of the only method, or naming the first reason if none of several can run
void check_methods(const scene::Scene& scene, const std::vector<std::string>& methods);

/// Writes DIR/summary.json atomically.
void write_summary(const std::string& out_dir, const nlohmann::json& summary);

}  // namespace coarsegrain::app
