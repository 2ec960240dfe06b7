#include "coarsegrain/solve/deflation.hpp"

namespace coarsegrain::solve {

DeflatedPreconditioner::DeflatedPreconditioner(const SparseMatrix& A,
                                               std::unique_ptr<Preconditioner> base, SparseMatrix Z)
    : m_A(A), m_base(std::move(base)), m_Z(std::move(Z)) {
    CG_VERIFY(m_base != nullptr, "deflation: no preconditioner to deflate");
    CG_VERIFY(A.rows() == A.cols() && m_Z.rows() == A.rows(),
              "deflation: {} x {} vectors for a {} x {} matrix", m_Z.rows(), m_Z.cols(), A.rows(),
              A.cols());
    CG_VERIFY(m_Z.cols() > 0, "deflation: no deflation vector");
    m_AZ = A * m_Z;
    const SparseMatrix E = m_Z.transpose() * m_AZ;
    // Z^T (A Z) is symmetric up to round-off; CHOLMOD reads one triangle, so symmetrize.
    const SparseMatrix Et = E.transpose();
    m_E.compute(SparseMatrix(0.5 * (E + Et)));
}

Vector DeflatedPreconditioner::coefficients(const Vector& r) const {
    const Vector Ztr = m_Z.transpose() * r;
    return m_E.solve(Ztr);
}

Vector DeflatedPreconditioner::apply(const Vector& r) const {
    CG_VERIFY(r.size() == m_A.rows(), "deflation: a residual of {} for {} unknowns", r.size(),
              m_A.rows());
    const Vector y = coefficients(r);
    Vector x = m_Z * y;
    x += m_base->apply(r - m_AZ * y);
    Vector Ax;
    symmetric_multiply(m_A, x, Ax);
    x += m_Z * coefficients(r - Ax);
    return x;
}

}  // namespace coarsegrain::solve
