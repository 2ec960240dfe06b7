#pragma once
// Steps of Algorithm 1 (private to src/mra): the solves for Z (global and localized), the
// invariance correction and the truncation.
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::mra::detail {

/// Geometry of one step (level k+1 -> level k) on the regular grids.
struct StepGeometry {
    int dim = 3;
    Eigen::Vector3i fine_cells;    ///< cells of level k+1
    Eigen::Vector3i coarse_cells;  ///< cells of level k
    Eigen::Vector3d fine_spacing;  ///< cell size of level k+1
    IndexVector fine_dofs;         ///< present DOFs of level k+1 (grid DOF indices, sorted)
    IndexVector coarse_dofs;       ///< kept DOFs of level k (grid DOF indices, sorted)
};

/// Z of Algorithm 1 line 3 with global solves: B Z^T = -R, R = W A C^{†,T}, using one CHOLMOD
/// factorization of B and blocks of columns of R. #coarse_dofs by #wavelets.
SparseMatrix global_z(const SparseMatrix& B, const SparseMatrix& R);

/// Z with localized solves (Sec. 3.5 "Fast computation"): for each coarse node i, the region
/// R_i holds the level-(k+1) nodes within `rings` grid rings (Chebyshev distance) of the node
/// coincident with i; S_i are the wavelets (rows of W) with a nonzero on a node of R_i; the rows
/// of Z for the DOFs of node i solve B[S_i, S_i] z = -R[S_i, DOFs of i] and vanish outside S_i.
/// The nodes are processed in parallel (OpenMP), each with its own sparse Cholesky factorization.
SparseMatrix localized_z(const SparseMatrix& B, const SparseMatrix& R, const SparseMatrix& W,
                         const StepGeometry& g, int rings);

/// Drops entries with |M_ij| < tau max_l |M_il| (row-relative).
void truncate_rows(SparseMatrix& M, double tau);

/// Drops off-diagonal entries with |A_ij| < tau sqrt(|A_ii A_jj|) (keeps A symmetric).
void truncate_symmetric(SparseMatrix& A, double tau);

/// Translation and rotation invariance correction (Sec. 3.5) of C̃ (#coarse_dofs by
/// #fine_dofs), in place, keeping its sparsity pattern. For every fine DOF (j, c) whose node is
/// not skipped, the entries of column (j, c) get the smallest change (Euclidean norm) after
/// which, with T_i = C̃_ij^T the blocks that carry coarse node i to fine node j,
///   sum_i T_i = I   and   sum_i T_i R(x_i - x_j) = 0,
/// R(d) = -[d]_x (3D) or (-d_y, d_x)^T (2D) mapping a rotation vector to the displacement at
/// offset d; row c of these conditions only involves column (j, c). Together they say that a
/// coarse constant displacement and a coarse infinitesimal rotation u_i = omega x x_i map to the
/// same motion at fine node j (NOTES.md: sum_i C̃_ij^T [x_i]_x = [x_j]_x).
/// @param[in] skip_fine  per level-(k+1) node: do not correct its columns
/// @return per level-(k+1) node, 1 if its columns were corrected
std::vector<char> correct_invariance(SparseMatrix& Ct, const StepGeometry& g,
                                     const std::vector<char>& skip_fine);

}  // namespace coarsegrain::mra::detail
