#include "coarsegrain/sim/modes.hpp"

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::sim {

namespace {

/// Free DOFs at or below which the pencil is solved densely.
constexpr Index kDenseDofs = 600;

/// y = K_ff^{-1} x through one kept factorization: Spectra's shift-invert operator for shift 0.
class StiffnessInverse {
  public:
    using Scalar = double;
    StiffnessInverse(const SparseMatrix& K, const solve::SolverOptions& options)
        : m_solver(options) {
        m_solver.compute(K);
    }
    Index rows() const { return m_solver.rows(); }
    Index cols() const { return m_solver.rows(); }
    void set_shift(double sigma) {
        CG_VERIFY(sigma == 0, "modes: only shift 0 is factorized, not {}", sigma);
    }
    void perform_op(const double* x_in, double* y_out) const {
        Eigen::Map<Vector>(y_out, rows()) =
            m_solver.solve(Vector(Eigen::Map<const Vector>(x_in, rows())));
    }

  private:
    solve::SpdSolver m_solver;
};

/// The k lowest eigenpairs of (K, M) on free DOFs: (eigenvalues ascending, vectors).
std::pair<Vector, Matrix> lowest_pairs(const SparseMatrix& K, const SparseMatrix& M, Index k,
                                       const solve::SolverOptions& options) {
    const Index n = K.rows();
    if (n <= kDenseDofs) {
        const Eigen::GeneralizedSelfAdjointEigenSolver<Matrix> eig{Matrix(K), Matrix(M)};
        CG_VERIFY(eig.info() == Eigen::Success,
                  "modes: the dense eigensolver failed on {} free DOFs (is the mass positive "
                  "definite?)",
                  n);
        CG_VERIFY_AS(NotPositiveDefinite, eig.eigenvalues()[0] > 0,
                     "modes: the stiffness is singular on the free DOFs (smallest eigenvalue "
                     "{:.3g}); the Dirichlet conditions must hold the body",
                     eig.eigenvalues()[0]);
        return {eig.eigenvalues().head(k), eig.eigenvectors().leftCols(k)};
    }
    StiffnessInverse op(K, options);
    Spectra::SparseSymMatProd<double> mass(M);
    const Index ncv = std::min<Index>(n, std::max<Index>(2 * k + 1, 20));
    Spectra::SymGEigsShiftSolver<StiffnessInverse, Spectra::SparseSymMatProd<double>,
                                 Spectra::GEigsMode::ShiftInvert>
        eigs(op, mass, k, ncv, 0.0);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10, Spectra::SortRule::SmallestAlge);
    CG_VERIFY(eigs.info() == Spectra::CompInfo::Successful,
              "modes: shift-invert Lanczos for {} eigenpairs of {} free DOFs did not converge", k,
              n);
    return {eigs.eigenvalues(), eigs.eigenvectors()};
}

}  // namespace

Modes modes(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc, int count,
            const solve::SolverOptions& solver) {
    CG_VERIFY(K.rows() == K.cols() && M.rows() == M.cols() && K.rows() == M.rows(),
              "modes: stiffness {}x{} and mass {}x{} must be square of one size", K.rows(),
              K.cols(), M.rows(), M.cols());
    CG_VERIFY(count >= 1, "modes: expected a count >= 1, got {}", count);
    const Vector zero = Vector::Zero(K.rows());
    const fem::ReducedSystem Kf = fem::reduce(K, zero, bc);
    const SparseMatrix Mf = fem::reduce(M, zero, bc).K;
    const Index free = Kf.free_dofs.size();
    CG_VERIFY(free > 0, "modes: every DOF is prescribed");
    const Index k = std::min<Index>(count, free);
    auto [lambda, phi] = lowest_pairs(Kf.K, Mf, k, solver);
    Modes m;
    m.eigenvalues = lambda;
    m.frequencies_hz = lambda.cwiseMax(0).cwiseSqrt() / (2 * std::numbers::pi);
    m.vectors = Matrix::Zero(K.rows(), k);
    for (Index j = 0; j < k; ++j) {
        Vector v = phi.col(j) / std::sqrt(phi.col(j).dot(Mf * phi.col(j)));
        Index top = 0;
        v.cwiseAbs().maxCoeff(&top);
        if (v[top] < 0) v = -v;
        for (Index i = 0; i < free; ++i) m.vectors(Kf.free_dofs[i], j) = v[i];
    }
    return m;
}

double mac(const Vector& a, const Vector& b) {
    CG_VERIFY(a.size() == b.size(), "mac: vectors of {} and {} entries", a.size(), b.size());
    const double aa = a.squaredNorm(), bb = b.squaredNorm();
    CG_VERIFY(aa > 0 && bb > 0, "mac: a zero vector has no shape");
    const double ab = a.dot(b);
    return ab * ab / (aa * bb);
}

std::vector<ModePair> pair_modes(const Matrix& reference, const Matrix& candidates) {
    CG_VERIFY(reference.rows() == candidates.rows() && candidates.cols() > 0,
              "pair_modes: {} reference rows against {} x {} candidates", reference.rows(),
              candidates.rows(), candidates.cols());
    std::vector<ModePair> pairs(static_cast<std::size_t>(reference.cols()));
    for (Index i = 0; i < reference.cols(); ++i) {
        ModePair& p = pairs[static_cast<std::size_t>(i)];
        for (Index j = 0; j < candidates.cols(); ++j) {
            const double m = mac(reference.col(i), candidates.col(j));
            if (m > p.mac) p = {j, m};
        }
    }
    return pairs;
}

}  // namespace coarsegrain::sim
