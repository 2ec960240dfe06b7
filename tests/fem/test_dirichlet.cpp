#include <gtest/gtest.h>

#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/dirichlet.hpp"

using namespace coarsegrain;

namespace {

// fix_nodes prescribes every component of each node (DOF dim*node + d), keeps the DOFs sorted
// and unique, and later calls override earlier values; fix_component sets one component.
TEST(Dirichlet, FixNodesAndComponentsMergeSorted) {
    fem::Dirichlet bc;
    bc.fix_nodes({4, 1}, Eigen::Vector3d(1, 2, 3));
    EXPECT_EQ(bc.dofs, (std::vector<Index>{3, 4, 5, 12, 13, 14}));
    EXPECT_EQ(bc.values, (Vector(6) << 1, 2, 3, 1, 2, 3).finished());
    bc.fix_component({1, 2}, 3, 2, -7.0);  // overrides DOF 5, adds DOF 8
    EXPECT_EQ(bc.dofs, (std::vector<Index>{3, 4, 5, 8, 12, 13, 14}));
    EXPECT_EQ(bc.values, (Vector(7) << 1, 2, -7, -7, 1, 2, 3).finished());
    bc.fix_nodes({4, 4}, Eigen::Vector3d(0, 0, 9));  // a repeated node: one entry per DOF
    EXPECT_EQ(bc.dofs.size(), 7u);
    EXPECT_EQ(bc.values[6], 9.0);
    EXPECT_FALSE(bc.empty());
    EXPECT_THROW(bc.fix_component({0}, 3, 3, 0.0), Error);
    EXPECT_THROW(bc.fix_nodes({-1}, Eigen::Vector2d(0, 0)), Error);
}

// reduce/expand against a dense reference on a random sparse symmetric matrix: K_ff is the
// free block, rhs = f_f - K_fd u_d (1e-14 relative), and expand puts the free solution and
// the prescribed values back in place (exactly).
TEST(Dirichlet, ReduceMatchesDenseEliminationAndExpandRestores) {
    const Index n = 40;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-1, 1);
    Matrix dense = Matrix::Zero(n, n);
    for (Index i = 0; i < n; ++i)
        for (Index j = 0; j <= i; ++j)
            if (i == j || U(rng) > 0.6) dense(i, j) = dense(j, i) = U(rng);
    const SparseMatrix K = dense.sparseView();
    Vector f(n);
    for (Index i = 0; i < n; ++i) f[i] = U(rng);
    fem::Dirichlet bc;
    bc.dofs = {0, 3, 4, 17, 39};
    bc.values = (Vector(5) << 0.5, -1.0, 0.0, 2.0, 0.25).finished();

    const fem::ReducedSystem sys = fem::reduce(K, f, bc);
    ASSERT_EQ(sys.free_dofs.size(), n - 5);
    Vector ud = Vector::Zero(n);
    for (std::size_t k = 0; k < bc.dofs.size(); ++k)
        ud[bc.dofs[k]] = bc.values[static_cast<Index>(k)];
    const Vector full_rhs = f - dense * ud;
    const Matrix Kff(sys.K);
    for (Index a = 0; a < sys.free_dofs.size(); ++a) {
        EXPECT_NEAR(sys.rhs[a], full_rhs[sys.free_dofs[a]], 1e-14 * full_rhs.norm());
        for (Index b = 0; b < sys.free_dofs.size(); ++b)
            EXPECT_EQ(Kff(a, b), dense(sys.free_dofs[a], sys.free_dofs[b]));
    }
    const Vector uf = Vector::LinSpaced(n - 5, 1, 2);
    const Vector u = fem::expand(sys, uf, bc, n);
    for (Index a = 0; a < uf.size(); ++a) EXPECT_EQ(u[sys.free_dofs[a]], uf[a]);
    for (std::size_t k = 0; k < bc.dofs.size(); ++k)
        EXPECT_EQ(u[bc.dofs[k]], bc.values[static_cast<Index>(k)]);

    // No Dirichlet DOFs: the system is returned unchanged.
    const fem::ReducedSystem all = fem::reduce(K, f, fem::Dirichlet{});
    EXPECT_EQ(Matrix(all.K), dense);
    EXPECT_EQ(all.rhs, f);
}

TEST(Dirichlet, ReduceRejectsBadInput) {
    const SparseMatrix K = Matrix::Identity(6, 6).sparseView();
    const Vector f = Vector::Zero(6);
    fem::Dirichlet unsorted;
    unsorted.dofs = {3, 1};
    unsorted.values = Vector::Zero(2);
    EXPECT_THROW(fem::reduce(K, f, unsorted), Error);
    fem::Dirichlet out_of_range;
    out_of_range.dofs = {6};
    out_of_range.values = Vector::Zero(1);
    EXPECT_THROW(fem::reduce(K, f, out_of_range), Error);
    EXPECT_THROW(fem::reduce(K, Vector::Zero(5), fem::Dirichlet{}), Error);
}

}  // namespace
