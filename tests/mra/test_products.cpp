// The Galerkin product of the construction (src/mra/products.hpp, private to the library) on
// each of its kernels, against Eigen's product.
#include <gtest/gtest.h>

#include <random>

#include "../../src/mra/products.hpp"

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

}  // namespace
}  // namespace coarsegrain::mra::detail
