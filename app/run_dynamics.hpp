#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

/// `coarsegrain simulate`: steps the scene's "dynamics" on the fine model and on the coarse model
/// of each method (carried to the fine mesh frame by frame) and compares the trajectories.
///
/// Files in DIR: fine.pvd with fine/frame_NNNNN.vtu, and <method>.pvd with
/// <method>/frame_NNNNN.vtu per method (ParaView time series: displacement, its magnitude and,
/// for a method, its error against the fine frame); trajectory.csv (time, then each model's
/// probe displacements), trajectory.png (scripts/plot_trajectory.py); animation_data.bin (the
/// fine mesh's visible surface in a view plane and every model's displacement on it at up to
/// kAnimationFrames of the saved frames, animation.hpp) and animation.gif from it
/// (scripts/plot_animation.py); summary.json with "times", "probes" ([{point, u_fine: [[..] per
/// time], u: [[..] per time]}], u with one method), "timings" {"fine": {factorize, per_step,
/// write frames, animation, ...}, "coarse": {build, mass, factorize, per_step}}, "speedup"
/// {"per_step"}, "errors" {"trajectory_l2_rel", "probe_max_rel", "phase": per probe
/// sim::compare_phase on its dominant component} and, with several methods, "methods": one such
/// entry per method, named by "method". A method that fails is reported in its entry ("error")
/// and the others still run.
/// @return the number of methods that failed
/// @throws InvalidScene before any work if the scene has no "dynamics" block; Error if a method
///         cannot run on the scene (coarsen::validate_method) or the frames would not fit in
///         memory
int run_simulate(const scene::Scene& scene, const std::vector<std::string>& methods,
                 const std::string& out_dir, double read_seconds);

/// The table of a run's summary (run_simulate) on stdout: per model its DOFs,
/// factorization and per-step seconds, per-step speedup, trajectory error and the lag of the
/// first probe (errors.phase[0].lag, "-" if null).
void print_simulate_table(const scene::Scene& scene, const nlohmann::json& summary);

/// `coarsegrain modes`: the `count` lowest natural frequencies and modes of the fine model and
/// of each method's coarse model (K φ = ω² M φ; the fine mass is dynamics.mass, consistent
/// without a "dynamics" block), the coarse modes carried to the fine mesh and paired with the
/// fine ones by the modal assurance criterion.
///
/// Files in DIR: mode_NN.vtu per fine mode (its shape "mode", and "mode_<method>" the paired
/// coarse mode of each method), frequencies.csv and frequencies.png
/// (scripts/plot_frequencies.py); summary.json with "fine.frequencies_hz", "coarse.frequencies_hz",
/// "errors.frequency_rel" (per fine mode, against its paired coarse mode) and "mac" (the
/// pairs' MAC values, "mac_pairs" the coarse mode of each); with several methods, "methods":
/// one entry per method, named by "method".
/// @return the number of methods that failed
/// @throws Error if a method cannot run on the scene
int run_modes(const scene::Scene& scene, const std::vector<std::string>& methods, int count,
              const std::string& out_dir, double read_seconds);

}  // namespace coarsegrain::app
