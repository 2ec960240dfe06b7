#pragma once
#include <string>
#include <vector>

#include "coarsegrain/scene/scene.hpp"

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
/// @param[in] command       "coarsen" or "demo" (summary.json "command")
/// @param[in] read_seconds  time already spent reading the scene (reported as "read")
/// @return the number of methods that failed (0 with one method: its failure throws)
/// @throws Error before any work if the only method, or every method, cannot run on the scene
int run_coarsen(const scene::Scene& scene, const std::vector<std::string>& methods,
                 const std::string& out_dir, const std::string& command, double read_seconds);

}  // namespace coarsegrain::app
