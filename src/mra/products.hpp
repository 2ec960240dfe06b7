#pragma once
// Sparse matrix products of the hierarchy's construction (private to src/mra): the products of
// Algorithm 1 (B = W A W^T, R, Φ, Ψ) and the Galerkin product A^k = C̃ A^{k+1} C̃^T, each by
// the cheapest of a sparse, a dense and a grouped kernel. All run on every OpenMP thread.
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::mra::detail {

/// X Y by the cheaper of a sparse (Gustavson) product and a dense one. The sparse product keeps
/// its structural pattern (cancellations are stored as zeros), so that matrices of the same
/// structure get the same pattern whatever the material (the localized solves reuse symbolic
/// factorizations across regions on that); the dense one stores nonzeros only.
SparseMatrix product(const SparseMatrix& X, const SparseMatrix& Y);

/// (M + M^T) / 2, compressed.
SparseMatrix symmetrized(const SparseMatrix& M);

/// The lower triangle (diagonal included) of M X M^T for symmetric X (both triangles stored).
///
/// `groups` partitions the rows of M (the columns of the result) into groups of rows with
/// nearby supports, e.g. node_blocks of the coarse level. Unless M is at least 30% dense (then
/// the product is dense, by BLAS, X too if it is dense enough, up to 6e8 entries in all), each
/// group J of at most kMaxGroup rows is done at once: (X M^T)[:, J] is accumulated densely over
/// the union of the supports of M's rows J, then M (X M^T)[:, J], by M's columns at that union
/// or, where at least half of the entries scanned meet it (dense-ish M, e.g. after global
/// solves), by M's rows with each result row in registers.
/// Every column of M is read once per group instead of once per row of M, and the inner loops
/// are dense |J|-wide multiply-adds: on a 40x20x20 hex grid after localized solves (rho = 5
/// fine rings, C̃ with 22M entries, A^1 36% dense, 2 threads) A^1 took 6.6 s and 1.4 GB peak,
/// against 17.9 s and 2.2 GB for column-by-column Gustavson products, which stream C̃ from memory
/// once per column of the result and hold X M^T. With global solves there (C̃ 132M entries, 32%
/// dense) A^1 took 97.7 s by columns, 80.6 s with the rows, and 36.8 s by the dense product.
/// By columns, a run of consecutive columns with one pattern (a node's DOFs) is taken at once,
/// so that each row of the accumulator is read and written once per run instead of once per
/// column: 32^3 hexes, Dirac, rho = 5, A^1 4.9 s -> 4.35 s, and 3.46 s once the truncation kept
/// a node's columns in one pattern (truncate_rows); 64^3: 62.4 s -> 40.7 s for both.
SparseMatrix congruence(const SparseMatrix& M, const SparseMatrix& X,
                        const std::vector<IndexVector>& groups);

/// Largest group congruence takes.
constexpr Index kMaxGroup = 32;

/// The DOFs `dofs` (grid DOF indices, sorted, dim per node) of a grid with `cells` per axis,
/// grouped by blocks of side^dim nodes (block index floor(x / side) per axis); each group
/// lists positions in `dofs`, ascending. Empty blocks are left out.
std::vector<IndexVector> node_blocks(const IndexVector& dofs, const Eigen::Vector3i& cells, int dim,
                                     int side);

}  // namespace coarsegrain::mra::detail
