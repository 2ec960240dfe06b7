#pragma once
#include <string>
#include <vector>

#include "coarsegrain/scene/scene.hpp"
#include "export.hpp"

namespace coarsegrain::app {

/// Solves the scene's static problem once on the fine model and once on the coarse model of each
/// method, and compares them. Prints a table on stdout.
///
/// One method: DIR/summary.json (DESIGN.md keys), DIR/solution_fine.vtu,
/// DIR/solution_coarse.vtu (the coarse solution carried to the fine mesh) and the method's own
/// files. Several methods (a comparison, as `coarsegrain demo`): DIR/solution_fine.vtu once,
/// each method's files in DIR/<method>/ (its summary.json as above), and DIR/summary.json with
/// the fine figures and a "methods" array of every method's sizes, timings, errors and speedup,
/// DIR/report.md with the table and the pictures (report.hpp).
/// A method of a comparison that cannot run on the scene, or fails while it builds or solves, is
/// reported (stderr, the table, report.md, and its row of "methods" with "error": the reason)
/// and the others still run; summary.json "failed_methods" counts them.
/// With exports.calculix each method's folder also gets coarse_model.inp (Exports).
/// Automatic level meshes (coarsen::with_automatic_levels) are made once, before the fine
/// solve, and each mra method writes them to its folder as level_<k>.vtu.
/// @param[in] command       "coarsen" or "demo" (summary.json "command")
/// @param[in] read_seconds  time already spent reading the scene (reported as "read")
/// @return the number of methods that failed (0 with one method: its failure throws)
/// @throws Error before any work if the only method, or every method, cannot run on the scene
int run_coarsen(scene::Scene scene, const std::vector<std::string>& methods,
                const std::string& out_dir, const std::string& command, double read_seconds,
                const Exports& exports = {});

/// `coarsegrain demo`: the comparison of every method the scene configures (run_coarsen with
/// command "demo"), then a dynamic run of the same fine model and of the coarse models the
/// comparison built (simulate_built: the scene's "dynamics"; nothing is built twice) into
/// DIR/dynamics/. report.md gains the dynamic run's table and pictures, and summary.json its
/// overview under "dynamics" (simulate_overview). Prints both tables.
/// @return the number of methods that failed, in the comparison or in the dynamic run
/// @throws Error before any work if no method can run on the scene; InvalidScene if it has no
///         "dynamics" block
int run_demo(const scene::Scene& scene, const std::string& out_dir, double read_seconds);

}  // namespace coarsegrain::app
