#pragma once
/// @file Canonical multiresolution of nested regular grids (Chen et al. 2019, Sec. 3.2 and 3.7):
/// refinement C^k (Eq. 6), its left inverse C^{k,†} (Eq. 10) and kernel W^k (C^k W^{k,T} = 0).
///
/// Levels follow the paper: level 1 is the coarsest grid, level q the finest; level k has half the
/// cells of level k+1 along every axis, and node (i, j, l) of level k coincides with node
/// (2i, 2j, 2l) of level k+1. Node numbering at every level is that of mesh::make_grid (x fastest,
/// then y, then z); DOFs are interleaved, DOF d of node v being dim*v + d.
///
/// Every block of these matrices is a scalar times the dim x dim identity: the node-level scalar
/// matrices are built first and expanded to DOFs, restricted to the DOFs present at each level
/// (Dirichlet DOFs may be absent, see refinement_operators).
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::mra {

/// Canonical refinement stencils (Sec. 3.7).
enum class Refinement {
    Dirac,   ///< lazy wavelets: a coarse node refines to the fine node at its position only
    Linear,  ///< the refinement of (bi/tri)linear hat functions: 1D weights 1/2, 1, 1/2
};

/// Nodes per axis of a grid with `cells` cells per axis (1 along z in 2D).
Eigen::Vector3i node_counts(const Eigen::Vector3i& cells, int dim);

/// Nodes of a grid with `cells` cells per axis (cells[2] ignored in 2D).
Index grid_nodes(const Eigen::Vector3i& cells, int dim);

/// Grid coordinates (i, j, l) of node v (l = 0 in 2D).
Eigen::Vector3i node_coordinates(Index v, const Eigen::Vector3i& cells, int dim);

/// Fine node (level k+1) at the position of each coarse node (level k) with `coarse_cells`:
/// node (i, j, l) -> node (2i, 2j, 2l) of the grid with 2 coarse_cells cells.
std::vector<Index> coincident_nodes(const Eigen::Vector3i& coarse_cells, int dim);

/// Scalar node-level canonical refinement c_ij of Eq. 6: #coarse nodes by #fine nodes, the fine
/// grid having 2 coarse_cells cells per axis. Row i holds the coefficients of coarse basis
/// function i in the fine basis functions:
/// - Dirac: c_ij = 1 if j is the fine node coincident with i, else 0;
/// - Linear: c_ij = prod_axes w(x_j - x_i) over the fine nodes j within one fine cell of node i
///   along every axis, with w(0) = 1 and w(+-h) = 1/2; this is the refinement relation of
///   (bi/tri)linear hat functions (1/2 at edge midpoints, 1/4 at face centres, 1/8 at cell
///   centres in 3D). All weights are powers of two, so every product below is exact.
SparseMatrix canonical_refinement(const Eigen::Vector3i& coarse_cells, int dim,
                                  Refinement refinement);

/// Stiffness weight of every fine node: w_j = tr(K_jj) / (dim n_j), the mean diagonal stiffness
/// of node j's dim x dim block per element around it (n_j elements of `elements`). On a grid of
/// one material every node gets the same weight, the boundary nodes included.
/// @throws Error if K is not dim * #nodes square or a weight is not positive and finite
Vector stiffness_weights(const SparseMatrix& K, const IndexMatrix& elements, int dim);

/// Stiffness-weighted measurements: c_ij w_j / w_{p(i)} for the canonical refinement C_node,
/// node weights w (stiffness_weights) and p(i) = coincident[i]. Row i then measures the
/// w-weighted average of the fine displacement around coarse node i (row scaling by 1 / w_{p(i)}
/// keeps the coincident coefficient at 1 and changes neither the kernel nor the coarse space).
/// The weighted quasi-interpolation of Peterseim and Scheichl (2016) and Hellman and Målqvist
/// (2017), who show that it makes the decay of the localized corrections independent of the
/// contrast for many coefficients; see Options::measurement.
SparseMatrix weighted_refinement(SparseMatrix C_node, const std::vector<Index>& coincident,
                                 const Vector& w);

/// The canonical operators of one level pair, restricted to the DOFs present at each level.
struct RefinementOperators {
    /// Coarse DOFs kept (indices dim*node + d into the coarse grid's DOFs, sorted).
    IndexVector coarse_dofs;
    /// Coarse DOFs of the coarse grid left out (sorted): their measurement functions (rows of the
    /// canonical refinement restricted to the present fine DOFs) vanish, or no exclusive pivot
    /// was found for them (see refinement_operators).
    IndexVector dropped_dofs;
    /// C^k restricted: #coarse_dofs by #fine_dofs (Eq. 6, blocks c_ij I).
    SparseMatrix C;
    /// A left inverse of C: C_dagger C^T = I, #coarse_dofs by #fine_dofs (Eq. 10's C^{k,†}).
    SparseMatrix C_dagger;
    /// Kernel of C: #wavelets by #fine_dofs with C W^T = 0, full row rank, #wavelets = #fine_dofs
    /// - #coarse_dofs (Sec. 3.2 "Kernel matrix").
    SparseMatrix W;
};

/// Builds C^k, a left inverse C^{k,†} and the kernel W^k on the present DOFs.
///
/// Present fine DOFs: `fine_dofs` (sorted indices into the fine grid's DOFs). A coarse DOF whose
/// coincident fine DOF is present keeps it as its pivot. A coarse DOF whose coincident fine DOF is
/// absent (a Dirichlet DOF of the finest level, or a DOF dropped at a finer level) is
/// - dropped if `keep_boundary_rows` is false (elimination: the coarse space loses the node);
/// - kept if `keep_boundary_rows` is true and its restricted row has an exclusive pivot: a present
///   fine DOF, not coincident with a coarse node, weighted by no other such row (the largest
///   weight wins, then the smallest index). For the linear refinement on a fixed boundary this is
///   the fine node one cell inside; for Dirac refinement the restricted row is empty and the DOF
///   is dropped.
///
/// With the pivots p_r, C_dagger has its support on the pivot columns, C_dagger[:, p] = D^{-T}
/// with D = C[:, p] = [[I, E], [0, F]] (rows with a coincident pivot first; F is diagonal because
/// pivots are exclusive), so D^{-1} = [[I, -E F^{-1}], [0, F^{-1}]] is exact and sparse. On the
/// rows with a coincident pivot C_dagger is the injection (for Dirac refinement C_dagger = C,
/// which is also the Moore-Penrose pseudo-inverse (C C^T)^{-1} C of Eq. 10; for the linear
/// refinement the Moore-Penrose inverse is dense, whereas any left inverse yields the same
/// minimizer of Eq. 9, and this one keeps the right-hand sides of the localized solves local).
/// The kernel is W = S (I - C^T C_dagger), S selecting the non-pivot fine DOFs: then
/// C W^T = C - C C_dagger^T C = 0 and W = [X I] in (pivot, non-pivot) columns has full rank; for
/// all DOFs present this is the block form W = [-P I] (linear) or the selection of the
/// non-coincident nodes (Dirac).
///
/// @param[in] C_node       scalar canonical refinement (canonical_refinement)
/// @param[in] coincident   coincident fine node of each coarse node (coincident_nodes)
/// @param[in] dim          2 or 3
/// @param[in] fine_dofs    present fine DOFs, sorted, in [0, dim * C_node.cols())
/// @param[in] keep_boundary_rows  see above
RefinementOperators refinement_operators(const SparseMatrix& C_node,
                                         const std::vector<Index>& coincident, int dim,
                                         const IndexVector& fine_dofs, bool keep_boundary_rows);

/// Kronecker product S ⊗ I_dim of a scalar node matrix: entry (i, j) becomes the dim x dim block
/// (dim*i.., dim*j..) times the identity.
SparseMatrix expand_to_dofs(const SparseMatrix& S, int dim);

}  // namespace coarsegrain::mra
