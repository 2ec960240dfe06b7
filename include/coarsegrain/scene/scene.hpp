#pragma once
/// @file Scene files (JSON, DESIGN.md "command-line contract") and the fine model they define.
///
/// Every key is validated where it is read; errors are InvalidScene naming the file and the
/// JSON key (e.g. "beam.json: dirichlet[1].box.min: expected 3 numbers, got 2"). Unknown keys
/// are rejected so a typo never silently changes a simulation.
#include <initializer_list>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/homogenize/options.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/mra/options.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::scene {

/// An axis-aligned box (closed), size dim each.
struct Box {
    Eigen::VectorXd min, max;
};

/// A condition on the nodes or boundary facets inside a box.
struct BoxCondition {
    std::string key;  ///< JSON key for messages, e.g. "dirichlet[0]"
    Box box;
    Eigen::VectorXd value;  ///< prescribed displacement (dirichlet) or traction (force/area)
};

/// The scene's "coarse" block: the options of every coarsening method, parsed and validated
/// when the scene is loaded (docs/guide.md "coarse"), so that a bad value fails before any mesh
/// is read or any matrix assembled.
struct CoarseOptions {
    /// coarse.mesh, read like "mesh" (effective-tensor, naive, voigt, reuss); its material ids
    /// are ignored.
    std::optional<mesh::Mesh> mesh;
    /// coarse.normals, coarse.boundary, coarse.map (effective tensors and baselines).
    homogenize::Options homogenize;
    /// coarse.level_meshes, each read like "mesh": the meshes of the hierarchy's levels
    /// 1..q-1, coarsest first (the fine mesh is level q), simplicial; empty: nested grids, or on
    /// a simplicial fine mesh that is no grid the automatic level meshes.
    std::vector<mesh::Mesh> level_meshes;
    /// Set when level_meshes were made by coarsen::with_automatic_levels
    /// (mra::automatic_level_meshes) rather than read from the scene: the seconds that took.
    std::optional<double> automatic_levels_seconds;
    /// coarse.levels or coarse.level_meshes was given: the scene configures the
    /// material-adapted hierarchy.
    bool hierarchy = false;
    /// coarse.boundary_blind (true | false, default false): `--method all` adds the
    /// boundary-blind variants mra-linear-blind and mra-dirac-blind.
    bool boundary_blind = false;
    /// coarse.levels, refinement, radius, radius_grid, defect_tolerance, max_radius, patch,
    /// patch_clip, localization, relaxation, measurement, truncation, invariance, dirichlet
    /// (mra::validate holds).
    mra::Options mra;
    /// coarse.spectrum_max_dofs, coarse.cell_tensors.
    mra::CompareOptions mra_compare;
};

/// A parsed, validated scene.
struct Scene {
    std::string source;  ///< file name (or "demo") for messages
    int dimension = 3;
    mesh::Mesh mesh;  ///< material ids already set by the material field, if any
    std::map<int, material::Material> materials;
    material::PlaneMode plane = material::PlaneMode::Strain;
    std::vector<BoxCondition> dirichlet;
    Eigen::VectorXd gravity;  ///< size dim (zero if absent)
    std::vector<BoxCondition> traction;
    std::vector<Eigen::VectorXd> probes;
    /// "fem": {"formulation": ..}: the fine element (default standard; incompatible: hex/quad).
    fem::Formulation formulation = fem::Formulation::Standard;
    /// "solver": the backend of the fine model's systems and its options (fine_solver); coarse
    /// models and other systems use direct_solver.
    solve::SolverOptions solver;
    /// solver.levels, solver.radius, solver.smoother_degree of the mra-pcg backend.
    mra::PreconditionerOptions preconditioner;
    /// The "coarse" block, parsed and validated (CoarseOptions).
    CoarseOptions coarse;
    /// "dynamics": time stepping of `coarsegrain simulate` (absent: none; simulate requires it).
    std::optional<sim::DynamicsOptions> dynamics;
    /// "kinematics": "linear" (default) or "corotational" (Kharevych et al. 2009, Sec. 4): the
    /// fine model and every coarse element model are solved corotated.
    sim::Kinematics kinematics = sim::Kinematics::Linear;
    /// "corotation": the frame and the Newton solve of corotated kinematics.
    sim::CorotationOptions corotation;
    /// "warp": "rs" (default "none"): every linear solution carried to the fine mesh (the fine
    /// model's with linear kinematics, the hierarchy's, and the element models' with linear
    /// kinematics) is post-warped by rotation-strain coordinates (Chen et al. 2019, Sec. 4.3,
    /// Eq. 13; fem::RsWarp); corotated solutions are not.
    bool rs_warp = false;
    /// Folder that relative file names in the scene are resolved against.
    std::string base_dir;
    /// The "coarse" block as written (null if absent), for with_coarse_overrides.
    nlohmann::json coarse_block;
};

/// Meshes given directly instead of the scene's "mesh" and "coarse.mesh" keys (the Python
/// module builds them from arrays). The scene JSON must then leave out the key it replaces.
struct GivenMeshes {
    /// Replaces "mesh"; checked with mesh::validate.
    std::optional<mesh::Mesh> mesh;
    /// One material per element of `mesh` (ids 0..#E-1, which mesh.material_ids must hold), as a
    /// .vtu mesh file can carry them; the scene may then have no "materials" or
    /// "material_field". Empty: the scene's materials apply.
    std::map<int, material::Material> element_materials;
    /// Replaces "coarse.mesh"; checked with mesh::validate.
    std::optional<mesh::Mesh> coarse_mesh;
};

/// Parses and validates a "coarse" block's options, all but the meshes of coarse.mesh and
/// coarse.level_meshes (null: defaults).
/// @throws InvalidScene naming coarse.<key>, the expected values and `source`
CoarseOptions parse_coarse_options(const nlohmann::json& coarse, const std::string& source);

/// Parses and validates a "dynamics" block (all but initial_velocity's size, checked against
/// the scene's dimension by parse_scene).
/// @throws InvalidScene naming dynamics.<key>, the expected values and `source`
sim::DynamicsOptions parse_dynamics_options(const nlohmann::json& dynamics,
                                            const std::string& source);

/// Parses and validates a "corotation" block.
/// @throws InvalidScene naming corotation.<key>, the expected values and `source`
sim::CorotationOptions parse_corotation_options(const nlohmann::json& corotation,
                                                const std::string& source);

/// Parses scene JSON text. Rejects duplicate keys (naming the key's path: a repeated key
/// would otherwise silently win) and numbers beyond double range.
/// @throws InvalidScene naming `source`
nlohmann::json parse_json(std::string_view text, const std::string& source);

/// Reads and validates a scene file; relative file names inside are relative to its folder.
/// @throws InvalidScene / MeshReadError / Error naming the file and key
Scene load_scene(const std::string& file);

/// Validates a scene given as JSON. `base_dir` resolves relative file names. `given` (optional)
/// holds meshes that replace the "mesh" / "coarse.mesh" keys, which j must then leave out.
/// @throws InvalidScene / MeshReadError / Error naming `source` and the key
Scene parse_scene(const nlohmann::json& j, const std::string& source, const std::string& base_dir,
                  const GivenMeshes& given = {});

/// The scene with keys of its "coarse" block replaced or added: each key of `overrides` (a JSON
/// object, e.g. {"levels": 2, "refinement": "dirac"}) replaces the block's, and the block is
/// validated again as when the scene was loaded. A "mesh" key is read as the scene's
/// coarse.mesh (relative to base_dir); without it the scene's coarse mesh is kept.
/// @throws InvalidScene naming coarse.<key> and the scene's source
Scene with_coarse_overrides(Scene scene, const nlohmann::json& overrides);

/// The fine FEM model of a scene: mesh, materials, stiffness, load and Dirichlet conditions.
struct FineModel {
    std::string source;  ///< the scene's file name (or "demo"), for messages
    mesh::Mesh mesh;
    material::ElementMaterials materials;
    mesh::Boundary boundary;
    SparseMatrix K;  ///< num_dofs square stiffness (no conditions applied)
    Vector f;        ///< num_dofs load: gravity + traction
    fem::Dirichlet bc;
    /// One line per problem worth a user's attention (fem::locking_warnings), for stderr and
    /// summary.json's "warnings".
    std::vector<std::string> warnings;
};

/// The fine model's mass matrix (num_dofs square, fem::mass_matrix): lumped or consistent as the
/// scene's dynamics.mass says, consistent without a "dynamics" block.
SparseMatrix mass_matrix(const Scene& scene, const FineModel& model);

/// The scene's Dirichlet boxes on `mesh`: the nodes inside each box, all components fixed at
/// its value (a later box wins on shared nodes). `what` names the mesh in errors ("mesh",
/// "coarse mesh").
/// @throws InvalidScene naming the condition if a box selects no node
fem::Dirichlet dirichlet_conditions(const Scene& scene, const mesh::Mesh& mesh,
                                    const std::string& what);

/// The scene's load on `mesh` (num_dofs entries): gravity times the element masses, plus each
/// traction box's force per unit area on the boundary facets inside it.
/// @throws InvalidScene naming the condition if a traction box selects no boundary facet
Vector load_vector(const Scene& scene, const mesh::Mesh& mesh,
                   const material::ElementMaterials& materials, const mesh::Boundary& boundary,
                   const std::string& what);

/// Assembles the fine model. Phases "assemble" (stiffness, loads) are added to `timings`.
/// @throws InvalidScene if a box selects no node/facet, Error on bad elements
FineModel build_fine_model(const Scene& scene, Timings* timings = nullptr);

/// The solver options of the fine model's systems (its stiffness, step and shifted operators, all
/// on the DOFs free of the Dirichlet conditions `model.bc`): the scene's, with mra-pcg's
/// preconditioner bound to the fine mesh (mra::hierarchy_preconditioner).
solve::SolverOptions fine_solver(const Scene& scene, const FineModel& model);

/// The solver options of every other system (coarse models, warps): the scene's, or CHOLMOD's
/// defaults if the scene's backend is mra-pcg, which solves fine models only.
solve::SolverOptions direct_solver(const Scene& scene);

/// The result of a static solve on the fine model.
struct StaticSolution {
    Vector u;  ///< num_dofs displacement, interleaved
    double strain_energy = 0;
    /// The factorization of K_ff, the stiffness without the Dirichlet DOFs (FineModel::bc.dofs,
    /// fem::reduce), if kept: for further solves or the spectrum of the same operator.
    std::shared_ptr<const solve::SpdSolver> factorization;
    /// How the Newton solve went, if the solution is corotated (solve_corotated); strain_energy
    /// is then the corotated energy W(u).
    std::optional<sim::NewtonReport> newton;
};

/// Solves K u = f with the Dirichlet conditions eliminated. Phases "factorize" and "solve".
/// With `keep_factorization` the solution keeps the factorization (its memory with it).
/// @throws NotPositiveDefinite naming the source and the cause: a connected part of the mesh
///         without a Dirichlet node (its size and centre), one whose fixed DOFs do not stop its
///         rigid motions, or else (every part held) the materials' stiffness contrast, at which
///         K is numerically singular; also for conjugate gradients that do not converge for one
///         of these causes (contrast from 1e10) -- otherwise their NotConverged
StaticSolution solve_static(const FineModel& model, const solve::SolverOptions& options,
                            Timings* timings = nullptr, bool keep_factorization = false);

/// Solves the scene's fine model with corotated kinematics (Kharevych et al. 2009, Sec. 4):
/// sim::solve_corotated_static with the scene's formulation, "corotation" options and solver
/// (node-blocked ordering). Phases "newton", "factorize" and "solve".
/// @throws NotPositiveDefinite as solve_static; sim::NewtonFailed naming the source if
///         Newton's method fails at the smallest load increment
StaticSolution solve_corotated(const FineModel& model, const Scene& scene,
                               Timings* timings = nullptr);

/// The scene's probes located once on a mesh, to sample many displacement fields (the frames
/// of a time series).
class ProbeSampler {
  public:
    /// @throws InvalidScene naming the first probe that lies outside the mesh
    ProbeSampler(const Scene& scene, const mesh::Mesh& mesh);
    /// Displacement at each probe point (size dim each) of u (mesh DOFs, interleaved).
    std::vector<Eigen::VectorXd> operator()(const Vector& u) const;

  private:
    const mesh::Mesh* m_mesh;
    std::vector<mesh::Location> m_locations;
};

/// Displacement at each probe point (size dim each).
/// @throws InvalidScene naming the probe if it lies outside the mesh
std::vector<Eigen::VectorXd> probe_displacements(const Scene& scene, const mesh::Mesh& mesh,
                                                 const Vector& u);

/// The built-in demo scene (a layered composite hung from one face under gravity, with a
/// "dynamics" block: released from rest, about two periods of its lowest bending mode) as JSON.
/// @param[in] scale  1 for the full demo (48x12x12 hexes); the grid is 16b x 4b x 4b with
///                   b = round(3 scale), at least 1 (tests use 0.25: 16x4x4)
nlohmann::json demo_scene(double scale = 1.0);

}  // namespace coarsegrain::scene
