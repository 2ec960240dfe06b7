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

/// X Y for a sparse X and a dense Y: by BLAS through a dense copy of X where that pays (at most
/// 6e7 entries, kSparseDensePenalty), else column by column of Y in parallel (OpenMP).
/// @throws Error on mismatched sizes
Matrix sparse_times_dense(const SparseMatrix& X, const Eigen::Ref<const Matrix>& Y);

/// W A Y (m x n for W m x k, A k x k', Y k' x n) without forming A Y: column j is W (A Y[:, j]),
/// accumulated densely per thread (OpenMP over the columns), in two passes, the pattern's size
/// then the values, so the result is allocated once at its size (sparse_product holds its
/// columns apart and then copies them: twice the result, and A Y besides). B^k = W A W^T of the
/// 48^3 hex grid's fine step (5.5e7 entries): see docs/performance.md. Keeps the structural
/// pattern like product; through product when A Y pays dense.
/// @throws Error on mismatched sizes
SparseMatrix triple_product(const SparseMatrix& W, const SparseMatrix& A, const SparseMatrix& Y);

/// (M + M^T) / 2, compressed, in M's storage when M is structurally symmetric (pass an rvalue).
SparseMatrix symmetrized(SparseMatrix M);

/// How a symmetric matrix is stored: both triangles, or the lower one (diagonal included).
enum class Stored { Both, Lower };

/// The lower triangle (diagonal included) of M X M^T for symmetric X, stored as `x_stored` says.
///
/// `groups` partitions the rows of M (the columns of the result) into groups of rows with
/// nearby supports, e.g. node_blocks of the coarse level. Unless M is at least 30% dense (then
/// the product is dense, by BLAS, X too if it is dense enough, up to 6e8 entries in all), each
/// group J of at most kMaxGroup rows is done at once: (X M^T)[:, J] is accumulated densely over
/// the union of the supports of M's rows J, then M (X M^T)[:, J], by M's columns at that union
/// or, where at least half of the entries scanned meet it (dense-ish M, e.g. after global
/// solves), by M's rows with each result row in registers.
/// An M at most 5% dense (a localized C̃) is read by rows through 16 bands of its rows transposed
/// one at a time, each band's groups taking the rows past it by columns, instead of one
/// transposed copy of M (the 64^3 checker's C̃^2 with 4 rings: 7 GB); the result's columns are
/// assembled once, from blocks unmapped as they are copied (56^3 checker, 3 levels: A^2's
/// product 14.3 -> 9.8 GB peak, 54 -> 37 s).
/// Every column of M is read once per group instead of once per row of M, and the inner loops
/// are dense |J|-wide multiply-adds: on a 40x20x20 hex grid after localized solves (rho = 5 fine
/// rings) A^1 takes 6.6 s against 17.9 s for column-by-column Gustavson products, which stream
/// C̃ from memory once per column of the result. By columns, a run of consecutive columns with
/// one pattern (a node's DOFs, see truncate_rows) is taken at once, so that each row of the
/// accumulator is read and written once per run instead of once per column. Measurements of
/// each kernel: docs/performance.md.
/// X stored by its lower triangle L: the grouped kernel adds, per band of M's rows, the
/// strictly upper entries of X in the columns those rows reach, read from L's rows there
/// transposed (a band's share of L^T where M is local, e.g. W^k: B^k from the lower A^{k+1}
/// without a copy with both triangles); the dense kernel takes a copy with both triangles.
SparseMatrix congruence(const SparseMatrix& M, const SparseMatrix& X,
                        const std::vector<IndexVector>& groups, Stored x_stored = Stored::Both);

/// Largest group congruence takes.
constexpr Index kMaxGroup = 32;

/// Rows 0..n-1 in groups of `size` consecutive ones (the last may be shorter), for congruence
/// where the rows have no positions (the wavelets of W^k, in the order of their fine DOFs).
std::vector<IndexVector> consecutive_groups(Index n, Index size);

/// The DOFs `dofs` (grid DOF indices, sorted, dim per node) of a grid with `cells` per axis,
/// grouped by blocks of side^dim nodes (block index floor(x / side) per axis); each group
/// lists positions in `dofs`, ascending. Empty blocks are left out.
std::vector<IndexVector> node_blocks(const IndexVector& dofs, const Eigen::Vector3i& cells, int dim,
                                     int side);

/// The DOFs `dofs` (dim * node + d, sorted) of nodes at `positions` (#nodes by dim), grouped by
/// the unit cubes (squares) of space their nodes lie in, each cube's DOFs cut into groups of at
/// most kMaxGroup (whole nodes); each group lists positions in `dofs`, ascending.
std::vector<IndexVector> position_blocks(const IndexVector& dofs, const Matrix& positions, int dim);

}  // namespace coarsegrain::mra::detail
