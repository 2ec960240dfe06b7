#pragma once
/// @file Sparse symmetric positive-definite solver facade.
#include <memory>
#include <string>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/solve/pcg.hpp"

namespace coarsegrain::solve {

enum class Backend {
    Cholmod,            ///< CHOLMOD supernodal Cholesky (default)
    SimplicialLDLT,     ///< Eigen SimplicialLDLT
    ConjugateGradient,  ///< Eigen CG with Jacobi preconditioner
    /// Conjugate gradients (pcg) preconditioned by SolverOptions::preconditioner, which builds
    /// the preconditioner at factorize (on the fine model of a grid scene: a multigrid cycle
    /// over the material-adapted hierarchy, mra/preconditioner.hpp).
    MraPcg,
};

/// A factorization was refused before any numeric work: its predicted size exceeds
/// SolverOptions::max_factor_bytes (or the memory available). The message names the sizes.
class FactorTooLarge : public ErrorOf<FactorTooLarge> {
  public:
    using ErrorOf::ErrorOf;
};

/// "cholmod", "ldlt", "cg", "mra-pcg".
std::string backend_name(Backend b);
/// Whether the backend iterates (cg, mra-pcg) rather than factorizes.
bool is_iterative(Backend b);

/// A solver's NotPositiveDefinite or NotConverged message without its guess at the cause (too
/// few Dirichlet conditions; for cg also the advice to use cholmod), for a caller that has
/// established the cause itself.
std::string without_singular_hint(std::string message);
/// Parses backend_name's strings. @throws Error listing the valid names
Backend parse_backend(const std::string& name);

struct SolverOptions {
    Backend backend = Backend::Cholmod;
    double cg_tolerance = 1e-12;  ///< relative residual for cg and mra-pcg
    int cg_max_iterations = 0;    ///< 0: 10 * n (cg), 1000 (mra-pcg)
    /// mra-pcg: seconds a solve of one right-hand side may take (0: no limit).
    double time_limit = 0;
    /// mra-pcg: builds the preconditioner of the factorized matrix (required by mra-pcg).
    PreconditionerFactory preconditioner;
    /// Unknowns per node when A is interleaved per node (dim for elasticity: x0 y0 z0 x1 ...).
    /// With node_dofs > 1, cholmod computes its fill-reducing ordering on the graph of nodes
    /// (about node_dofs^2 times fewer edges than A; CHOLMOD's AMD and METIS, whichever gives
    /// the smaller factor), then expands each node to its unknowns. A node is a run of at most
    /// node_dofs consecutive columns with identical patterns, so nodes with components removed
    /// by Dirichlet conditions are fine. If A has no such runs (or node_dofs = 1) CHOLMOD's
    /// default ordering is used: AMD, then METIS on A itself when AMD's fill is large. Matrices
    /// with over 90% of their entries stored keep their own order, whatever the options.
    int node_dofs = 1;
    /// cholmod: A is already in a fill-reducing, postordered order (the caller applied the
    /// permutation() of an earlier analysis of its pattern): CHOLMOD keeps A's order and reads
    /// its lower triangle in place, without the two permuted transposes per factorization that
    /// a fill-reducing ordering costs (the hierarchy's localized solves: 13% of their time at
    /// 40x20x20, rho = 5). The rows of a column may then come in any order when check_input
    /// is off.
    bool keep_order = false;
    /// Check every factorized matrix for non-finite values and symmetry (O(nnz)). Off only for
    /// matrices symmetric by construction whose values were checked upstream: the hierarchy's
    /// localized solves factorize thousands of principal submatrices of the symmetrized B^k,
    /// where the check took 5% of the time (40x20x20 hex checker, rho = 5). A non-finite
    /// value then shows up as a failed or numerically singular factorization.
    bool check_input = true;
    /// A holds only its lower triangle, diagonal included (as mra::Level::A and B keep A^k and
    /// B^k): no copy of the other triangle is made. With check_input, an entry above the
    /// diagonal is an error. Node blocks (node_dofs > 1) are not detected in a lower triangle,
    /// so CHOLMOD's default ordering is used.
    bool lower_triangle = false;
    /// cholmod: the most bytes a numeric factorization may allocate (the supernodal L, its
    /// largest update matrix and CHOLMOD's permuted copies of A, or the dense copy for a dense
    /// matrix), predicted by the symbolic analysis; analyze refuses a larger factorization
    /// with FactorTooLarge naming the sizes, instead of the operating system killing the process
    /// partway through the factorization. 0 (default): the memory available at analysis time
    /// (MemAvailable in /proc/meminfo; no limit where it cannot be read), checked for factors
    /// of 64 MB and more (the fine factorization of 64^3 hexes, 811,200 DOFs, needs 19.4 GB).
    double max_factor_bytes = 0;
};

/// Symbolic statistics of a CHOLMOD analysis.
struct FactorStats {
    /// Fill-reducing ordering: "amd" or "metis" (CHOLMOD's default on A), "node-amd" or
    /// "node-metis" (on the node graph, SolverOptions::node_dofs).
    std::string ordering;
    double nonzeros = 0;  ///< nnz(L)
    double flops = 0;     ///< floating-point operations of the numeric factorization
};

/// Dense Cholesky factorization A = L L^T by LAPACK (dpotrf: OpenBLAS's blocked, multithreaded
/// one through Debian's liblapack.so.3; one BLAS thread inside an OpenMP parallel region).
/// About 3x faster than Eigen's LLT from 1000 unknowns (1188 unknowns, one thread: 17.5-18.3 ms
/// against 50-55 ms; docs/performance.md). No checks of symmetry or definiteness beyond
/// LAPACK's pivots.
class DenseCholesky {
  public:
    /// Factorizes A (its lower triangle is read). Returns 0 on success, else the order of the
    /// leading minor that is not positive definite (LAPACK's info; solve then throws).
    /// @throws Error if A is not square
    Index compute(Matrix A);
    /// Solves A x = b (n by k) by LAPACK dpotrs.
    /// @throws Error without a successful compute, or on a size mismatch
    Matrix solve(const Matrix& b) const;
    /// b <- A^{-1} b, without a copy of b.
    /// @throws Error without a successful compute, or on a size mismatch
    void solve_in_place(Matrix& b) const;
    /// L (lower triangle; the upper holds what A had there).
    const Matrix& factor() const { return m_factor; }

  private:
    Matrix m_factor;
    bool m_ok = false;
};

/// Sets OpenBLAS's thread count before a BLAS call: OpenMP's (omp_get_max_threads), or one inside
/// an OpenMP parallel region or if `serial`; nothing if the user set OPENBLAS_NUM_THREADS or the
/// BLAS is not OpenBLAS. See spd_solver.cpp for the measurements behind the rule.
void match_blas_threads(bool serial = false);

/// C = op(A) op(B) + beta C by BLAS dgemm (op: transpose if asked), with match_blas_threads.
/// OpenBLAS picks its kernel for the CPU at run time, so it uses the vector width that the
/// library's own code, compiled for x86-64-v2, does not: 8019 x 8019 times 8019 x 1275 took
/// 1.10 s against 5.58 s in Eigen's product (2 threads, AVX-512 machine).
/// @throws Error if the sizes do not match or exceed BLAS's int
void gemm(const Eigen::Ref<const Matrix>& A, bool transpose_a, const Eigen::Ref<const Matrix>& B,
          bool transpose_b, double beta, Eigen::Ref<Matrix> C);

/// C's lower triangle += alpha A^T A by BLAS dsyrk (A k by n, C n by n; the strict upper triangle
/// is not touched), with match_blas_threads: half dgemm's flops for a Gram matrix.
/// @throws Error if the sizes do not match or exceed BLAS's int
void syrk_lower(const Eigen::Ref<const Matrix>& A, double alpha, Eigen::Ref<Matrix> C);

/// Offsets of A's column groups (size #groups + 1; A compressed): maximal runs of at most
/// `max_size` consecutive columns with identical row patterns. In an interleaved FEM matrix these
/// are the nodes (a node with components eliminated by Dirichlet conditions gives a shorter run).
std::vector<Index> column_groups(const SparseMatrix& A, int max_size);

/// Fill-reducing order of the pattern of a symmetric A (both triangles stored, rows sorted), for
/// SolverOptions::keep_order: CHOLMOD's AMD and METIS, whichever gives the smaller factor
/// nnz(L) (AMD alone without `nested_dissection`: METIS costs more than it saves on a system
/// factorized once), followed by the elimination-tree postorder (new column k = old perm[k]).
/// With node_dofs > 1 they order the graph of nodes (runs of up to node_dofs consecutive columns
/// with identical patterns), as SpdSolver's analysis does, and each node is expanded to its
/// columns.
/// @throws Error if A is not square and compressed, or node_dofs < 1
IndexVector fill_reducing_order(const SparseMatrix& A, int node_dofs = 1,
                                bool nested_dissection = true);

/// Symmetric positive-definite sparse solver that keeps its factorization: factorize once,
/// solve many right-hand sides. Checks that the matrix is square, finite and symmetric, and
/// reports a matrix that is not positive definite (e.g. a structure without Dirichlet
/// conditions: its rigid motions make it singular) as NotPositiveDefinite instead of
/// returning garbage.
///
/// The matrix must be compressed and hold both triangles (the direct backends read the lower
/// one; SolverOptions::lower_triangle takes that one alone); symmetry is checked as
/// ||A - A^T||_F <= 1e-10 ||A||_F.
///
/// Positive definiteness: a failed Cholesky (CHOLMOD) or a non-positive LDL^T pivot is
/// reported directly. A singular matrix may also factor "successfully" with a round-off pivot;
/// when the pivot ratio min(D)/max(D) is below 1e-8 the solver estimates the smallest
/// eigenvalue (two inverse-iteration steps with the factorization and the Rayleigh quotient
/// with A) and reports the matrix if it is below 1e-14 times the largest diagonal entry, i.e.
/// the condition number exceeds 1e14 (measurements in spd_solver.cpp). CG reports a
/// non-positive diagonal entry at factorize and non-convergence at solve (as Error, with the
/// iteration count and residual).
///
/// Not thread-safe: one solve at a time (CHOLMOD's workspace is shared). CHOLMOD uses its
/// supernodal factorization with BLAS/OpenMP threads as configured. The cholmod backend hands
/// matrices with over 90% of their entries stored (the coarse operators of the hierarchy) to
/// LAPACK's dense Cholesky (dpotrf) instead, with the same checks: CHOLMOD's symbolic work
/// costs more than the factorization on them.
class SpdSolver {
  public:
    /// @throws Error if cg_tolerance is not in (0, 1) or cg_max_iterations < 0
    explicit SpdSolver(SolverOptions options = {});
    ~SpdSolver();
    SpdSolver(SpdSolver&&) noexcept;
    SpdSolver& operator=(SpdSolver&&) noexcept;

    /// Symbolic analysis (ordering) of A's pattern.
    /// @throws Error if A is not square, empty or not compressed
    /// @throws FactorTooLarge (cholmod) if its factor would exceed SolverOptions::max_factor_bytes
    void analyze(const SparseMatrix& A);
    /// Numeric factorization. Analyzes A first if it was never analyzed or its pattern differs
    /// from the analyzed one (compared by size, nonzero count and a hash of the indices).
    /// @throws Error if A has a non-finite value or is not symmetric
    /// @throws NotPositiveDefinite with the size, backend and the failing pivot or eigenvalue
    void factorize(const SparseMatrix& A);
    /// analyze + factorize.
    void compute(const SparseMatrix& A);
    /// Solves A x = b (b: n, or n by k for several right-hand sides).
    /// @throws Error before a successful factorize, on a size mismatch or non-finite b, and
    ///         (CG) if the iteration does not converge
    Matrix solve(const Matrix& b) const;
    Vector solve(const Vector& b) const;

    Backend backend() const;
    /// Ordering, nnz(L) and flops of the last analysis.
    /// @throws Error unless the backend is cholmod and analyze has run
    FactorStats factor_stats() const;
    /// Fill-reducing permutation of the last analysis, postordered (new k = old p[k]).
    /// @throws Error unless the backend is cholmod and analyze has run
    IndexVector permutation() const;
    /// Size n of the analyzed matrix (0 before analyze).
    Index rows() const;

  private:
    /// factorize for the pattern of the last analyze.
    void factorize_analyzed(const SparseMatrix& A);

    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace coarsegrain::solve
