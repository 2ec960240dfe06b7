#pragma once
/// @file Sparse LU factorization of square, non-symmetric matrices (UMFPACK).
#include <memory>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"

namespace coarsegrain::solve {

/// UMFPACK found the matrix singular (numerically).
class SingularMatrix : public ErrorOf<SingularMatrix> {
  public:
    using ErrorOf::ErrorOf;
};

/// A sparse LU factorization by UMFPACK (SuiteSparse, through Eigen's UmfPackSupport), for
/// matrices that are not symmetric (the consistent corotated tangent): factorize, then solve
/// many right-hand sides. The symbolic analysis is kept while the pattern stays the same
/// (compared by size, nonzero count and indices), as in Newton's iterations. The solves skip
/// UMFPACK's iterative refinement: x is as accurate as the factorization's backward error
/// allows (what a Newton step or a preconditioner needs), not refined towards round-off.
/// Not thread-safe: one solve at a time.
class SparseLu {
  public:
    SparseLu();
    ~SparseLu();
    SparseLu(SparseLu&&) noexcept;
    SparseLu& operator=(SparseLu&&) noexcept;

    /// Factorizes A (square, compressed, finite).
    /// @throws Error if A is not square, empty, or has a non-finite value;
    ///         SingularMatrix if UMFPACK finds A singular
    void factorize(const SparseMatrix& A);
    /// Solves A x = b.
    /// @throws Error before a successful factorize or on a size mismatch
    Vector solve(const Vector& b) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace coarsegrain::solve
