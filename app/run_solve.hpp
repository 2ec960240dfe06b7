#pragma once
#include <string>

#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

/// `coarsegrain solve`: solves a scene's static problem on the fine mesh and writes
/// DIR/solution_fine.vtu (the name `coarsen` gives the same field) and DIR/summary.json (DESIGN.md keys); prints a short table on stdout.
/// @param[in] read_seconds  time already spent reading the scene (reported as "read")
void run_solve(const scene::Scene& scene, const std::string& out_dir, double read_seconds);

}  // namespace coarsegrain::app
