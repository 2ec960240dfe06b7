// Stiff clusters and their rigid motions (fem/stiff_clusters.hpp): components of one stiff
// material through shared facets; per cluster the rigid motions of its nodes, orthonormal, and
// their energy-minimizing extension over a few rings.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <functional>
#include <set>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/stiff_clusters.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

/// An n x n quad grid of the unit square with two materials (E 1 and E contrast), stiff where
/// stiff(centroid): its mesh, materials, and stiffness on the DOFs free of the clamp at y = 0.
struct ClusterProblem {
    mesh::Mesh mesh;
    material::ElementMaterials materials;
    fem::Dirichlet bc;
    SparseMatrix A;  ///< free by free
};

ClusterProblem cluster_problem(int n, double contrast,
                               const std::function<bool(const Eigen::VectorXd&)>& stiff) {
    ClusterProblem p;
    p.mesh = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d::Zero(),
                             Eigen::Vector2d::Ones(), Eigen::Vector2i(n, n));
    p.materials.dim = 2;
    p.materials.table = {material::isotropic(2, 1.0, 0.3, 1.0),
                         material::isotropic(2, contrast, 0.3, 1.0)};
    p.materials.index.resize(p.mesh.num_elements());
    const Matrix centres = mesh::element_centroids(p.mesh);
    for (Index e = 0; e < p.mesh.num_elements(); ++e)
        p.materials.index[e] = stiff(centres.row(e).transpose()) ? 1 : 0;
    p.bc.fix_nodes(mesh::nodes_in_box(p.mesh, Eigen::Vector2d(-1, -1e-9), Eigen::Vector2d(2, 1e-9)),
                   Eigen::Vector2d::Zero());
    const SparseMatrix K = fem::stiffness_matrix(p.mesh, p.materials);
    p.A = fem::reduce(K, Vector::Zero(K.rows()), p.bc).K;
    return p;
}

/// Stiff squares of side `side` in a checkerboard: they touch only at corners.
std::function<bool(const Eigen::VectorXd&)> checker_of(double side) {
    return [side](const Eigen::VectorXd& x) {
        return (static_cast<int>(std::floor(x[0] / side)) +
                static_cast<int>(std::floor(x[1] / side))) %
                   2 ==
               1;
    };
}

TEST(StiffClusters, ComponentsOfOneStiffMaterialThroughFacets) {
    const ClusterProblem p = cluster_problem(8, 1e3, checker_of(0.25));
    const fem::StiffClusters c = fem::stiff_clusters(p.mesh, p.materials, 10);
    EXPECT_EQ(c.count, 8);  // the 8 stiff 2 x 2 blocks, touching at corners only
    std::vector<int> sizes(static_cast<size_t>(c.count), 0);
    for (Index e = 0; e < p.mesh.num_elements(); ++e) {
        EXPECT_EQ(c.cluster[e] >= 0, p.materials.index[e] == 1) << "element " << e;
        if (c.cluster[e] >= 0) ++sizes[static_cast<size_t>(c.cluster[e])];
    }
    for (const int s : sizes) EXPECT_EQ(s, 4);
    // Same Poisson ratio: the stiffness scales are in the ratio of E, 1e3.
    EXPECT_EQ(fem::stiff_clusters(p.mesh, p.materials, 999).count, 8);
    EXPECT_EQ(fem::stiff_clusters(p.mesh, p.materials, 1001).count, 0);
    const ClusterProblem homogeneous = cluster_problem(4, 1e3, [](const auto&) { return true; });
    EXPECT_EQ(fem::stiff_clusters(homogeneous.mesh, homogeneous.materials, 10).count, 0);
    test::expect_error([&] { fem::stiff_clusters(p.mesh, p.materials, 1); }, "expected a finite");
}

/// The rigid motions (x, y translations, rotation) of the grid nodes in `nodes`, rows over the
/// free DOFs.
Matrix rigid_on(const ClusterProblem& p, const std::set<Index>& nodes) {
    const IndexVector free = fem::free_dofs(p.mesh.num_dofs(), p.bc);
    Matrix R = Matrix::Zero(free.size(), 3);
    for (Index i = 0; i < free.size(); ++i) {
        const Index v = free[i] / 2, d = free[i] % 2;
        if (!nodes.count(v)) continue;
        R(i, d) = 1;
        const Eigen::Vector2d x = p.mesh.rest_positions.row(v).transpose();
        R(i, 2) = d == 0 ? -x[1] : x[0];
    }
    return R;
}

std::set<Index> cluster_nodes(const ClusterProblem& p, const fem::StiffClusters& c, Index k) {
    std::set<Index> nodes;
    for (Index e = 0; e < p.mesh.num_elements(); ++e)
        if (c.cluster[e] == k)
            for (Index a = 0; a < p.mesh.elements.cols(); ++a) nodes.insert(p.mesh.elements(e, a));
    return nodes;
}

TEST(StiffClusters, RigidMotionsPerClusterFormAPartitionOfUnity) {
    // 2 x 2 stiff blocks touching at corners: each shared node is the corner of two blocks.
    const ClusterProblem p = cluster_problem(8, 1e3, checker_of(0.25));
    const fem::StiffClusters c = fem::stiff_clusters(p.mesh, p.materials, 10);
    const Matrix Z = Matrix(fem::cluster_rigid_modes(p.mesh, c, p.A, p.bc.dofs, 0));
    ASSERT_EQ(Z.cols(), 3 * c.count);  // no cluster touches the clamp at y = 0 with all nodes
    const IndexVector free = fem::free_dofs(p.mesh.num_dofs(), p.bc);
    Vector shared = Vector::Zero(free.size());  // the clusters at each free DOF's node
    std::set<Index> all;
    for (Index k = 0; k < c.count; ++k)
        for (const Index v : cluster_nodes(p, c, k)) {
            all.insert(v);
            for (Index i = 0; i < free.size(); ++i) shared[i] += free[i] / 2 == v;
        }
    EXPECT_EQ(shared.maxCoeff(), 2);
    for (Index k = 0; k < c.count; ++k) {
        // Undoing the division by the node's cluster count gives orthonormal columns that span
        // the cluster's rigid motions and are zero off its nodes.
        const Matrix Zk = shared.cwiseMax(1).asDiagonal() * Z.middleCols(3 * k, 3);
        EXPECT_LE((Zk.transpose() * Zk - Matrix::Identity(3, 3)).norm(), 1e-12);
        const Matrix R = rigid_on(p, cluster_nodes(p, c, k));
        EXPECT_LE((R - Zk * (Zk.transpose() * R)).norm(), 1e-12 * R.norm()) << "cluster " << k;
        EXPECT_LE((Zk - R * R.colPivHouseholderQr().solve(Zk)).norm(), 1e-12) << "cluster " << k;
    }
    // The body's rigid motions on all the clusters' nodes lie in the span: the division makes the
    // columns a partition of unity where clusters touch.
    const Matrix R = rigid_on(p, all);
    const Matrix fit = Z * Z.colPivHouseholderQr().solve(R);
    EXPECT_LE((R - fit).norm(), 1e-12 * R.norm());
}

TEST(StiffClusters, ExtensionIsEnergyMinimizingWithinTheRings) {
    const ClusterProblem p = cluster_problem(16, 1e3, checker_of(0.25));
    const fem::StiffClusters c = fem::stiff_clusters(p.mesh, p.materials, 10);
    const SparseMatrix Z0 = fem::cluster_rigid_modes(p.mesh, c, p.A, p.bc.dofs, 0);
    const SparseMatrix Z2 = fem::cluster_rigid_modes(p.mesh, c, p.A, p.bc.dofs, 2);
    ASSERT_EQ(Z2.cols(), Z0.cols());
    const IndexVector free = fem::free_dofs(p.mesh.num_dofs(), p.bc);
    const Matrix AZ = Matrix(p.A * Z2);
    const Matrix Z0d = Matrix(Z0), Z2d = Matrix(Z2);
    const double h = 1.0 / 16;
    for (Index k = 0; k < c.count; ++k) {
        const std::set<Index> nodes = cluster_nodes(p, c, k);
        Eigen::Vector2d lo = Eigen::Vector2d::Constant(2), hi = Eigen::Vector2d::Constant(-1);
        for (const Index v : nodes) {
            lo = lo.cwiseMin(p.mesh.rest_positions.row(v).transpose());
            hi = hi.cwiseMax(p.mesh.rest_positions.row(v).transpose());
        }
        for (Index i = 0; i < free.size(); ++i) {
            const Index v = free[i] / 2;
            const Eigen::Vector2d x = p.mesh.rest_positions.row(v).transpose();
            // Rings of a quad grid's node graph are squares: 2 rings reach 2h beyond the cluster.
            const double reach = std::max((lo - x).maxCoeff(), (x - hi).maxCoeff()) / h;
            for (Index j = 3 * k; j < 3 * k + 3; ++j) {
                if (nodes.count(v)) {
                    EXPECT_NEAR(Z2d(i, j), Z0d(i, j), 1e-14);  // the cluster's values kept
                } else if (reach > 2.5) {
                    EXPECT_EQ(Z2d(i, j), 0);
                } else if (reach > 0.5 && Z2d(i, j) != 0) {
                    // An extension DOF: the residual of the soft problem vanishes there (its
                    // neighbours in other clusters count as zero, and are zero in Z2 too,
                    // unless the node neighbours the cluster's own shell only).
                    EXPECT_LE(std::abs(AZ(i, j)), 1e-10 * p.A.diagonal().maxCoeff())
                        << "cluster " << k << " DOF " << free[i];
                }
            }
        }
    }
}

TEST(StiffClusters, CornerTouchingElementsWithoutOwnNodesAreSkipped) {
    // A checkerboard of single elements: an interior stiff element shares all 4 nodes with its
    // diagonal neighbours, so its rigid motions would depend on theirs.
    const ClusterProblem p = cluster_problem(6, 1e3, checker_of(1.0 / 6));
    const fem::StiffClusters c = fem::stiff_clusters(p.mesh, p.materials, 10);
    EXPECT_EQ(c.count, 18);
    const SparseMatrix Z = fem::cluster_rigid_modes(p.mesh, c, p.A, p.bc.dofs, 1);
    EXPECT_GT(Z.cols(), 0);
    EXPECT_LT(Z.cols(), 3 * c.count);
    // The columns kept are independent: Z^T A Z is positive definite.
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(Matrix(Z.transpose() * p.A * Z));
    EXPECT_GT(eig.eigenvalues().minCoeff(), 1e-10 * eig.eigenvalues().maxCoeff());
}

TEST(StiffClusters, RefusesMismatchedInput) {
    const ClusterProblem p = cluster_problem(4, 1e3, checker_of(0.5));
    const fem::StiffClusters c = fem::stiff_clusters(p.mesh, p.materials, 10);
    test::expect_error([&] { fem::cluster_rigid_modes(p.mesh, c, p.A, p.bc.dofs, -1); },
                       "rings = -1");
    test::expect_error([&] { fem::cluster_rigid_modes(p.mesh, c, p.A, {}, 0); }, "the free DOFs");
    test::expect_error([&] { fem::cluster_rigid_modes(p.mesh, c, p.A, {3, 1}, 0); }, "sorted");
}

}  // namespace
}  // namespace coarsegrain
