// The step on the whole level with the measurements G (detail::whole_level_refinement, private to
// the library): on A's factorization where A is definite, on M's where it is singular, against the
// constrained minimization solved densely, and against the relaxed step's space.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "../../src/mra/detail.hpp"
#include "../../src/mra/products.hpp"
#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra::detail {
namespace {

/// The stiffness of a chain of n nodes and n - 1 springs alternating between 1 and `contrast`,
/// held at node 0 by a spring of stiffness 1 when `held` (definite), else free (singular: the
/// constants are its null space). Both triangles.
SparseMatrix chain(Index n, double contrast, bool held) {
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index e = 0; e + 1 < n; ++e) {
        const double k = e % 2 == 0 ? 1.0 : contrast;
        t.emplace_back(e, e, k);
        t.emplace_back(e + 1, e + 1, k);
        t.emplace_back(e, e + 1, -k);
        t.emplace_back(e + 1, e, -k);
    }
    if (held) t.emplace_back(0, 0, 1.0);
    SparseMatrix A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
}

/// Linear interpolation from m coarse nodes to n = (m - 1) r + 1 fine ones, as m x n (C: rows
/// are coarse nodes).
SparseMatrix interpolation(Index m, Index r) {
    const Index n = (m - 1) * r + 1;
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index j = 0; j < n; ++j) {
        const Index i = j / r, s = j % r;
        t.emplace_back(i, j, 1.0 - static_cast<double>(s) / static_cast<double>(r));
        if (s > 0) t.emplace_back(i + 1, j, static_cast<double>(s) / static_cast<double>(r));
    }
    SparseMatrix C(m, n);
    C.setFromTriplets(t.begin(), t.end());
    return C;
}

/// C plus entries of size `spread` at random with probability `density` (measurements that are
/// not C's, dense where density is large).
SparseMatrix perturbed(const SparseMatrix& C, double density, double spread, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> value(-spread, spread), coin(0.0, 1.0);
    Matrix G(C);
    for (Index j = 0; j < G.cols(); ++j)
        for (Index i = 0; i < G.rows(); ++i)
            if (coin(rng) < density) G(i, j) += value(rng);
    return G.sparseView();
}

/// The relaxed step on the whole level, C - ((A + p G^T G)^{-1} A C^T)^T, by a dense Cholesky.
Matrix relaxed_formula(const SparseMatrix& A, const SparseMatrix& C, const SparseMatrix& G,
                       double p) {
    const Matrix Gd(G), Cd(C);
    const Matrix M = Matrix(A) + p * Gd.transpose() * Gd;
    return Cd - Matrix(M.llt().solve(Matrix(A) * Cd.transpose())).transpose();
}

/// argmin tr(X A X^T) subject to G X^T = I, by the dense KKT system [A G^T; G 0].
Matrix constrained_minimizer(const SparseMatrix& A, const SparseMatrix& G) {
    const Index n = A.rows(), m = G.rows();
    Matrix kkt = Matrix::Zero(n + m, n + m);
    kkt.topLeftCorner(n, n) = Matrix(A);
    kkt.topRightCorner(n, m) = Matrix(G.transpose());
    kkt.bottomLeftCorner(m, n) = Matrix(G);
    Matrix rhs = Matrix::Zero(n + m, m);
    rhs.bottomRows(m).setIdentity();
    return Matrix(kkt.fullPivLu().solve(rhs)).topRows(n).transpose();
}

// 13 coarse and 61 fine nodes, contrast 100: held, cond(A) = 1.6e5, so the solves with A are
// accurate to about cond(A) eps = 2e-11; the KKT system's LU to about its condition times eps.
// 1e-10 relative. Measurements sparse (C's pattern: the column-by-column product of
// sparse_times_dense) and 40% dense (its dense copy). Free, A's null space (the constants) makes
// it singular and the step goes through M (penalties 0.1 and 100 around the stiffnesses). A given
// by its lower triangle gives the same step.
TEST(MraWholeLevelStep, IsTheConstrainedMinimizerWithAndWithoutDirichletConditions) {
    const SparseMatrix C = interpolation(13, 5);
    for (const bool held : {true, false})
        for (const double density : {0.0, 0.4})
            for (const double p : {0.1, 100.0}) {
                const SparseMatrix A = chain(C.cols(), 100.0, held);
                const SparseMatrix G = perturbed(C, density, 0.2, 7);
                const Matrix Ct(whole_level_refinement(A, G, p));
                const Matrix expected = constrained_minimizer(A, G);
                // A by its lower triangle: the same factorizations, to round-off.
                const SparseMatrix A_lower = A.triangularView<Eigen::Lower>();
                EXPECT_LT(
                    (Matrix(whole_level_refinement(A_lower, G, p, Stored::Lower)) - Ct).norm(),
                    1e-12 * Ct.norm());
                ASSERT_EQ(Ct.rows(), G.rows());
                ASSERT_EQ(Ct.cols(), G.cols());
                const std::string label = std::string(held ? "held" : "free") + ", density " +
                                          std::to_string(density) + ", penalty " +
                                          std::to_string(p);
                EXPECT_LT((Ct - expected).norm(), 1e-10 * expected.norm()) << label;
                // The relaxed step's basis D spans the same space, in which every function v is
                // C̃^T G v: D^T = C̃^T G D^T (M's condition is below 1e3 here).
                const Matrix D = relaxed_formula(A, C, G, p);
                EXPECT_LT((Ct.transpose() * (Matrix(G) * D.transpose()) - D.transpose()).norm(),
                          1e-10 * D.norm())
                    << label;
            }
}

TEST(MraWholeLevelStep, RefusesMismatchedShapesNoPenaltyAndDependentMeasurements) {
    const SparseMatrix C = interpolation(4, 2), A = chain(C.cols(), 10.0, true);
    EXPECT_THROW(whole_level_refinement(chain(5, 10.0, true), C, 1.0), Error);
    EXPECT_THROW(whole_level_refinement(A, C, 0.0), Error);
    Matrix twice(Matrix(C).rows() + 1, C.cols());
    twice.topRows(C.rows()) = Matrix(C);
    twice.row(C.rows()) = Matrix(C).row(0);
    EXPECT_THROW(whole_level_refinement(A, SparseMatrix(twice.sparseView()), 1.0), Error);
}

// Both kernels of sparse_times_dense: the dense copy (X 60% dense) and X's columns (1%), against
// Eigen's product; each sums the same products in another order: 1e-13 relative.
TEST(MraSparseTimesDense, EitherKernelIsTheProduct) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> value(-1.0, 1.0), coin(0.0, 1.0);
    for (const double density : {0.6, 0.01}) {
        std::vector<Eigen::Triplet<double, Index>> t;
        for (Index j = 0; j < 300; ++j)
            for (Index i = 0; i < 200; ++i)
                if (coin(rng) < density) t.emplace_back(i, j, value(rng));
        SparseMatrix X(200, 300);
        X.setFromTriplets(t.begin(), t.end());
        const Matrix Y = Matrix::Random(300, 70);
        const Matrix expected = Matrix(X) * Y;
        EXPECT_LT((sparse_times_dense(X, Y) - expected).norm(), 1e-13 * expected.norm()) << density;
    }
    EXPECT_THROW(sparse_times_dense(SparseMatrix(2, 3), Matrix::Zero(4, 1)), Error);
}

}  // namespace
}  // namespace coarsegrain::mra::detail
