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
/// @param[in] command       "coarsen" or "demo" (summary.json "command")
/// @param[in] read_seconds  time already spent reading the scene (reported as "read")
void run_coarsen(const scene::Scene& scene, const std::vector<std::string>& methods,
                 const std::string& out_dir, const std::string& command, double read_seconds);

}  // namespace coarsegrain::app
