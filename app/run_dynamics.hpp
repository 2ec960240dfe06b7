#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "export.hpp"

namespace coarsegrain::app {

/// `coarsegrain simulate`: steps the scene's "dynamics" on the fine model and on the coarse model
/// of each method (carried to the fine mesh frame by frame) and compares the trajectories. The
/// run is coarsen::simulate_models, its summary coarsen::simulate_summary (as the Python
/// module's simulate()); this writes their files.
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
/// With exports.calculix, each method's folder also gets its coarse model for other codes
/// (write_export: a CalculiX deck with a *DYNAMIC step, or the hierarchy's matrices).
/// Automatic level meshes (coarse.levels on a simplicial mesh) are made once for all hierarchy
/// methods (coarsen::with_automatic_levels); each such method writes them to its folder as
/// level_<k>.vtu, listed in its entry's "coarse.files" (paths relative to DIR).
/// @return the number of methods that failed
/// @throws InvalidScene before any work if the scene has no "dynamics" block, or with
///         exports.calculix a run no deck states (check_dynamic_export); Error if a method cannot
///         run on the scene (coarsen::validate_method) or the frames would not fit in memory
int run_simulate(const scene::Scene& scene, const std::vector<std::string>& methods,
                 const std::string& out_dir, double read_seconds, const Exports& exports = {});

/// A coarse model built beforehand (by a static comparison) for the method named.
struct BuiltModel {
    std::string method;
    coarsen::CoarseModel model;
};

/// The dynamic run of `coarsegrain demo`: run_simulate's stepping, comparison and files on models
/// already built, the fine model (its mass is computed here; it must outlive the call) and the
/// coarse models of the static comparison, which move into the run (each is freed once
/// stepped). Writes every file of run_simulate to `out_dir` but the ParaView series and returns
/// its summary (also written as out_dir/summary.json); print_simulate_table prints its table.
/// @param[in,out] failed  incremented by the methods whose run failed (reported as run_simulate)
/// @throws InvalidScene if the scene has no "dynamics" block; Error if the frames would not fit
///         in memory or the folder cannot be written
nlohmann::json simulate_built(const scene::Scene& scene, const scene::FineModel& fine,
                              std::vector<BuiltModel> coarse, const std::string& out_dir,
                              int& failed);

/// A run's figures for a report (the demo's summary.json "dynamics" and report.md): "folder",
/// "integrator", "dt", "steps", "start", "fine" {"dofs", "timings" {"per_step"}, "period": the
/// first probe's fine period or null}, "methods" (each method's entry of the summary without
/// its probe series and fine timings: "method", "coarse" {"dofs", "timings"}, "speedup",
/// "errors" {"trajectory_l2_rel", "probe_max_rel", "phase"}; or "method" and "error"),
/// "failed_methods", and "plots" (the pictures made, as paths below `folder`'s parent).
/// @param summary  the run's summary (simulate_built)
/// @param folder   the run's folder, relative to the report's
nlohmann::json simulate_overview(const nlohmann::json& summary, const std::string& folder);

/// The table of a run's summary (run_simulate, simulate_built) on stdout under the heading
/// "<command>: <scene>, <integrator>, dt, steps": per model its DOFs, factorization and per-step
/// seconds, per-step speedup, trajectory error and the lag of the first probe
/// (errors.phase[0].lag, "-" if null).
void print_simulate_table(const scene::Scene& scene, const nlohmann::json& summary,
                          const std::string& command = "coarsegrain simulate");

/// `coarsegrain modes`: the `count` lowest natural frequencies and modes of the fine model and
/// of each method's coarse model (K φ = ω² M φ; the fine mass is dynamics.mass, consistent
/// without a "dynamics" block), the coarse modes carried to the fine mesh and paired with the
/// fine ones by the modal assurance criterion. The run is coarsen::modes_models, its summary
/// coarsen::modes_summary (as the Python module's modes()); this writes their files.
///
/// Files in DIR: mode_NN.vtu per fine mode (its shape "mode", and "mode_<method>" the paired
/// coarse mode of each method), frequencies.csv and frequencies.png
/// (scripts/plot_frequencies.py); summary.json with "fine.frequencies_hz", "coarse.frequencies_hz",
/// "errors.frequency_rel" (per fine mode, against its paired coarse mode) and "mac" (the
/// pairs' MAC values, "mac_pairs" the coarse mode of each); with several methods, "methods":
/// one entry per method, named by "method". Automatic level meshes are made once for all
/// hierarchy methods and written as in run_simulate: DIR/<method>/level_<k>.vtu, listed in the
/// entry's "coarse.files".
/// @return the number of methods that failed
/// @throws Error if a method cannot run on the scene
int run_modes(const scene::Scene& scene, const std::vector<std::string>& methods, int count,
              const std::string& out_dir, double read_seconds);

}  // namespace coarsegrain::app
