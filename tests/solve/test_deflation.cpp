// Deflation (solve/deflation.hpp): the balancing form B = Q + (I - QA) M (I - AQ) formed column by
// column on a small SPD matrix is symmetric positive definite and inverts A on span Z.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "coarsegrain/solve/deflation.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

/// The 2D five-point Laplacian on an n x n grid plus a small shift (SPD, both triangles).
SparseMatrix shifted_laplacian(Index n) {
    std::vector<Eigen::Triplet<double>> t;
    const auto id = [n](Index i, Index j) { return i + n * j; };
    for (Index j = 0; j < n; ++j)
        for (Index i = 0; i < n; ++i) {
            t.emplace_back(id(i, j), id(i, j), 4.01);
            if (i + 1 < n) {
                t.emplace_back(id(i, j), id(i + 1, j), -1);
                t.emplace_back(id(i + 1, j), id(i, j), -1);
            }
            if (j + 1 < n) {
                t.emplace_back(id(i, j), id(i, j + 1), -1);
                t.emplace_back(id(i, j + 1), id(i, j), -1);
            }
        }
    SparseMatrix A(n * n, n * n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
}

/// Jacobi: M = diag(A)^-1.
class JacobiPreconditioner : public solve::Preconditioner {
  public:
    explicit JacobiPreconditioner(const SparseMatrix& A) : m_d(A.diagonal().cwiseInverse()) {}
    Vector apply(const Vector& r) const override { return m_d.cwiseProduct(r); }

  private:
    Vector m_d;
};

/// m random sparse columns (about a quarter of the entries set).
SparseMatrix random_columns(Index n, Index m, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    Matrix Z = Matrix::Zero(n, m);
    for (Index j = 0; j < m; ++j)
        for (Index i = 0; i < n; ++i)
            if (u(rng) > 0.5) Z(i, j) = u(rng);
    return Z.sparseView();
}

Matrix formed(const solve::Preconditioner& B, Index n) {
    Matrix dense(n, n);
    for (Index j = 0; j < n; ++j) dense.col(j) = B.apply(Vector::Unit(n, j));
    return dense;
}

TEST(Deflation, BalancingFormIsSpdAndInvertsTheOperatorOnTheVectors) {
    const SparseMatrix A = shifted_laplacian(8);
    const Index n = A.rows();
    const SparseMatrix Z = random_columns(n, 5, 3);
    const solve::DeflatedPreconditioner B(A, std::make_unique<JacobiPreconditioner>(A), Z);
    EXPECT_EQ(B.vectors(), 5);
    const Matrix Bd = formed(B, n);
    EXPECT_LE((Bd - Bd.transpose()).norm(), 1e-13 * Bd.norm());
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(0.5 * (Bd + Bd.transpose()));
    EXPECT_GT(eig.eigenvalues().minCoeff(), 1e-3 * eig.eigenvalues().maxCoeff());
    // B A = I on span Z: (I - BA) = (I - QA)(I - MA)(I - QA) and (I - QA) Z = 0.
    const Matrix Zd = Matrix(Z);
    EXPECT_LE((Bd * (Matrix(A) * Zd) - Zd).norm(), 1e-12 * Zd.norm());
    // Against the formula B = Q + (I - QA) M (I - AQ).
    const Matrix Ad = Matrix(A);
    const Matrix Q = Zd * (Zd.transpose() * Ad * Zd).inverse() * Zd.transpose();
    const Matrix I = Matrix::Identity(n, n);
    const Matrix M = Ad.diagonal().cwiseInverse().asDiagonal();
    EXPECT_LE((Bd - (Q + (I - Q * Ad) * M * (I - Ad * Q))).norm(), 1e-12 * Bd.norm());
}

TEST(Deflation, RefusesBadVectors) {
    const SparseMatrix A = shifted_laplacian(4);
    const auto jacobi = [&] { return std::make_unique<JacobiPreconditioner>(A); };
    test::expect_error(
        [&] { solve::DeflatedPreconditioner(A, jacobi(), random_columns(15, 2, 1)); },
        "15 x 2 vectors for a 16 x 16 matrix");
    test::expect_error([&] { solve::DeflatedPreconditioner(A, jacobi(), SparseMatrix(16, 0)); },
                       "no deflation vector");
    Matrix twice = Matrix(random_columns(16, 2, 1));
    twice.col(1) = twice.col(0);
    EXPECT_THROW(solve::DeflatedPreconditioner(A, jacobi(), twice.sparseView()),
                 NotPositiveDefinite);
}

}  // namespace
}  // namespace coarsegrain
