#pragma once
/// @file The material-adapted hierarchy as a coarsening method (`coarsen --method mra`).
#include <memory>
#include <string>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/mra/diagnostics.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/dynamics.hpp"

namespace coarsegrain::mra {

/// The coarsest level of a hierarchy as a coarse model: K = S A^1 S, f = S g^1 with
/// g^1 = C̃^1...C̃^{q-1} f, to_fine = Φ^{1,T} S, over all DOFs of the coarsest grid. S is
/// diagonal: the coefficients v of level 1 are measurements C^1...C^{q-1} u (Eq. 9), which for
/// a translation t are s t with s the row sums of the chain (s = 1 for Dirac, 4^(q-1) at
/// interior nodes of a 2D grid for the linear refinement); the model's DOFs u_c = v / s are
/// displacements of the coarse nodes. DOFs without a basis function (see
/// Level::dropped_dofs) have empty rows and columns and are fixed at 0 in bc, as are, on a
/// boundary-blind hierarchy, the DOFs of Level::fixed. `report` is a HierarchyReport: the
/// options, per level k < q nodes, dofs, wavelets, radius, build_seconds, nnz and density of C̃,
/// A and B, and the fine level's cells, nodes and nonzeros of A^q; `timings` the phases of h.
/// to_fine keeps h and applies Φ^{1,T} level by level (reconstruct) without forming Φ^1.
/// `K_fine` (fine grid DOFs square) is given when h is adapted to another operator than the
/// stiffness (Operator::Step): then K = S Φ^1 K_fine Φ^{1,T} S (galerkin_operator) instead of
/// S A^1 S.
/// @throws Error if h is a hierarchy on level meshes (Hierarchy::on_grid false)
coarsen::CoarseModel coarse_model(const std::shared_ptr<const Hierarchy>& h, const Vector& f_fine,
                                  const SparseMatrix* K_fine = nullptr);

/// Cell tensors (cell_tensors.hpp) are computed only for coarsest grids of at most this many
/// cells (one small free-body hierarchy each).
inline constexpr Index kCellTensorsMaxCells = 1024;

/// Figures of every level of `h` against the fine solution `u` (the run's own fine solve), for
/// the summary of `coarsen --method mra`: mra::diagnose for the load fine.f with
/// DiagnoseOptions {options.max_spectrum_dofs, keep_solutions, &u.u, u.factorization} (without
/// u for the penalty treatments, whose fine problem is their own): the fine operator is then
/// not factorized again if the fine solve kept its factorization. `report` is a ComparisonReport:
/// the diagnostics of the q levels, level k at index k-1, and the limit on the spectra. Each
/// level's single-level solve u^k = Φ^{k,T} (A^k)^{-1} g^k (Sec. 4.1) is a reconstruction
/// "level_<k>" of level index k-1; the table is levels_table (Figs. 8, 9: error and condition
/// number per level).
///
/// Sec. 5.6: coarsest_cells.vtu on the coarsest grid holds, per cell, the effective tensor
/// "C_eff" (Voigt), the directional Young's modulus "E_x", "E_y" ("E_z"), "E_min", "E_max" and
/// "E_directions" (at youngs_directions) of coarsest_cell_tensors (the same options as `h`), and
/// the cell averages of the stress recovered on the fine mesh from the coarsest solve,
/// "stress_coarse" = mean σ(u^1), and from the fine solve, "stress_fine" (physical components,
/// as solution VTUs; Fig. 16). The report's coarsest_cells has the file, the cells, E_min and
/// E_max over all cells and directions, and per cell E_axes, E_min, E_max; the table
/// "coarsest_youngs" has a row per cell and direction (cell, direction, E). In 2D the table
/// "coarsest_stress" has a row per fine element: centroid x, y, area, E and the stress (xx,
/// yy, xy, von Mises) of the fine solve and of the coarsest level's (Fig. 16). The cell tensors
/// (their file, report and table) are skipped (`skipped` says why) above kCellTensorsMaxCells
/// cells or if !options.cell_tensors.
coarsen::FineComparison compare_levels(const Hierarchy& h, const scene::FineModel& fine,
                                       const scene::StaticSolution& u,
                                       const CompareOptions& options);

/// Builds the hierarchy of the fine model with `options` (on nested grids, or on the level
/// meshes coarser_levels with the fine mesh as level q if given) and returns the coarsest level as
/// a CoarseModel (coarse_model) whose compare_with_fine is compare_levels with `compare` (the
/// hierarchy is kept alive by it). With options.fine_operator Operator::Step the hierarchy is
/// built on the step operator of `dynamics` (sim::step_operator with the fine mass of
/// dynamics->mass; phase "step operator" in the model's timings), the model's K is the fine
/// stiffness through it (coarse_model's K_fine), and there is no compare_with_fine: the levels'
/// operators are step operators, which the static diagnostics do not apply to.
/// @throws Error as build_hierarchy (coarsen::validate_method checks the scene beforehand), or
///         if Operator::Step comes without `dynamics`
coarsen::CoarseModel build_coarse_model(const Options& options, const CompareOptions& compare,
                                        const scene::FineModel& fine,
                                        const std::vector<mesh::Mesh>& coarser_levels = {},
                                        const sim::DynamicsOptions* dynamics = nullptr);

}  // namespace coarsegrain::mra
