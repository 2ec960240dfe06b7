#pragma once
#include <string>

#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

/// Builds the coarse model of `method` for a scene, solves the scene's static problem on the fine
/// and on the coarse model, and writes DIR/summary.json (DESIGN.md keys), DIR/solution_fine.vtu,
/// DIR/solution_coarse.vtu (the coarse solution carried to the fine mesh) and the method's own
/// files; prints a short table on stdout.
/// @param[in] read_seconds  time already spent reading the scene (reported as "read")
void run_coarsen(const scene::Scene& scene, const std::string& method, const std::string& out_dir,
                 double read_seconds);

}  // namespace coarsegrain::app
