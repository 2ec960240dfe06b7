#include "coarsegrain/solve/spd_solver.hpp"

#include <dlfcn.h>
#include <omp.h>

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/hash.hpp"

// LAPACK's dense Cholesky factorization and solve (Fortran ABI: OpenBLAS's LAPACK through
// Debian's liblapack.so.3 alternative). The trailing arguments are the hidden lengths of the
// character arguments.
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda,
             double* b, const int* ldb, int* info, std::size_t);
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc, std::size_t, std::size_t);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc,
            std::size_t, std::size_t);
}

namespace coarsegrain::solve {

namespace {

/// Relative asymmetry ||A - A^T||_F / ||A||_F above which a matrix is rejected.
constexpr double kSymmetryTolerance = 1e-10;

/// Pivot ratio min(D) / max(D) of the factorization (LL^T: squared ratio of L's diagonal,
/// what cholmod_rcond returns) below which the factorization is checked for numerical
/// singularity. An exactly singular matrix (a structure without enough Dirichlet conditions)
/// often factors "successfully" with a round-off pivot; its pivot ratio is then at round-off
/// level, and grows with n: up to 1.2e-13 measured on singular 3D graph Laplacians of 64K
/// unknowns with random weights. A legitimate stiffness matrix can have a small ratio too:
/// 3e-12 measured for a clamped hex beam of aspect ratio 100 with a 1e6 stiffness contrast.
/// The ratio alone thus cannot separate the two; it only selects the suspicious cases.
constexpr double kSuspectPivotRatio = 1e-8;

/// Smallest-eigenvalue estimate, relative to the largest diagonal entry of A, below which a
/// suspicious matrix is reported as not positive definite. The estimate is the Rayleigh
/// quotient z^T A z / z^T z of z from two steps of inverse iteration with the factorization,
/// evaluated with A itself: it is an upper bound of lambda_min(A), and for an exactly singular
/// matrix it is round-off of A z for z near the kernel. Measured: |rho| / max A_ii <= 3e-18
/// for every singular Laplacian that factored (2D/3D, up to 64K unknowns, weight contrast
/// 1e6), against >= 5e-10 for the same matrices made definite by one grounded node. A matrix
/// flagged by this bound has condition number > 1e14: a solve would keep at most two digits.
constexpr double kSingularEigenvalueRatio = 1e-14;

/// CHOLMOD's supernode amalgamation thresholds (Common->nrelax; CHOLMOD's defaults are 4, 16,
/// 48): supernodes of fewer columns than these are merged with their parent when the merged
/// supernode's fraction of explicit zeros stays below Common->zrelax (0.8, 0.1, 0.05, kept).
/// Larger supernodes give the dense kernels (OpenBLAS dsyrk/dgemm/dpotrf) larger blocks: the
/// 52K-DOF layered hex box of bench/ccx_vs_coarsegrain.py factorizes in 1.41-1.76 s against
/// 1.77-2.39 s with the defaults, for 11% more factor entries (docs/performance.md).
constexpr std::array<std::size_t, 3> kSupernodeRelaxation{32, 128, 512};

/// Factors below this many bytes are not checked against the available memory (reading it
/// costs a file read; the localized solves of the hierarchy analyze thousands of small ones).
constexpr double kMinCheckedFactorBytes = 64.0 * (1 << 20);

/// MemAvailable of /proc/meminfo in bytes, or infinity where it cannot be read. The process's
/// free heap pages are returned to the kernel first (return_free_memory), so that memory the
/// program freed but its allocator kept (e.g. after retain_freed_memory) counts as available:
/// after the hierarchy's build at 64^3 (bench_mra, with retain_freed_memory) MemAvailable read
/// 16.0 GB with the trim and 10.6 GB without.
double available_memory() {
    return_free_memory();
    std::ifstream in("/proc/meminfo");
    std::string line;
    while (std::getline(in, line)) {
        double kib = 0;
        if (std::sscanf(line.c_str(), "MemAvailable: %lf kB", &kib) == 1) return kib * 1024;
    }
    return std::numeric_limits<double>::infinity();
}

constexpr const char* kDirichletHint =
    "is the structure held by enough Dirichlet conditions to remove its rigid motions?";
constexpr const char* kCgAdvice =
    "the matrix may be singular (is the structure held by enough Dirichlet conditions to remove "
    "its rigid motions?) or too ill-conditioned (use cholmod)";

}  // namespace

std::string without_singular_hint(std::string message) {
    for (const std::string& advice :
         {std::string("; ") + kCgAdvice, std::string(kDirichletHint) + " "})
        if (const std::size_t at = message.find(advice); at != std::string::npos)
            message.erase(at, advice.size());
    return message;
}

namespace {

// Eigen's supernodal CHOLMOD wrapper, opened up for CHOLMOD's factor and status, and for a
// symbolic analysis with a given fill-reducing permutation.
class CholmodFactor : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> {
  public:
    CholmodFactor() {
        cholmod().print = 0;  // failures are reported by our own exceptions
        std::copy(kSupernodeRelaxation.begin(), kSupernodeRelaxation.end(), cholmod().nrelax);
    }
    /// analyzePattern with the fill-reducing permutation `perm` (new column k = old perm[k]),
    /// followed by CHOLMOD's elimination-tree postorder.
    void analyze_permuted(const SparseMatrix& A, std::vector<int>& perm) {
        if (m_cholmodFactor) cholmod_free_factor(&m_cholmodFactor, &cholmod());
        cholmod_sparse view = Eigen::viewAsCholmod(A.selfadjointView<Eigen::Lower>());
        cholmod().nmethods = 1;
        cholmod().method[0].ordering = CHOLMOD_GIVEN;
        cholmod().postorder = 1;
        m_cholmodFactor = cholmod_analyze_p(&view, perm.data(), nullptr, 0, &cholmod());
        m_isInitialized = true;
        m_info = Eigen::Success;
        m_analysisIsOk = true;
        m_factorizationIsOk = false;
    }
    /// The next analyzePattern keeps A's order, without postordering: factorizations then read
    /// A's lower triangle in place (no permuted copies).
    void use_natural_order() {
        cholmod().nmethods = 1;
        cholmod().method[0].ordering = CHOLMOD_NATURAL;
        cholmod().postorder = 0;
    }
    bool has_factor() const { return m_cholmodFactor != nullptr; }
    /// Column at which the factorization stopped (n on success).
    Index minor() const { return static_cast<Index>(m_cholmodFactor->minor); }
    bool is_supernodal() const { return m_cholmodFactor->is_super != 0; }
    int status() { return cholmod().status; }
    /// (min diag L / max diag L)^2.
    double rcond() { return cholmod_rcond(m_cholmodFactor, &cholmod()); }
    /// Fill-reducing permutation of the analysis (new column k = old permutation[k]).
    IndexVector permutation() const {
        const int* perm = static_cast<const int*>(m_cholmodFactor->Perm);
        return Eigen::Map<const IndexVector>(perm, static_cast<Index>(m_cholmodFactor->n));
    }
    /// nnz(L) and the flop count of the factorization, from the last analysis.
    double factor_nonzeros() { return cholmod().lnz; }
    /// Bytes the numeric factorization of the last analysis allocates: the supernodal L's
    /// values (explicit zeros included) and row indices, and the largest update matrix of the
    /// supernodal factorization.
    double factor_bytes() const {
        const cholmod_factor& L = *m_cholmodFactor;
        return static_cast<double>(L.xsize + L.maxcsize) * sizeof(double) +
               static_cast<double>(L.ssize) * sizeof(int);
    }
    double factor_flops() { return cholmod().fl; }
    /// CHOLMOD's code (CHOLMOD_AMD, ...) of the ordering selected by its last analysis.
    int selected_ordering() { return cholmod().method[cholmod().selected].ordering; }
};

std::string ordering_name(int ordering) {
    switch (ordering) {
        case CHOLMOD_NATURAL:
            return "natural";
        case CHOLMOD_AMD:
            return "amd";
        case CHOLMOD_METIS:
            return "metis";
        case CHOLMOD_NESDIS:
            return "nesdis";
        case CHOLMOD_COLAMD:
            return "colamd";
        default:
            return "given";
    }
}

/// Fill-reducing order of a symmetric pattern (n columns, CSC arrays p and i, lower triangle
/// read) from CHOLMOD's analysis for the ordering only (simplicial, postordered): AMD and, with
/// `nested_dissection`, METIS are tried and the one with the smaller factor kept. Returns the
/// permutation (new column k = old perm[k]) and the chosen method.
std::pair<std::vector<int>, int> order_pattern(Index n, const int* p, const int* i,
                                               bool nested_dissection) {
    cholmod_sparse pattern{};
    pattern.nrow = pattern.ncol = static_cast<std::size_t>(n);
    pattern.nzmax = static_cast<std::size_t>(p[n]);
    pattern.p = const_cast<int*>(p);
    pattern.i = const_cast<int*>(i);
    pattern.stype = -1;
    pattern.itype = CHOLMOD_INT;
    pattern.xtype = CHOLMOD_PATTERN;
    pattern.dtype = CHOLMOD_DOUBLE;
    pattern.sorted = 1;
    pattern.packed = 1;
    cholmod_common common;
    cholmod_start(&common);
    common.print = 0;
    common.nmethods = 0;
    common.method[common.nmethods++].ordering = CHOLMOD_AMD;
    if (nested_dissection) common.method[common.nmethods++].ordering = CHOLMOD_METIS;
    common.postorder = 1;
    common.supernodal = CHOLMOD_SIMPLICIAL;  // only the ordering is wanted
    cholmod_factor* L = cholmod_analyze(&pattern, &common);
    CG_VERIFY(L != nullptr,
              "solver (cholmod): ordering a pattern of {} columns failed (CHOLMOD status {}; out "
              "of memory?)",
              n, common.status);
    const int* perm = static_cast<const int*>(L->Perm);
    std::pair<std::vector<int>, int> out{std::vector<int>(perm, perm + n),
                                         common.method[common.selected].ordering};
    cholmod_free_factor(&L, &common);
    cholmod_finish(&common);
    return out;
}

/// Fill-reducing ordering of A computed on its quotient graph: one vertex per column group
/// (a node), an edge where A has an entry between two groups. CHOLMOD tries AMD and (with
/// `nested_dissection`) METIS on that graph, which has about (n / #groups)^2 times fewer edges
/// than A, and keeps the one with the smaller factor nnz(L); each group is then expanded to its
/// columns, in order. Returns the permutation (new column k = old perm[k]) and the name of the
/// graph ordering.
std::pair<std::vector<int>, std::string> group_ordering(const SparseMatrix& A,
                                                        const std::vector<Index>& start,
                                                        bool nested_dissection) {
    const Index groups = static_cast<Index>(start.size()) - 1;
    std::vector<Index> group_of(A.cols());
    for (Index g = 0; g < groups; ++g)
        std::fill(group_of.begin() + start[g], group_of.begin() + start[g + 1], g);
    // Lower triangle of the quotient graph: the rows of each group's first column (every column
    // of a group has the same pattern), mapped to groups; sorted rows give sorted groups.
    std::vector<int> p{0}, rows;
    rows.reserve(static_cast<std::size_t>(A.nonZeros() / std::max<Index>(1, A.cols() / groups)));
    for (Index g = 0; g < groups; ++g) {
        for (SparseMatrix::InnerIterator it(A, start[g]); it; ++it) {
            const Index h = group_of[it.row()];
            if (h >= g && (static_cast<int>(rows.size()) == p.back() || rows.back() != h))
                rows.push_back(h);
        }
        p.push_back(static_cast<int>(rows.size()));
    }
    const auto [group_perm, method] =
        order_pattern(groups, p.data(), rows.data(), nested_dissection);
    std::vector<int> perm;
    perm.reserve(A.cols());
    for (Index k = 0; k < groups; ++k)
        for (Index j = start[group_perm[k]]; j < start[group_perm[k] + 1]; ++j) perm.push_back(j);
    std::string name = ordering_name(method);
    return {std::move(perm), "node-" + name};
}

// Dense factorizations (DenseCholesky) of fewer unknowns run LAPACK on one thread: waking the
// second OpenBLAS thread costs more than it shares (dpotrf of 243 unknowns: 0.40 ms on 2 threads
// against 0.30-0.33 ms on one; of 1188: 10 against 17.5 ms; docs/performance.md).
constexpr Index kDenseParallelMin = 800;

using Ldlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<Index>>;
using Cg = Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper,
                                    Eigen::DiagonalPreconditioner<double>>;

// Matrices with fewer nonzeros are scanned on one thread: a parallel region costs a barrier, and
// on a busy machine (a descheduled worker) that barrier took 16 ms for a 243-DOF coarse model
// whose factorization takes 0.4 ms.
constexpr Index kParallelNonzeros = 200000;

// Matrices with more than this fraction of their entries stored are factorized in their own
// order, as dense matrices (LAPACK dpotrf): a fill-reducing ordering can save little on them and
// costs a large part of the factorization (the coarse operators of global hierarchies are
// dense), and CHOLMOD's own work on a small dense matrix (symbolic analysis, permuted transposes,
// supernode bookkeeping) costs several times its flops: the 243-DOF coarsest operator of the
// 32x8x8 beam takes 0.38-0.50 ms here against 1.6-2.4 ms through CHOLMOD (docs/performance.md).
constexpr double kDenseFraction = 0.9;

/// Whether over kDenseFraction of A's entries (of its lower triangle if `lower`) are stored.
bool is_dense(const SparseMatrix& A, bool lower) {
    const double n = static_cast<double>(A.rows());
    return static_cast<double>(A.nonZeros()) > kDenseFraction * (lower ? n * (n + 1) / 2 : n * n);
}

// Hash of the sparsity pattern: the sum of a mix of every entry's (row, column), so that the
// entries hash independently (pipelined, and in parallel over columns). Equal patterns give
// equal hashes; the solver compares n and nnz as well. (A per-column chain of mixes, each
// waiting for the previous one, took 4% of the hierarchy's localized solves.)
std::uint64_t pattern_hash(const SparseMatrix& A) {
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    std::uint64_t total = 0;
#pragma omp parallel for reduction(+ : total) schedule(static) if (A.nonZeros() > kParallelNonzeros)
    for (Index j = 0; j < A.outerSize(); ++j) {
        const std::uint64_t column = static_cast<std::uint64_t>(j) << 32;
        for (int k = outer[j]; k < outer[j + 1]; ++k)
            total += mix64(column | static_cast<std::uint32_t>(inner[k]));
    }
    return total;
}

// Checks that A's values are finite and A is symmetric: ||A - A^T||_F <= tol ||A||_F, without a
// transposed copy, in one sequential pass: column j's entries below the diagonal, (i, j) with
// i > j, are met in increasing j, so their partners (j, i) are met in increasing row order in
// column i; a cursor per column walks over them. (A binary search per entry, parallel, took 16%
// of the hierarchy's localized solves on ~1000-4000-unknown systems.)
void check_values(const SparseMatrix& A, const std::string& where) {
    const Index n = static_cast<Index>(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* value = A.valuePtr();
    std::vector<int> cursor(outer, outer + n);  // next upper entry (row < column) to match
    double norm2 = 0, asym2 = 0;
    Index bad = -1;
    // An unmatched entry a contributes a^2 twice to ||A - A^T||^2, a matched pair 2 (a - b)^2.
    const auto skip_unmatched = [&](Index i, Index below) {
        int& c = cursor[static_cast<std::size_t>(i)];
        for (; c < outer[i + 1] && inner[c] < below; ++c) asym2 += 2 * value[c] * value[c];
    };
    for (Index j = 0; j < n && bad < 0; ++j) {
        for (Index k = outer[j]; k < outer[j + 1]; ++k) {
            const Index i = inner[k];
            const double a = value[k];
            if (!std::isfinite(a)) {
                bad = j;
                break;
            }
            norm2 += a * a;
            if (i <= j) continue;
            skip_unmatched(i, j);
            int& c = cursor[static_cast<std::size_t>(i)];
            if (c < outer[i + 1] && inner[c] == j) {
                const double d = a - value[c++];
                asym2 += 2 * d * d;
            } else {
                asym2 += 2 * a * a;
            }
        }
    }
    for (Index i = 0; i < n && bad < 0; ++i) skip_unmatched(i, i);
    CG_VERIFY(bad < 0, "{}: the matrix has a non-finite value (NaN or inf) in column {}", where,
              bad);
    const double rel = norm2 > 0 ? std::sqrt(asym2 / norm2) : 0.0;
    CG_VERIFY(rel <= kSymmetryTolerance,
              "{}: the matrix is not symmetric: ||A - A^T|| / ||A|| = {:.3g} exceeds {:.0e} (both "
              "triangles must be stored)",
              where, rel, kSymmetryTolerance);
}

// Checks that a matrix given as its lower triangle (SolverOptions::lower_triangle) is finite
// and has no entry above the diagonal.
void check_lower_values(const SparseMatrix& A, const std::string& where) {
    for (Index j = 0; j < A.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(A, j); it; ++it) {
            CG_VERIFY(std::isfinite(it.value()),
                      "{}: the matrix has a non-finite value (NaN or inf) in column {}", where, j);
            CG_VERIFY(it.row() >= j,
                      "{}: entry ({}, {}) lies above the diagonal, but the solver was told it gets "
                      "the lower triangle only (lower_triangle)",
                      where, it.row(), j);
        }
}

// check_values for a dense copy D of the matrix, in tiles of kTile x kTile entries so that D's
// columns and rows are both read from cache (the sparse check's column cursors took longer than
// LAPACK's factorization of a dense 1188 x 1188 coarse operator).
void check_dense_values(const Matrix& D, const std::string& where) {
    constexpr Index kTile = 64;
    const Index n = static_cast<Index>(D.rows());
    for (Index j = 0; j < n; ++j)
        CG_VERIFY(D.col(j).allFinite(),
                  "{}: the matrix has a non-finite value (NaN or inf) in column {}", where, j);
    double asym2 = 0;
    for (Index j0 = 0; j0 < n; j0 += kTile)
        for (Index i0 = j0; i0 < n; i0 += kTile) {
            const Index rows = std::min(kTile, n - i0), cols = std::min(kTile, n - j0);
            asym2 += (D.block(i0, j0, rows, cols) - D.block(j0, i0, cols, rows).transpose())
                         .squaredNorm() *
                     (i0 == j0 ? 1 : 2);
        }
    const double norm2 = D.squaredNorm();
    const double rel = norm2 > 0 ? std::sqrt(asym2 / norm2) : 0.0;
    CG_VERIFY(rel <= kSymmetryTolerance,
              "{}: the matrix is not symmetric: ||A - A^T|| / ||A|| = {:.3g} exceeds {:.0e} (both "
              "triangles must be stored)",
              where, rel, kSymmetryTolerance);
}

}  // namespace

// CHOLMOD's supernodal kernels call BLAS (dpotrf, dsyrk, dgemm, dtrsm on the supernodes), where
// most of a large factorization's time goes (gemm calls it too). Debian's OpenBLAS
// (libopenblas0-pthread) runs its own thread pool, which by default would use every core even
// with --threads 1; so before each factorization and each gemm its thread count is set to OpenMP's
// (omp_get_max_threads: --threads or OMP_NUM_THREADS, else all cores), unless the user set
// OPENBLAS_NUM_THREADS. The two pools take turns: no OpenMP region runs inside a factorization, and
// idle OpenBLAS threads spin for at most about 0.1 s (2^28 cycles, OpenBLAS's default) before
// sleeping. On an idle 2-core machine 2 threads factorize bench/ccx_vs_coarsegrain.py's problem
// in 2.56 s against 3.93 s on one. OpenBLAS threads spin while they wait for work, and each BLAS
// call waits for its slowest thread, so on a machine whose cores are busy with other jobs 2
// threads are slower than one and such runs should pass --threads 1; the OpenMP build of
// OpenBLAS (libopenblas0-openmp, which would share coarsegrain's OpenMP pool) is slower still
// under load, so setup.sh keeps the pthreads build (docs/performance.md, "BLAS threads"). Other
// BLAS libraries (no openblas_set_num_threads symbol) are left alone. Inside an OpenMP parallel
// region (the hierarchy's localized solves: one factorization per thread) BLAS gets one thread:
// with OpenMP's count, the 2 threads' concurrent factorizations each woke both OpenBLAS threads
// (localized solves of the 24x12x12 hex checker, rho = 5: 25.6 s against 18.5 s).
void match_blas_threads(bool serial) {
    static const bool user_set = std::getenv("OPENBLAS_NUM_THREADS") != nullptr;
    if (user_set) return;
    using SetThreads = void (*)(int);
    static const auto set =
        reinterpret_cast<SetThreads>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    if (set) set(serial || omp_in_parallel() ? 1 : omp_get_max_threads());
}

namespace {

int blas_int(Eigen::Index v) {
    CG_VERIFY(v <= std::numeric_limits<int>::max(), "BLAS: dimension {} exceeds BLAS's int", v);
    return static_cast<int>(v);
}

}  // namespace

void gemm(const Eigen::Ref<const Matrix>& A, bool transpose_a, const Eigen::Ref<const Matrix>& B,
          bool transpose_b, double beta, Eigen::Ref<Matrix> C) {
    using Eigen::Index;  // dense sizes are ptrdiff_t; BLAS takes int
    const Index m = transpose_a ? A.cols() : A.rows(), k = transpose_a ? A.rows() : A.cols();
    const Index kb = transpose_b ? B.cols() : B.rows(), n = transpose_b ? B.rows() : B.cols();
    CG_VERIFY(kb == k && C.rows() == m && C.cols() == n, "gemm: {}x{} times {}x{} into {}x{}", m, k,
              kb, n, C.rows(), C.cols());
    if (m == 0 || n == 0) return;
    if (k == 0) {
        if (beta == 0.0)
            C.setZero();
        else
            C *= beta;
        return;
    }
    const int mi = blas_int(m), ni = blas_int(n), ki = blas_int(k);
    const int lda = blas_int(A.outerStride()), ldb = blas_int(B.outerStride()),
              ldc = blas_int(C.outerStride());
    const double one = 1.0;
    match_blas_threads();
    dgemm_(transpose_a ? "T" : "N", transpose_b ? "T" : "N", &mi, &ni, &ki, &one, A.data(), &lda,
           B.data(), &ldb, &beta, C.data(), &ldc, 1, 1);
}

void syrk_lower(const Eigen::Ref<const Matrix>& A, double alpha, Eigen::Ref<Matrix> C) {
    CG_VERIFY(C.rows() == A.cols() && C.cols() == A.cols(), "syrk: {}x{} Gram matrix into {}x{}",
              A.cols(), A.cols(), C.rows(), C.cols());
    if (A.cols() == 0 || A.rows() == 0) return;
    const int n = blas_int(A.cols()), k = blas_int(A.rows());
    const int lda = blas_int(A.outerStride()), ldc = blas_int(C.outerStride());
    const double one = 1.0;
    match_blas_threads();
    dsyrk_("L", "T", &n, &k, &alpha, A.data(), &lda, &one, C.data(), &ldc, 1, 1);
}

std::vector<Index> column_groups(const SparseMatrix& A, int max_size) {
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const auto same_pattern = [&](Index a, Index b) {
        return outer[a + 1] - outer[a] == outer[b + 1] - outer[b] &&
               std::equal(inner + outer[a], inner + outer[a + 1], inner + outer[b]);
    };
    std::vector<Index> start{0};
    const Index n = static_cast<Index>(A.cols());
    for (Index j = 1; j < n; ++j)
        if (j - start.back() >= max_size || !same_pattern(start.back(), j)) start.push_back(j);
    start.push_back(n);
    return start;
}

Index DenseCholesky::compute(Matrix A) {
    CG_VERIFY(A.rows() == A.cols(), "dense Cholesky: the matrix is {} by {}, it must be square",
              A.rows(), A.cols());
    m_factor = std::move(A);
    const int n = static_cast<int>(m_factor.rows());
    int info = 0;
    match_blas_threads(n < kDenseParallelMin);
    if (n > 0) dpotrf_("L", &n, m_factor.data(), &n, &info, 1);
    CG_VERIFY(info >= 0, "dense Cholesky: LAPACK dpotrf rejected argument {}", -info);
    m_ok = info == 0;
    return info;
}

Matrix DenseCholesky::solve(const Matrix& b) const {
    Matrix x = b;
    solve_in_place(x);
    return x;
}

void DenseCholesky::solve_in_place(Matrix& b) const {
    CG_VERIFY(m_ok, "dense Cholesky: solve called before a successful compute");
    CG_VERIFY(b.rows() == m_factor.rows(),
              "dense Cholesky: the right-hand side has {} rows, the matrix {}", b.rows(),
              m_factor.rows());
    // By LAPACK dpotrs (BLAS dtrsm), as the factorization: Eigen's triangular solves, compiled
    // for x86-64-v2, took 12% of the 24^3 checker's 3-level build (relaxed, coarse step in 3
    // rings, whose regions' solves have about 1,000 right-hand sides).
    if (b.rows() == 0 || b.cols() == 0) return;
    const int n = blas_int(b.rows()), nrhs = blas_int(b.cols());
    int info = 0;
    match_blas_threads();
    dpotrs_("L", &n, &nrhs, m_factor.data(), &n, b.data(), &n, &info, 1);
    CG_VERIFY(info == 0, "dense Cholesky: LAPACK dpotrs rejected argument {}", -info);
}

IndexVector fill_reducing_order(const SparseMatrix& A, int node_dofs, bool nested_dissection) {
    CG_VERIFY(A.rows() == A.cols() && A.isCompressed(),
              "fill_reducing_order: the matrix must be square and compressed, got {} by {}",
              A.rows(), A.cols());
    CG_VERIFY(node_dofs >= 1, "fill_reducing_order: node_dofs must be at least 1, got {}",
              node_dofs);
    if (A.rows() == 0) return {};
    const std::vector<Index> start = column_groups(A, node_dofs);
    const std::vector<int> perm =
        static_cast<Index>(start.size()) - 1 < A.rows()
            ? group_ordering(A, start, nested_dissection).first
            : order_pattern(A.rows(), A.outerIndexPtr(), A.innerIndexPtr(), nested_dissection)
                  .first;
    return Eigen::Map<const IndexVector>(perm.data(), A.rows());
}

std::string backend_name(Backend b) {
    switch (b) {
        case Backend::Cholmod:
            return "cholmod";
        case Backend::SimplicialLDLT:
            return "ldlt";
        case Backend::ConjugateGradient:
            return "cg";
        case Backend::MraPcg:
            return "mra-pcg";
    }
    return "?";
}

bool is_iterative(Backend b) { return b == Backend::ConjugateGradient || b == Backend::MraPcg; }

Backend parse_backend(const std::string& name) {
    for (Backend b :
         {Backend::Cholmod, Backend::SimplicialLDLT, Backend::ConjugateGradient, Backend::MraPcg})
        if (backend_name(b) == name) return b;
    CG_VERIFY(false, "unknown solver backend '{}': expected one of cholmod, ldlt, cg, mra-pcg",
              name);
    return Backend::Cholmod;
}

struct SpdSolver::Impl {
    SolverOptions options;
    Index n = 0;
    Eigen::Index nnz = -1;
    std::uint64_t pattern = 0;
    bool analyzed = false;
    bool factorized = false;
    FactorStats stats;
    std::unique_ptr<CholmodFactor> cholmod;
    /// Cholmod backend on a dense matrix (is_dense): LAPACK's factorization in place of
    /// CHOLMOD's.
    bool dense = false;
    DenseCholesky dense_factor;
    std::unique_ptr<Ldlt> ldlt;
    std::unique_ptr<Cg> cg;
    SparseMatrix cg_matrix;  // CG keeps a reference to its matrix, so it gets its own copy
    std::unique_ptr<Preconditioner> preconditioner;  // mra-pcg, of cg_matrix

    std::string name() const { return backend_name(options.backend); }

    /// Refuses a factor of `bytes` above options.max_factor_bytes (0: the available memory, for
    /// factors of kMinCheckedFactorBytes and more).
    void check_factor_memory(double bytes) const {
        const bool given = options.max_factor_bytes > 0;
        if (!given && bytes < kMinCheckedFactorBytes) return;
        const double limit = given ? options.max_factor_bytes : available_memory();
        CG_VERIFY_AS(FactorTooLarge, bytes <= limit,
                     "solver ({}): the factor of the n = {} matrix ({} stored entries) would take "
                     "{:.3g} GB, more than the {:.3g} GB {}; make the system smaller (e.g. more "
                     "coarsening levels) or the memory larger, or solve a fine model iteratively "
                     "(\"solver\": {{\"backend\": \"mra-pcg\"}})",
                     name(), n, nnz, bytes / 1e9, limit / 1e9,
                     given ? "allowed (max_factor_bytes)" : "available (MemAvailable)");
    }

    [[noreturn]] void not_positive_definite(const std::string& detail) const {
        throw NotPositiveDefinite(
            fmt::format("matrix is not positive definite (n = {}, backend {}): {} ({})", n, name(),
                        kDirichletHint, detail));
    }

    Matrix solve_factored(const Matrix& b) const {
        switch (options.backend) {
            case Backend::Cholmod:
                return dense ? dense_factor.solve(b) : Matrix(cholmod->solve(b));
            case Backend::SimplicialLDLT:
                return ldlt->solve(b);
            case Backend::ConjugateGradient:
            case Backend::MraPcg:
                break;
        }
        return {};
    }

    /// Factorizes a dense A with LAPACK (which reads the lower triangle).
    void factorize_dense(const SparseMatrix& A) {
        Matrix D = A;
        if (options.check_input && !options.lower_triangle)
            check_dense_values(D, fmt::format("solver ({})", name()));
        const Index minor = dense_factor.compute(std::move(D));
        if (minor > 0) {
            not_positive_definite(fmt::format(
                "LAPACK dpotrf: the leading minor of order {} is not positive definite", minor));
        }
        const auto d = dense_factor.factor().diagonal();
        const double ratio = std::pow(d.minCoeff() / d.maxCoeff(), 2);
        if (!(ratio >= kSuspectPivotRatio)) check_numerically_singular(A, ratio);
    }

    // Called when the pivot ratio is suspicious: two steps of inverse iteration from a fixed
    // random vector, then the Rayleigh quotient with A (see kSingularEigenvalueRatio).
    void check_numerically_singular(const SparseMatrix& A, double pivot_ratio) const {
        std::mt19937 rng(12345);
        std::uniform_real_distribution<double> U(-1.0, 1.0);
        Vector z(n);
        for (Index i = 0; i < n; ++i) z[i] = U(rng);
        double rho = 0;
        for (int it = 0; it < 2; ++it) {
            z = solve_factored(z);
            const double norm = z.norm();
            if (!std::isfinite(norm) || norm == 0) {
                not_positive_definite(fmt::format(
                    "the solve with the factorization overflows; pivot ratio {:.3g}", pivot_ratio));
            }
            z /= norm;
            rho = options.lower_triangle ? z.dot(A.selfadjointView<Eigen::Lower>() * z)
                                         : z.dot(A * z);
        }
        const double scale = A.diagonal().maxCoeff();
        if (!(rho > kSingularEigenvalueRatio * scale)) {
            not_positive_definite(fmt::format(
                "numerically singular: smallest eigenvalue estimate {:.3g} is below {:.0e} times "
                "the largest diagonal entry {:.3g}; pivot ratio {:.3g}",
                rho, kSingularEigenvalueRatio, scale, pivot_ratio));
        }
    }
};

SpdSolver::SpdSolver(SolverOptions options) : m_impl(std::make_unique<Impl>()) {
    CG_VERIFY(options.cg_tolerance > 0 && options.cg_tolerance < 1,
              "solver: cg_tolerance = {} must be in (0, 1)", options.cg_tolerance);
    CG_VERIFY(options.node_dofs >= 1, "solver: node_dofs = {} must be >= 1", options.node_dofs);
    CG_VERIFY(options.cg_max_iterations >= 0,
              "solver: cg_max_iterations = {} must be >= 0 (0: 10 n)", options.cg_max_iterations);
    CG_VERIFY(options.time_limit >= 0, "solver: time_limit = {} must be >= 0 (0: none)",
              options.time_limit);
    m_impl->options = options;
}

SpdSolver::~SpdSolver() = default;
SpdSolver::SpdSolver(SpdSolver&&) noexcept = default;
SpdSolver& SpdSolver::operator=(SpdSolver&&) noexcept = default;

void SpdSolver::analyze(const SparseMatrix& A) {
    Impl& s = *m_impl;
    CG_VERIFY(A.rows() == A.cols(), "solver ({}): the matrix is {} by {}, it must be square",
              s.name(), A.rows(), A.cols());
    CG_VERIFY(A.rows() > 0, "solver ({}): the matrix is empty (no free degrees of freedom?)",
              s.name());
    CG_VERIFY(A.isCompressed(), "solver ({}): the matrix must be compressed (call makeCompressed)",
              s.name());
    s.analyzed = s.factorized = false;
    s.n = static_cast<Index>(A.rows());
    s.nnz = A.nonZeros();
    s.dense = s.options.backend == Backend::Cholmod && is_dense(A, s.options.lower_triangle);
    s.pattern = s.dense ? 0 : pattern_hash(A);
    switch (s.options.backend) {
        case Backend::Cholmod: {
            s.dense_factor = DenseCholesky();
            if (s.dense) {
                s.cholmod.reset();
                const double n = static_cast<double>(s.n);
                s.stats = {"natural", n * (n + 1) / 2, n * n * n / 3};
                s.check_factor_memory(n * n * sizeof(double));
                break;
            }
            s.cholmod = std::make_unique<CholmodFactor>();
            std::string ordering;
            if (s.options.keep_order) {
                s.cholmod->use_natural_order();
                s.cholmod->analyzePattern(A);
            } else if (const std::vector<Index> start = column_groups(A, s.options.node_dofs);
                       static_cast<Index>(start.size()) - 1 < s.n) {
                auto [perm, name] = group_ordering(A, start, true);
                s.cholmod->analyze_permuted(A, perm);
                ordering = std::move(name);
            } else {
                s.cholmod->analyzePattern(A);  // no node blocks: CHOLMOD's default ordering
            }
            CG_VERIFY(s.cholmod->has_factor() && s.cholmod->status() >= 0,
                      "solver (cholmod): symbolic analysis of an n = {} matrix with {} nonzeros "
                      "failed (CHOLMOD status {}; out of memory? a fine model can be solved "
                      "iteratively: \"solver\": {{\"backend\": \"mra-pcg\"}})",
                      s.n, s.nnz, s.cholmod->status());
            if (ordering.empty()) ordering = ordering_name(s.cholmod->selected_ordering());
            s.stats = {ordering, s.cholmod->factor_nonzeros(), s.cholmod->factor_flops()};
            // With the permuted copies of A's lower triangle CHOLMOD makes (two transposes).
            s.check_factor_memory(s.cholmod->factor_bytes() +
                                  (s.options.keep_order ? 0.0 : 2.0 * 12.0 * s.nnz));
            break;
        }
        case Backend::SimplicialLDLT:
            s.ldlt = std::make_unique<Ldlt>();
            s.ldlt->analyzePattern(A);
            break;
        case Backend::ConjugateGradient:
            s.cg = std::make_unique<Cg>();
            break;
        case Backend::MraPcg:
            CG_VERIFY(bool(s.options.preconditioner),
                      "solver (mra-pcg): no preconditioner was given; the backend solves the fine "
                      "model of a scene on a regular grid");
            break;
    }
    s.analyzed = true;
}

void SpdSolver::factorize(const SparseMatrix& A) {
    Impl& s = *m_impl;
    // A dense matrix has no pattern to analyze: its order is kept whatever its zeros.
    const bool same_pattern = s.analyzed && A.rows() == s.n && A.cols() == s.n &&
                              A.isCompressed() &&
                              (s.dense ? is_dense(A, s.options.lower_triangle)
                                       : A.nonZeros() == s.nnz && pattern_hash(A) == s.pattern);
    if (!same_pattern) analyze(A);
    factorize_analyzed(A);
}

void SpdSolver::factorize_analyzed(const SparseMatrix& A) {
    Impl& s = *m_impl;
    s.factorized = false;
    if (s.options.check_input) {
        const std::string where = fmt::format("solver ({})", s.name());
        if (s.options.lower_triangle)
            check_lower_values(A, where);
        else if (!s.dense)
            check_values(A, where);
    }

    switch (s.options.backend) {
        case Backend::Cholmod: {
            if (s.dense) {
                s.factorize_dense(A);
                break;
            }
            CholmodFactor& f = *s.cholmod;
            match_blas_threads();
            f.factorize(A);
            CG_VERIFY(f.status() >= 0,
                      "solver (cholmod): numeric factorization of an n = {} matrix failed "
                      "(CHOLMOD status {}; out of memory?)",
                      s.n, f.status());
            CG_ASSERT(f.is_supernodal(), "CHOLMOD must use its supernodal factorization");
            if (f.info() != Eigen::Success) {
                s.not_positive_definite(
                    fmt::format("CHOLMOD: the leading minor of order {} is not positive definite",
                                f.minor() + 1));
            }
            const double ratio = f.rcond();
            if (!(ratio >= kSuspectPivotRatio)) s.check_numerically_singular(A, ratio);
            break;
        }
        case Backend::SimplicialLDLT: {
            Ldlt& f = *s.ldlt;
            f.factorize(A);
            const Vector& D = f.vectorD();
            const double dmin = D.minCoeff(), dmax = D.maxCoeff();
            if (f.info() != Eigen::Success || !(dmin > 0)) {
                Index at = 0;
                D.minCoeff(&at);
                s.not_positive_definite(
                    fmt::format("LDL^T pivot {} of the permuted matrix is {:.3g}", at + 1, dmin));
            }
            const double ratio = dmin / dmax;
            if (!(ratio >= kSuspectPivotRatio)) s.check_numerically_singular(A, ratio);
            break;
        }
        case Backend::ConjugateGradient:
        case Backend::MraPcg: {
            // A positive definite matrix has a positive diagonal; CG itself cannot tell.
            const Vector diagonal = A.diagonal();
            Index at = 0;
            const double dmin = diagonal.minCoeff(&at);
            if (!(dmin > 0)) {
                s.not_positive_definite(
                    fmt::format("diagonal entry {} is {:.3g}, not positive", at, dmin));
            }
            s.preconditioner.reset();
            s.cg_matrix =
                s.options.lower_triangle ? SparseMatrix(A.selfadjointView<Eigen::Lower>()) : A;
            if (s.options.backend == Backend::MraPcg) {
                s.preconditioner = s.options.preconditioner(s.cg_matrix);
                break;
            }
            s.cg->setTolerance(s.options.cg_tolerance);
            s.cg->setMaxIterations(s.options.cg_max_iterations > 0 ? s.options.cg_max_iterations
                                                                   : 10 * s.n);
            s.cg->compute(s.cg_matrix);
            break;
        }
    }
    s.factorized = true;
}

void SpdSolver::compute(const SparseMatrix& A) {
    analyze(A);
    factorize_analyzed(A);
}

Matrix SpdSolver::solve(const Matrix& b) const {
    const Impl& s = *m_impl;
    CG_VERIFY(s.factorized, "solver ({}): solve called before a successful factorize", s.name());
    CG_VERIFY(b.rows() == s.n, "solver ({}): the right-hand side has {} rows, the matrix {}",
              s.name(), b.rows(), s.n);
    CG_VERIFY(b.allFinite(), "solver ({}): the right-hand side has a non-finite value", s.name());
    Matrix x;
    if (s.options.backend == Backend::ConjugateGradient) {
        x.resize(b.rows(), b.cols());
        for (Eigen::Index c = 0; c < b.cols(); ++c) {
            x.col(c) = s.cg->solve(b.col(c));
            CG_VERIFY_AS(
                NotConverged, s.cg->info() == Eigen::Success,
                "solver (cg): conjugate gradients did not converge for right-hand side {} "
                "(n = {}): relative residual {:.3g} after {} iterations, tolerance {:.3g}; "
                "{}",
                c, s.n, s.cg->error(), s.cg->iterations(), s.options.cg_tolerance, kCgAdvice);
        }
    } else if (s.options.backend == Backend::MraPcg) {
        x.resize(b.rows(), b.cols());
        PcgOptions o;
        o.tolerance = s.options.cg_tolerance;
        o.max_iterations = s.options.cg_max_iterations > 0 ? s.options.cg_max_iterations : 1000;
        o.time_limit = s.options.time_limit;
        o.name = "solver (mra-pcg)";
        for (Eigen::Index c = 0; c < b.cols(); ++c)
            x.col(c) = pcg(s.cg_matrix, b.col(c), *s.preconditioner, o);
    } else {
        x = s.solve_factored(b);
        CG_VERIFY(
            s.options.backend != Backend::Cholmod || s.dense || s.cholmod->info() == Eigen::Success,
            "solver (cholmod): the triangular solves failed (n = {}, CHOLMOD status {}; out "
            "of memory?)",
            s.n, s.cholmod->status());
    }
    CG_VERIFY(x.allFinite(), "solver ({}): the solution has non-finite values (n = {})", s.name(),
              s.n);
    return x;
}

Vector SpdSolver::solve(const Vector& b) const { return solve(Matrix(b)).col(0); }

Backend SpdSolver::backend() const { return m_impl->options.backend; }

FactorStats SpdSolver::factor_stats() const {
    const Impl& s = *m_impl;
    CG_VERIFY(s.analyzed && s.options.backend == Backend::Cholmod,
              "solver ({}): factor_stats needs an analyzed cholmod solver", s.name());
    return s.stats;
}

IndexVector SpdSolver::permutation() const {
    const Impl& s = *m_impl;
    CG_VERIFY(s.analyzed && s.options.backend == Backend::Cholmod,
              "solver ({}): permutation needs an analyzed cholmod solver", s.name());
    return s.dense ? IndexVector(IndexVector::LinSpaced(s.n, 0, s.n - 1))
                   : s.cholmod->permutation();
}

Index SpdSolver::rows() const { return m_impl->analyzed ? m_impl->n : 0; }

}  // namespace coarsegrain::solve
