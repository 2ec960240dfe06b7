#pragma once
/// @file A coarsening run as a scene defines it: the fine solution every method is compared with
/// (linear or corotated, post-warped if the scene asks), each method's coarse solution solved the
/// same way, and their errors. The CLI's `coarsegrain coarsen` / `demo` and the Python module
/// both run a method through these functions.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::coarsen {

/// The fine side of a comparison, computed once for every method.
struct FineRun {
    scene::FineModel model;
    /// The fine solution every method is compared with: linear, or corotated with the scene's
    /// "kinematics": "corotational"; post-warped with "warp": "rs" and linear kinematics.
    scene::StaticSolution solution;
    /// With corotated kinematics or a warp, the linear solution too (phase "linear solve" if it
    /// took one): the hierarchy's level diagnostics are those of the linear operator.
    std::optional<scene::StaticSolution> linear;
    /// With "warp": "rs", the post-warp of fine displacements, factorized once, when a linear
    /// solution first needs it (phase "warp"; fine_warp).
    std::shared_ptr<const fem::RsWarp> warp;
    /// [read,] assemble, [newton,] factorize, solve, [linear solve,] [warp,] [write]
    Timings timings;
    /// The fine solution at the scene's probes (size dim each).
    std::vector<Eigen::VectorXd> probes;

    /// The solution's seconds: factorizations and solves, and Newton's evaluations.
    double factorize_and_solve() const {
        return timings["newton"] + timings["factorize"] + timings["solve"];
    }
    /// The linear solution: the one the methods' fine comparisons (CoarseModel::compare_with_fine)
    /// use, with the factorization of K_ff if kept (uses_fine_factorization).
    const scene::StaticSolution& linear_solution() const { return linear ? *linear : solution; }
};

/// Solves the scene's fine model as the scene asks: corotated (scene::solve_corotated, and the
/// linear solution beside it) with "kinematics": "corotational", else linear
/// (scene::solve_static), then post-warped with "warp": "rs" and linear kinematics. The
/// solution keeps the factorization of K_ff if one of `methods` uses it
/// (uses_fine_factorization). Its phases are added to `timings` (phases already spent, e.g. the
/// CLI's "read", stay first).
/// @param[in] model  build_fine_model(scene), moved into the run
/// @throws as scene::solve_static / solve_corotated, fem::RsWarp; InvalidScene if a probe lies
///         outside the mesh
FineRun solve_fine(const scene::Scene& scene, scene::FineModel model,
                   const std::vector<std::string>& methods, Timings timings = {});

/// solve_fine on a run whose model (and timings) are set: fills in its solution, linear solution,
/// warp and probes. If it throws, run.model is unchanged.
void solve_fine(const scene::Scene& scene, FineRun& run, const std::vector<std::string>& methods);

/// The run's RS post-warp of fine displacements (Chen et al. 2019, Eq. 13), factorized on first
/// use (phase "warp" in run.timings), so that only a run with a linear solution to warp pays.
const fem::RsWarp& fine_warp(const scene::Scene& scene, FineRun& run);

/// Whether a coarse model is solved corotated on this scene: corotated kinematics and an element
/// model to rotate (the hierarchy's coarse DOFs are solved linear).
bool solves_corotated(const CoarseModel& model, const scene::Scene& scene);

/// Solves a coarse model with the scene's kinematics (solve_coarse_corotated if
/// solves_corotated, else solve_coarse), not warped. Phases "newton", "factorize", "solve".
/// @throws as solve_coarse / solve_coarse_corotated
CoarseSolution solve_coarse_for_scene(const CoarseModel& model, const scene::Scene& scene,
                                      Timings* timings = nullptr);

/// Post-warps a linear coarse solution's u_fine with the run's RS warp if the scene asks for it
/// ("warp": "rs"; corotated solutions are not warped). Phase "warp" to `timings`.
void warp_coarse_solution(CoarseSolution& solution, const scene::Scene& scene, FineRun& run,
                          Timings* timings = nullptr);

/// One method run against the fine run: its coarse model, its solution as the scene asks and
/// its errors against the fine solution.
struct MethodRun {
    CoarseModel model;
    CoarseSolution solution;  ///< u_fine post-warped if the scene asks for it
    Errors errors;            ///< compare(run.model, run.solution.u, solution.u_fine)
};

/// Builds the method's coarse model (build_coarse_model with the run's fine factorization),
/// solves it (solve_coarse_for_scene, warp_coarse_solution) and compares it with the fine solution.
/// Build phases go to the model's timings, the solve's to `timings`.
/// @throws as validate_method, build_coarse_model, solve_coarse
MethodRun run_method(const scene::Scene& scene, FineRun& run, const std::string& method,
                     Timings* timings = nullptr);

}  // namespace coarsegrain::coarsen
