#pragma once
// Steps of Algorithm 1 (private to src/mra): the solves for Z (global and localized), the
// invariance correction and the truncation.
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "products.hpp"

namespace coarsegrain::mra::detail {

/// Number of cells of a grid with `cells` per axis in `dim` dimensions.
/// (A loop: GCC 12 gives false -Warray-bounds warnings on head(dim).prod() of a Vector3i.)
inline Index cell_count(const Eigen::Vector3i& cells, int dim) {
    Index count = 1;
    for (int a = 0; a < dim; ++a) count *= cells[a];
    return count;
}

/// A cell-wise region (Localization::Cell) is extended to the grid's boundary where it would leave
/// at most rings / kRegionSnap node layers out: a box a few layers short of the boundary clamps
/// what spans it (a layered beam's stiff plates across its section). 48x12x12 accordion, 3 levels,
/// relaxed, 6 rings: coarsest error 0.0169 -> 0.0024 (global 0.0027).
constexpr int kRegionSnap = 3;

/// Node adjacency of a mesh's elements (nodes sharing an element), as CSR: the neighbours of
/// node j are neighbours[first[j] .. first[j + 1]).
struct NodeGraph {
    std::vector<Index> first, neighbours;

    NodeGraph() = default;
    NodeGraph(const IndexMatrix& elements, Index nodes);
    Index nodes() const { return static_cast<Index>(first.size()) - 1; }
};

/// The nodes within `rings` rings of `centre` in `graph` (graph distance), in order of distance
/// (centre first). `mark` (#nodes, all 0) is used and left all 0.
std::vector<Index> nodes_within(const NodeGraph& graph, Index centre, int rings,
                                std::vector<char>& mark);

/// Geometry of one step (level k+1 -> level k): on the regular grids, their cells; on level
/// meshes, level k+1's node graph and the pivots.
struct StepGeometry {
    int dim = 3;
    Eigen::Vector3i fine_cells;    ///< cells of level k+1 (grids)
    Eigen::Vector3i coarse_cells;  ///< cells of level k (grids)
    Eigen::Vector3d fine_spacing;  ///< cell size of level k+1 (grids)
    IndexVector fine_dofs;         ///< present DOFs of level k+1 (dim * node + d, sorted)
    IndexVector coarse_dofs;       ///< kept DOFs of level k (dim * node + d, sorted)
    /// Level meshes (null on grids): the node graph of level k+1, and the node of level k+1
    /// each node of level k is centred at (pivot_nodes), around which its region grows.
    const NodeGraph* fine_graph = nullptr;
    std::vector<Index> pivots;

    bool on_grid() const { return fine_graph == nullptr; }
    Index fine_nodes() const;
    Index coarse_nodes() const;
};

/// C̃ = C^† + Z W (Eq. 11) with Z from global solves (Algorithm 1 line 3: B Z^T = -R,
/// R = W A C^{†,T}), one CHOLMOD factorization of B and blocks of columns of R, each block's rows
/// of C̃ truncated (as truncate_rows with tau and g.fine_dofs; 0: none) before they are stored,
/// so that neither Z nor C̃ is ever held densely. #coarse_dofs by #fine_dofs.
SparseMatrix global_adapted_refinement(const SparseMatrix& B, const SparseMatrix& R,
                                       const SparseMatrix& C_dagger, const SparseMatrix& W,
                                       double tau, const StepGeometry& g);

/// Rings of the localized solves' regions (on level k+1): `start`, and with defect_tolerance
/// > 0, doubled per region (up to `max`) until the Eq. 12 defect of its rows falls below it.
struct LocalizationRings {
    int start = 1;
    int max = 1;
    double defect_tolerance = 0;
};

/// C̃^k and, per node of level k, the rings of its region's final solve (0: a node without DOFs).
struct LocalizedRefinement {
    SparseMatrix Ct;
    std::vector<int> rings;
};

/// C̃^k = C^† + Z W (Eq. 11) with Z from localized solves (Sec. 3.5 "Fast computation"), each
/// region's rows of C̃ formed from its solution directly (Z is never assembled: at 64^3 it held
/// as many entries as C̃). For each coarse node i, the region
/// R_i holds the level-(k+1) nodes within `rings` rings of the node coincident with i: grid
/// rings (Chebyshev distance) on grids, rings of level k+1's node graph around the pivot of i
/// on level meshes (the same nodes on a hex grid); S_i are the wavelets (rows of W) with a
/// nonzero on a node of R_i; the rows
/// of Z for the DOFs of node i solve B[S_i, S_i] z = -R[S_i, DOFs of i] and vanish outside S_i.
///
/// Eq. 12 defect-driven radius (rings.defect_tolerance > 0): the rows of C̃ = C^† + Z W would
/// satisfy C̃ A W^T = 0 with global solves; the local solve makes the defect vanish on S_i
/// only. Each region starts at rings.start and doubles its rings until the relative defect
/// max_r ||(C̃ A W^T)[r, :]|| / ||(C^† A W^T)[r, :]|| of its rows is at most the tolerance, or
/// the rings reach rings.max, or the region covers the level.
///
/// Patch-wise localization: with patch > 1 the coarse nodes are grouped in blocks of patch^dim
/// nodes (by grid coordinates, block index floor(c / patch) per axis) and every node of a block
/// uses the block's region, the fine nodes within `rings` of any node of the block: one
/// factorization of B[S, S] serves all its columns. Whatever the patch, nodes (or blocks) whose
/// regions coincide after clipping to the grid share one factorization; with patch = 1 this
/// changes nothing but the cost. With `clip`, each node's rows of C̃ are formed from its block's
/// solution on the wavelets of its own region only (Options::patch_clip), so that they have the
/// support of patch 1. Patches are grid blocks: on level meshes, patch must be 1. The regions are
/// processed in parallel (OpenMP), each with its own dense (small) or sparse Cholesky
/// factorization; regions of the same shape reuse the symbolic analysis.
LocalizedRefinement localized_refinement(const SparseMatrix& B, const SparseMatrix& R,
                                         const SparseMatrix& C_dagger, const SparseMatrix& W,
                                         const StepGeometry& g, const LocalizationRings& rings,
                                         int patch, bool clip);

/// The part A_T of the fine operator from the fine elements inside one block T of patch^dim
/// cells of a coarser level (Localization::Cell; patch 1: one cell): the sum of their element
/// matrices on their present fine DOFs.
struct CellStiffness {
    Eigen::Vector3i cell;  ///< grid coordinates of T's first cell on its level
    int span = 1;          ///< cells per axis of T (the last blocks of an axis may hold fewer)
    IndexVector dofs;      ///< indices into the hierarchy's present fine DOFs, sorted
    SparseMatrix A;        ///< #dofs square
};

/// A_T for every block T of patch^dim cells of a level with `cells` per axis (blocks without
/// elements are left out); an element belongs to the cell containing its centroid. With the
/// present fine DOFs `fine_dofs` (the fixed ones eliminated) sum_T A_T is the fine operator
/// principal_submatrix(K, fine_dofs) when K is the stiffness of `materials` and `formulation`.
std::vector<CellStiffness> cell_stiffness(const mesh::Mesh& mesh,
                                          const material::ElementMaterials& materials,
                                          const IndexVector& fine_dofs,
                                          const Eigen::Vector3i& cells, int patch,
                                          fem::Formulation formulation);

/// Z with cell-wise localized solves (Localization::Cell): for every cell T of level k (parts),
/// R^T = (W Φ)[:, T] A_T (C^† Φ)[:, T]^T, Φ = Φ^{k+1} on the present fine DOFs (WPhi = W Φ,
/// CdPhi = C^† Φ), is solved on the wavelets S_T with a nonzero on a level-(k+1) node within
/// `rings` rings of T: B[S_T, S_T] z = -R^T[S_T, :], and Z = sum_T Z^T. Since sum_T A_T = A^q,
/// sum_T R^T = R = W A^{k+1} C^{†,T}: with regions spanning the grid this is the global Z.
/// One factorization per part (a cell, or a block of cells: CellStiffness), or per box where the
/// grid clips several parts' boxes to the same one; parts in parallel (OpenMP).
SparseMatrix cell_localized_z(const SparseMatrix& B, const SparseMatrix& W,
                              const SparseMatrix& WPhi, const SparseMatrix& CdPhi,
                              const std::vector<CellStiffness>& parts, const StepGeometry& g,
                              int rings);

/// C̃ = C + X by relaxed cell-wise corrections X (Options::relaxation gamma > 0), #coarse DOFs by
/// #level-(k+1) DOFs, starting from the canonical basis C Φ^{k+1} (Eq. 6). The constraint that
/// the corrector's measurements vanish (cell_localized_z, in the wavelet space) becomes the
/// penalty |G w|^2 d / (2 gamma), with G = C^k C^{k+1} .. C^{q-1} Φ^{k+1,T} (#coarse by
/// #level-(k+1) DOFs; C itself at the finest step) the measurements of the fine function w
/// stands for, and d the smallest diagonal entry of A at an interior node of level k+1 (the
/// softest material's stiffness at the level's scale): the corrector of part T minimizes
/// w^T A w / 2 + w^T Φ A_T (C Φ)^T + d / (2 gamma) |G w|^2 over the level-(k+1) vectors w
/// supported in the box of `rings` rings around T (the DOFs of its nodes but those on a face of the
/// box inside the grid), i.e. M[S_T, S_T] w = -(Φ A_T (C Φ)^T)[S_T, :] with M = A + (d / gamma)
/// G^T G, and X = sum_T w^T: the relaxed constraint energy minimization of Chung, Efendiev and
/// Leung (2018). Measuring C w instead, at a coarser step after relaxed ones (whose coefficients
/// are not measurements), lost 3-level hierarchies up to 7.6x (docs/mra-localization.md).
/// Localized, the reaction term makes the correctors decay faster. A rigid motion r with nodal
/// values r_c at level k (C^T r_c = r for the linear refinement) gives sum_i (r_c)_i w_i = 0 in
/// each part (A_T r = 0 where T touches no Dirichlet DOF), so C̃^T r_c = r without the invariance
/// correction. With boxes spanning the grid, C^T - M^{-1} A C^T = (d / gamma) M^{-1} G^T G C^T
/// spans M^{-1} G^T = A^{-1} G^T (I + (d / gamma) G A^{-1} G^T)^{-1} (Woodbury): for every gamma
/// the space the global solves give with the measurements G (with global solves at every step,
/// the global hierarchy's level k: the composed measurements are those of the global
/// construction, whose coefficients are measurements). Such a step is whole_level_refinement,
/// in the measurements' basis (its coefficients are G's, not nodal values), and does not read
/// Phi (it may be empty). A: A^{k+1}, stored as `a_stored` says (the lower triangle of a coarser
/// level, as Level::A keeps it: the step then holds no copy with both triangles; the 64^3
/// checker's A^2: 5.1 GB); Phi: Φ^{k+1} on the present fine DOFs (rows: level-(k+1) DOFs).
/// @throws Error if G and C differ in shape, or level k+1 has no interior node with all its DOFs
/// (no scale d)
SparseMatrix relaxed_adapted_refinement(const SparseMatrix& A, const SparseMatrix& C,
                                        const SparseMatrix& G, const SparseMatrix& Phi,
                                        const std::vector<CellStiffness>& parts,
                                        const StepGeometry& g, int rings, double relaxation,
                                        Stored a_stored = Stored::Both);

/// Whether the region of every part (`rings` rings around it, reaching the grid's boundary where
/// at most rings / kRegionSnap short) is the whole level k+1.
bool regions_span_level(const std::vector<CellStiffness>& parts, int rings, const StepGeometry& g);

/// C̃ = (G Y)^{-1} Y^T with Y = A^{-1} G^T: the step on the whole level k+1 with the measurements
/// G, the functions of least energy A with G C̃^T = I (the global construction's C̃ where G = C).
/// The relaxed step whose every region spans the level gives the same space for every penalty,
/// C^T - M^{-1} A C^T = Y S^{-1} G C^T with M = A + penalty G^T G and S = I / penalty + G Y
/// (Woodbury), but in the basis of coefficients G C^T, which the composed measurements after a
/// localized relaxed step can leave near singular (40x40x8 hung checker, 3 levels, 6 fine
/// rings: sigma_min / sigma_max of G C^T 4e-7, and A^k numerically singular); here A^k =
/// (G Y)^{-1}, definite whenever G has full rank. A's sparse factorization and #rows(G) solves;
/// G^T G, which is dense, is never formed (the 80x20x20 accordion's coarse step, 14,883 unknowns
/// and 2,268 measurements: G^T G took 27.8 s, M 7.5 s and M's dense factorization 15.5 s).
/// Where A is singular (no Dirichlet conditions hold the model: SpdSolver reports
/// NotPositiveDefinite), Y = M^{-1} G^T: the penalty is constant where G w is fixed, so the
/// constrained minimizer is the same. A: n x n, stored as `a_stored` says; G: m x n;
/// penalty > 0.
/// @throws Error on mismatched shapes, a penalty <= 0, or G A^{-1} G^T not definite (dependent
/// measurements); NotPositiveDefinite if M is not definite
SparseMatrix whole_level_refinement(const SparseMatrix& A, const SparseMatrix& G, double penalty,
                                    Stored a_stored = Stored::Both);

/// A sparse left inverse X^T of C^T (C X = I, the role of C^† in Eq. 11) that reproduces rigid
/// motions, X C r = r for the modes rig_fine (Rig^{k+1}), which cell localization needs: then
/// A_T X C r = A_T r = 0 and the cell-wise corrections of a rigid motion vanish. Y: the rows of C
/// scaled to unit sums, corrected as correct_invariance does (fine nodes with an absent DOF
/// skipped); then X^T = Y + (I - Y C^T) C^†, so that C X = I and X C r = Y^T C r = r. Pattern:
/// that of C plus that of (Y C^T) C^†. Linear refinement (for Dirac, C's single entry per row
/// cannot hold the rotations).
SparseMatrix rigid_left_inverse(const SparseMatrix& C, const SparseMatrix& C_dagger,
                                const StepGeometry& g, const Matrix& rig_fine,
                                const Matrix& fine_positions, double rotation_scale);

/// Truncation of C̃ by nodes of its columns (row-relative): the entries of row i at the DOFs of
/// one level-(k+1) node (columns, fine_dofs[j] / dim the node of column j) are dropped together
/// when all of them are below tau max_l |M_il|; exact zeros are dropped. The d entries of a row at
/// a node are one row of the paper's d x d coefficient C̃_ij; dropping them together keeps the
/// columns of a node in one pattern, which the run storage of C̃ (RunMatrix) and the Galerkin
/// product take at once.
void truncate_rows(SparseMatrix& M, double tau, const IndexVector& fine_dofs, int dim);

/// Rigid motions on the present DOFs `dofs` (dim * node + d, sorted) of a level with node
/// `positions` (#nodes by 3, z = 0 in 2D, in the unit of the invariance correction): dim
/// translations, then the infinitesimal rotations about the origin (1 in 2D: u = (-y, x); 3 in
/// 3D: u = omega x x); #dofs by dim + dim(dim-1)/2.
Matrix rigid_modes(int dim, const Matrix& positions, const IndexVector& dofs);

/// Translation and rotation invariance correction (Sec. 3.5) of C̃ (#coarse_dofs by
/// #fine_dofs), in place, keeping its sparsity pattern.
///
/// A fine rigid motion r has coefficients Rig^{k+1} at level k+1 and, since C C̃^T = I,
/// Rig^k = C^k Rig^{k+1} at level k (the measurements of Eq. 9). Invariance asks that the coarse
/// representation map back to the motion itself, C̃^T Rig^k = Rig^{k+1}. For Dirac refinement the
/// coefficients are nodal values and this is the printed condition (NOTES.md: sum_i C̃_ij^T = I
/// and sum_i C̃_ij^T [x_i]_x = [x_j]_x for every fine node j); for the linear refinement the
/// coefficients are weighted sums over the stencil (2^dim times the nodal value in the interior,
/// so the global C̃ has column sums 2^-dim, not 1), and the printed form would be wrong.
///
/// Row (j, c) of the condition only involves column (j, c) of C̃: for every column whose node is
/// not skipped, the entries get the smallest change (Euclidean norm) that satisfies it,
/// delta = N (N^T N)^+ (t - N^T x) with N the rows of Rig^k at the column's entries, t the row
/// of Rig^{k+1} and x the current values. The rotations are taken about x_j (and scaled by
/// `rotation_scale`) so that N^T N is well conditioned; this is an equivalent set of constraints.
/// @param[in] skip_fine       per level-(k+1) node: do not correct its columns
/// @param[in] rig_coarse      Rig^k, #coarse_dofs by m
/// @param[in] rig_fine        Rig^{k+1}, #fine_dofs by m
/// @param[in] fine_positions  per level-(k+1) node, its position in the units of the modes
/// @return per level-(k+1) node, 1 if its columns were corrected and now meet the conditions
///         (to 1e-10 relative to the target row); 0 if skipped, or if a column has too few
///         entries (N^T N singular) to meet them
std::vector<char> correct_invariance(SparseMatrix& Ct, const StepGeometry& g,
                                     const std::vector<char>& skip_fine, const Matrix& rig_coarse,
                                     const Matrix& rig_fine, const Matrix& fine_positions,
                                     double rotation_scale);

}  // namespace coarsegrain::mra::detail
