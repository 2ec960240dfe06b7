#pragma once
/// @file Deflation of a preconditioner by a few given vectors: the near-kernel of a high-contrast
/// composite (the rigid motions of its stiff clusters, fem/stiff_clusters.hpp) removed exactly
/// at every iteration, the rest left to the preconditioner.
#include <memory>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/solve/pcg.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::solve {

/// The balancing (BNN) form of deflation (Tang, Nabben, Vuik and Erlangga 2009, "Comparison of
/// two-level preconditioners derived from deflation, domain decomposition and multigrid"):
/// with E = Z^T A Z and Q = Z E^{-1} Z^T,
///     B = Q + (I - Q A) M (I - A Q),
/// applied as x = Q r, x += M (r - A x), x += Q (r - A x): one product with A and two small
/// solves with E per application besides M. Its error propagation is (I - QA)(I - MA)(I - QA),
/// so B A is the identity on span Z, and B is symmetric positive definite whenever M is.
class DeflatedPreconditioner : public Preconditioner {
  public:
    /// @param A     n square, symmetric positive definite, both triangles stored; outlives this
    /// @param base  M, over the same n unknowns
    /// @param Z     n by m deflation vectors (m >= 1), linearly independent
    /// @throws Error if the sizes do not match or Z has no column; NotPositiveDefinite if
    ///         Z^T A Z is not positive definite (dependent columns)
    DeflatedPreconditioner(const SparseMatrix& A, std::unique_ptr<Preconditioner> base,
                           SparseMatrix Z);

    /// z = B r.
    Vector apply(const Vector& r) const override;

    const Preconditioner& base() const { return *m_base; }
    /// Number m of deflation vectors.
    Index vectors() const { return m_Z.cols(); }

  private:
    /// Q r = Z E^{-1} Z^T r as the m coefficients E^{-1} Z^T r.
    Vector coefficients(const Vector& r) const;

    const SparseMatrix& m_A;
    std::unique_ptr<Preconditioner> m_base;
    SparseMatrix m_Z;
    SparseMatrix m_AZ;  ///< A Z
    SpdSolver m_E;      ///< factorization of Z^T A Z
};

}  // namespace coarsegrain::solve
