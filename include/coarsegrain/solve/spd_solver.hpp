#pragma once
/// @file Sparse symmetric positive-definite solver facade.
#include <memory>
#include <string>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::solve {

enum class Backend {
    Cholmod,            ///< CHOLMOD supernodal Cholesky (default)
    SimplicialLDLT,     ///< Eigen SimplicialLDLT
    ConjugateGradient,  ///< Eigen CG with Jacobi preconditioner
};

/// "cholmod", "ldlt", "cg".
std::string backend_name(Backend b);
/// Parses backend_name's strings. @throws Error listing the valid names
Backend parse_backend(const std::string& name);

struct SolverOptions {
    Backend backend = Backend::Cholmod;
    double cg_tolerance = 1e-12;  ///< relative residual for CG
    int cg_max_iterations = 0;    ///< 0: 10 * n
};

/// Symmetric positive-definite sparse solver that keeps its factorization: factorize once,
/// solve many right-hand sides. Checks that the matrix is square, finite and symmetric, and
/// reports a matrix that is not positive definite (e.g. a structure without Dirichlet
/// conditions: its rigid motions make it singular) as NotPositiveDefinite instead of
/// returning garbage.
class SpdSolver {
public:
    explicit SpdSolver(SolverOptions options = {});
    ~SpdSolver();
    SpdSolver(SpdSolver&&) noexcept;
    SpdSolver& operator=(SpdSolver&&) noexcept;

    /// Symbolic analysis (ordering) of A's pattern.
    void analyze(const SparseMatrix& A);
    /// Numeric factorization; analyze() first if the pattern changed or was never analyzed.
    /// @throws NotPositiveDefinite with the size and backend status
    void factorize(const SparseMatrix& A);
    /// analyze + factorize.
    void compute(const SparseMatrix& A);
    /// Solves A x = b (b: n, or n by k for several right-hand sides).
    Matrix solve(const Matrix& b) const;
    Vector solve(const Vector& b) const;

    Backend backend() const;
    Index rows() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace coarsegrain::solve
