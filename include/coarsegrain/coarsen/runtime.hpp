#pragma once
/// @file The one runtime for every coarse model: a static solve on the coarse DOFs, carried to the
/// fine mesh, and its comparison with the fine solution (DESIGN.md "summary.json").
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/sim/corotational.hpp"

namespace coarsegrain::coarsen {

/// A coarse static solution.
struct CoarseSolution {
    Vector u;                  ///< coarse DOFs, Dirichlet values included
    Vector u_fine;             ///< to_fine * u: the coarse solution on the fine nodes
    double strain_energy = 0;  ///< ½ uᵀ K u, or the corotated energy W(u)
    /// How the Newton solve went, if the solution is corotated (solve_coarse_corotated).
    std::optional<sim::NewtonReport> newton;
};

/// Solves K u = f on the coarse DOFs with model.bc eliminated (fem::solve_static) and maps u to
/// the fine nodes. Phases "factorize" and "solve" go to `timings`.
/// @throws Error if the model's sizes disagree; NotPositiveDefinite if it does not hold
CoarseSolution solve_coarse(const CoarseModel& model, const solve::SolverOptions& options,
                            Timings* timings = nullptr);

/// The corotated model of a coarse model's elements (CoarseModel::element_model: each element
/// rotates its own tensor), over the model's DOFs (through its DOF map, if any).
/// @throws Error if the model has no element model (mra) or its DOFs disagree with it
fem::CorotatedModel corotated_model(const CoarseModel& model, fem::CorotationFrame frame);

/// `options` with the node blocking of an element model's DOFs (node_dofs = dim for nodal DOFs,
/// 1 when its DOF map combines them); unchanged for a model without elements.
solve::SolverOptions node_solver_options(const CoarseModel& model,
                                         const solve::SolverOptions& options);

/// Solves the coarse model with corotated kinematics: sim::solve_corotated_static on its element
/// model (CoarseModel::element_model, each element rotating its own tensor) with model.f and
/// model.bc, and maps u to the fine nodes. Phases "newton", "factorize" and "solve".
/// @throws Error if the model has no element model (mra) or its sizes disagree; as
///         sim::solve_corotated_static, naming the method
CoarseSolution solve_coarse_corotated(const CoarseModel& model,
                                      const sim::CorotationOptions& corotation,
                                      const solve::SolverOptions& options,
                                      Timings* timings = nullptr);

/// How far a coarse solution carried to the fine mesh, u_c, is from the fine solution u.
struct Errors {
    double energy_rel = 0;  ///< ||u_c - u||_K / ||u||_K, K the fine stiffness
    /// ||u_c - u||_K / ||g||_2 with g the load on the free DOFs (Chen 2019, Fig. 9, Table 1;
    /// the hierarchy's diagnostics normalise the same way)
    double energy_over_load = 0;
    double l2_rel = 0;                ///< |u_c - u|_2 / |u|_2 over the fine nodes
    double max_displacement_rel = 0;  ///< |max_i |u_c,i| - max_i |u_i|| / max_i |u_i|
    double compliance_ratio = 0;      ///< f.u_c / f.u: 1 is perfect, below 1 too stiff
    /// Element stresses of u_c against those of u: ||σ_c - σ||_L2 / ||σ||_L2 (Frobenius norm,
    /// element stresses weighted by element volume; Chen 2019 Fig. 16 compares the two fields).
    double stress_rel = 0;
};

/// The errors as summary.json writes them: {"energy_rel", "energy_over_load", "l2_rel",
/// "max_displacement_rel", "compliance_ratio", "stress_rel"}, the members of the same names.
nlohmann::json errors_json(const Errors& errors);

/// Compares u_c with u on the fine model (both full fine DOF vectors).
/// @throws Error if sizes disagree or the fine solution is zero
Errors compare(const scene::FineModel& fine, const Vector& u, const Vector& u_c);

/// Names of the methods `build_coarse_model` knows, in the order reports list them.
/// "mra-linear" and "mra-dirac" are "mra" with the linear / Dirac refinement (replacing
/// coarse.refinement), so that one run compares both refinements (Chen 2019, Sec. 3.7);
/// "mra-linear-blind" and "mra-dirac-blind" also use the boundary-blind Dirichlet treatment
/// (coarse.dirichlet "ignore", the construction of Chen et al. 2018 that Fig. 12 compares with).
const std::vector<std::string>& method_names();

/// The methods a scene's "coarse" block configures (what `--method all` runs): with coarse.mesh
/// effective-tensor, naive, voigt and reuss; with coarse.levels mra-linear and mra-dirac, and
/// with coarse.boundary_blind true also mra-linear-blind and mra-dirac-blind.
/// @throws InvalidScene naming the scene if it configures none
std::vector<std::string> configured_methods(const scene::Scene& scene);

/// Checks, before any assembly, that `method` can run on the scene: a coarse.mesh for the
/// effective tensors and the baselines; for the mra methods zero prescribed displacements and a
/// regular grid whose cells per axis are divisible by 2^(levels - 1), or level meshes
/// (mra::validate_level_meshes), or a simplicial fine mesh for automatic level meshes
/// (mra::validate_automatic_levels: not too many levels for its nodes). (Every option's value
/// was validated when the scene was loaded.)
/// @throws Error for an unknown method, InvalidScene naming the key otherwise
void validate_method(const scene::Scene& scene, const std::string& method);

/// Whether `method` builds its hierarchy on automatic level meshes (mra::automatic_level_meshes
/// with coarse.levels): an mra method on a simplicial fine mesh that is no grid, without
/// coarse.level_meshes.
bool uses_automatic_levels(const scene::Scene& scene, const std::string& method);

/// The scene with coarse.level_meshes made by mra::automatic_level_meshes and
/// coarse.automatic_levels_seconds set if one of `methods` that can run on the scene
/// (validate_method) uses them (uses_automatic_levels), so that all hierarchy methods of a run
/// share one set; otherwise the scene unchanged. Phase "automatic levels". Call it before the
/// fine solve.
/// @throws InvalidScene naming coarse.levels if a level cannot be made
scene::Scene with_automatic_levels(scene::Scene scene, const std::vector<std::string>& methods);

/// Whether a run of `methods` on the scene uses the fine solve's factorization of K_ff (the
/// fine stiffness without the Dirichlet DOFs), so that scene::solve_static should keep it
/// (StaticSolution::factorization, for build_coarse_model and CompareWithFine). True with a
/// direct solver (cholmod, ldlt) if one of the methods factorizes K_ff itself:
/// - an mra method adapted to the stiffness whose diagnostics compute the spectrum of the fine
///   operator, which is K_ff for every Dirichlet treatment but the penalties (they factorize
///   their own), i.e. if K_ff has at most coarse.spectrum_max_dofs rows;
/// - the effective tensors' harmonic solve with coarse.boundary "mixed" on a simplicial fine
///   mesh (on a hex or quad mesh it solves on the mesh split into simplices, another operator;
///   the pure-Neumann one pins other DOFs).
/// Otherwise keeping it would only hold its memory through the run.
bool uses_fine_factorization(const scene::Scene& scene, const scene::FineModel& fine,
                             const std::vector<std::string>& methods);

/// Builds the coarse model of `method` (one of method_names()) with the scene's coarse options.
/// An mra method on automatic level meshes (made here if uses_automatic_levels, i.e. the scene
/// did not go through with_automatic_levels) adds their seconds as the phase "automatic levels"
/// and the levels' meshes as outputs level_<k>.vtu (LevelReport::mesh_file), k = 1..q-1.
/// `fine_factorization` (optional): the fine solve's factorization of K_ff, which the
/// effective tensors' mixed harmonic solve uses where it is its operator (uses_fine_factorization).
/// @throws everything validate_method throws; Error from the method's construction
CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                               const std::string& method,
                               const solve::SpdSolver* fine_factorization = nullptr);

}  // namespace coarsegrain::coarsen
