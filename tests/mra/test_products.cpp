// The Galerkin product of the construction (src/mra/products.hpp, private to the library) on
// each of its kernels, against Eigen's product.
#include <gtest/gtest.h>

#include <random>

#include "../../src/mra/products.hpp"
#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra::detail {
namespace {

/// An m x n matrix whose entries are nonzero with probability `density`.
SparseMatrix random_sparse(Index m, Index n, double density, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> value(-1.0, 1.0), coin(0.0, 1.0);
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index j = 0; j < n; ++j)
        for (Index i = 0; i < m; ++i)
            if (coin(rng) < density) t.emplace_back(i, j, value(rng));
    SparseMatrix M(m, n);
    M.setFromTriplets(t.begin(), t.end());
    return M;
}

/// Groups of up to 8 consecutive rows.
std::vector<IndexVector> consecutive_groups(Index rows) {
    std::vector<IndexVector> groups;
    for (Index b = 0; b < rows; b += 8)
        groups.push_back(IndexVector::LinSpaced(std::min<Index>(8, rows - b), b,
                                                std::min<Index>(b + 8, rows) - 1));
    return groups;
}

// M 60% dense takes the dense kernel, with X dense (50%) or sparse (1%: M X by columns of X,
// times_sparse); M 5% dense the grouped one. Every kernel sums the same products in
// another order: 1e-13 relative.
TEST(MraCongruence, EveryKernelIsTheGalerkinProduct) {
    const Index m = 600, n = 300;  // m above the dense kernel's 512-column blocks
    for (const double m_density : {0.6, 0.05})
        for (const double x_density : {0.5, 0.01}) {
            const SparseMatrix half = random_sparse(n, n, x_density / 2, 7);
            SparseMatrix X = SparseMatrix(half + SparseMatrix(half.transpose()));
            for (Index i = 0; i < n; ++i) X.coeffRef(i, i) += 1.0;
            X.makeCompressed();  // as the library's operators (the kernels read raw CSC arrays)
            const SparseMatrix M = random_sparse(m, n, m_density, 11);
            const SparseMatrix A = congruence(M, X, consecutive_groups(m));
            const Matrix expected = Matrix(M) * Matrix(X) * Matrix(M).transpose();
            const Matrix lower = expected.triangularView<Eigen::Lower>();
            EXPECT_LT((Matrix(A) - lower).norm(), 1e-13 * expected.norm())
                << "M " << m_density << ", X " << x_density;
        }
}

// A sparse M (at most 5% dense) is read through bands of its rows, transposed one at a time.
// Here M is banded like a localized C̃ (each row's entries near its position), 1.3% dense, and
// the groups are like a grid's node blocks: two runs of 4 rows, `stride` rows apart, so that a
// band's groups reach into the next band's rows. Groups read their band's rows by rows where
// most of those rows' entries meet their product with X, by columns else, and the rows past
// their band by columns (leaving those out fails both cases). Same sums in another order: 1e-13.
TEST(MraCongruence, SparseRowsAreReadBandByBand) {
    const Index m = 1200, n = 1500, width = 20, stride = 60;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index i = 0; i < m; ++i) {
        const Index centre = i * n / m;
        for (Index j = std::max<Index>(0, centre - width / 2);
             j < std::min<Index>(n, centre + width / 2); ++j)
            t.emplace_back(i, j, value(rng));
    }
    SparseMatrix M(m, n);
    M.setFromTriplets(t.begin(), t.end());
    ASSERT_LT(static_cast<double>(M.nonZeros()), 0.05 * m * n);
    std::vector<IndexVector> groups;
    for (Index b = 0; b < m; b += 2 * stride)
        for (Index r = b; r < b + stride; r += 4) {
            IndexVector J(8);
            for (Index c = 0; c < 4; ++c) {
                J[c] = r + c;
                J[4 + c] = r + stride + c;
            }
            groups.push_back(J);
        }
    for (const double x_density : {0.5, 0.01}) {
        const SparseMatrix half = random_sparse(n, n, x_density / 2, 7);
        SparseMatrix X = SparseMatrix(half + SparseMatrix(half.transpose()));
        for (Index i = 0; i < n; ++i) X.coeffRef(i, i) += 1.0;
        X.makeCompressed();
        const SparseMatrix A = congruence(M, X, groups);
        const Matrix expected = Matrix(M) * Matrix(X) * Matrix(M).transpose();
        const Matrix lower = expected.triangularView<Eigen::Lower>();
        EXPECT_LT((Matrix(A) - lower).norm(), 1e-13 * expected.norm()) << "X " << x_density;
    }
}

// W A Y fused: the dense product to round-off, with the structural pattern of the two sparse
// products (a column of Y hitting only cancelling entries keeps them as stored zeros), for a
// W wider than tall (B^k) and Y wide (R), with 400 columns so that both threads take part;
// through product when A Y pays dense.
TEST(MraTripleProduct, IsTheProductOfThree) {
    for (const double a_density : {0.02, 0.6}) {
        const SparseMatrix W = random_sparse(300, 500, 0.01, 3);
        const SparseMatrix A = random_sparse(500, 500, a_density, 5);
        const SparseMatrix Y = random_sparse(500, 400, 0.01, 9);
        const SparseMatrix P = triple_product(W, A, Y);
        const Matrix expected = Matrix(W) * Matrix(A) * Matrix(Y);
        ASSERT_EQ(P.rows(), 300);
        ASSERT_EQ(P.cols(), 400);
        EXPECT_LT((Matrix(P) - expected).norm(), 1e-13 * expected.norm()) << a_density;
        if (a_density < 0.1) {  // sparse: the same pattern as the two sparse products
            const SparseMatrix two = product(W, product(A, Y));
            EXPECT_EQ(P.nonZeros(), two.nonZeros());
        }
    }
}

TEST(MraTripleProduct, KeepsCancellationsAsStructuralZeros) {
    // A Y = (1, -1, 0, ...) and W = (1 1 0 ...): the single entry cancels, kept as a stored
    // zero (100 columns: small enough, A Y would go dense, which stores nonzeros only).
    SparseMatrix W(1, 100), A(100, 100), Y(100, 1);
    W.insert(0, 0) = 1.0;
    W.insert(0, 1) = 1.0;
    A.insert(0, 0) = 1.0;
    A.insert(1, 0) = -1.0;
    Y.insert(0, 0) = 1.0;
    const SparseMatrix P = triple_product(W, A, Y);  // uncompressed inputs are compressed first
    ASSERT_EQ(P.nonZeros(), 1);
    EXPECT_EQ(P.coeff(0, 0), 0.0);
}

TEST(MraTripleProduct, RefusesMismatchedSizes) {
    EXPECT_THROW(triple_product(SparseMatrix(2, 3), SparseMatrix(4, 4), SparseMatrix(4, 1)),
                 Error);
    EXPECT_THROW(triple_product(SparseMatrix(2, 4), SparseMatrix(4, 4), SparseMatrix(3, 1)),
                 Error);
}

// In place for a structurally symmetric matrix: the storage is the argument's.
TEST(MraSymmetrized, AveragesInPlaceOrThroughTheTranspose) {
    const SparseMatrix half = random_sparse(50, 50, 0.1, 13);
    SparseMatrix M = SparseMatrix(half + SparseMatrix(half.transpose()));
    for (Index j = 0; j < M.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(M, j); it; ++it) it.valueRef() *= 1.0 + 0.01 * it.row();
    M.makeCompressed();
    const Matrix expected = 0.5 * (Matrix(M) + Matrix(M).transpose());
    const double* storage = M.valuePtr();
    const SparseMatrix S = symmetrized(std::move(M));
    EXPECT_EQ(S.valuePtr(), storage);
    EXPECT_LT((Matrix(S) - expected).norm(), 1e-15 * expected.norm());
    const SparseMatrix U = random_sparse(40, 40, 0.1, 17);  // not structurally symmetric
    EXPECT_LT((Matrix(symmetrized(U)) - 0.5 * (Matrix(U) + Matrix(U).transpose())).norm(),
              1e-15 * Matrix(U).norm());
}

}  // namespace
}  // namespace coarsegrain::mra::detail
