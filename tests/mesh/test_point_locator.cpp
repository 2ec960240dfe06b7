#include <gtest/gtest.h>

#include <chrono>
#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "mesh/drop_elements.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

// The position x(local) of a location computed from its local coordinates alone (barycentric
// combination for simplices, this test's own bilinear/trilinear map for quads/hexes), and a
// check that local is in the element's reference domain up to `slack`.
Eigen::VectorXd position_from_local(const mesh::Mesh& m, const mesh::Location& loc, double slack) {
    const Matrix X = m.element_positions(loc.element);
    const int dim = m.dim();
    if (mesh::is_simplex(m.type)) {
        EXPECT_EQ(loc.local.size(), dim + 1);
        EXPECT_GE(loc.local.minCoeff(), -slack);
        EXPECT_NEAR(loc.local.sum(), 1.0, 1e-14);
        return X.transpose() * loc.local;
    }
    EXPECT_EQ(loc.local.size(), dim);
    EXPECT_GE(loc.local.minCoeff(), -slack);
    EXPECT_LE(loc.local.maxCoeff(), 1.0 + slack);
    // Corners of the reference square/cube in the element's node order.
    const int corners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    Eigen::VectorXd x = Eigen::VectorXd::Zero(dim);
    for (Index a = 0; a < X.rows(); ++a) {
        double N = 1;
        for (int k = 0; k < dim; ++k) N *= corners[a][k] ? loc.local[k] : 1 - loc.local[k];
        EXPECT_NEAR(loc.weights[a], N, 1e-15);
        x += N * X.row(a).transpose();
    }
    return x;
}

mesh::Mesh distorted_grid(ElementType type, int n) {
    const int dim = mesh::element_dim(type);
    Eigen::VectorXd lo(dim), hi(dim);
    Eigen::VectorXi cells(dim);
    for (int d = 0; d < dim; ++d) {
        lo[d] = -1.0 + 0.25 * d;
        hi[d] = 1.0 + 0.5 * d;
        cells[d] = n + d;
    }
    mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    test::distort_interior(m, 0.3, 7);
    return m;
}

Eigen::VectorXd random_point(std::mt19937& rng, const Eigen::VectorXd& lo,
                             const Eigen::VectorXd& hi) {
    std::uniform_real_distribution<double> U(0.0, 1.0);
    Eigen::VectorXd p(lo.size());
    for (Eigen::Index d = 0; d < lo.size(); ++d) p[d] = lo[d] + U(rng) * (hi[d] - lo[d]);
    return p;
}

}  // namespace

class PointLocatorTest : public ::testing::TestWithParam<ElementType> {};

// Random points in a distorted grid (boundary undistorted, so every point of the box is in
// the mesh): every point is found, the local coordinates lie in the element and map back to
// the point (proof of containment), and the weights reproduce a linear field exactly
// (1e-12: round-off of an O(1) field over O(1) weights).
TEST_P(PointLocatorTest, RandomPointsAreFoundAndInterpolateLinearFields) {
    const mesh::Mesh m = distorted_grid(GetParam(), 6);
    const int dim = m.dim();
    const mesh::PointLocator locator(m);
    const Matrix box = mesh::bounding_box(m);
    const Eigen::VectorXd lo = box.row(0).transpose(), hi = box.row(1).transpose();
    const Matrix A = Matrix::Random(dim, dim);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(dim);
    const Vector field = test::linear_field(m.rest_positions, A, b);
    std::mt19937 rng(3);
    for (int i = 0; i < 2000; ++i) {
        const Eigen::VectorXd p = random_point(rng, lo, hi);
        const std::optional<mesh::Location> loc = locator.locate(p);
        ASSERT_TRUE(loc.has_value()) << p.transpose();
        EXPECT_NEAR(loc->weights.sum(), 1.0, 1e-14);
        // Containment: local coordinates in the reference domain (1e-10, the documented
        // tolerance) and mapping to p (1e-12 of the O(1) coordinates: Newton converges to
        // 1e-15 in reference coordinates).
        EXPECT_LT((position_from_local(m, *loc, 1e-10) - p).norm(), 1e-12);
        const Eigen::VectorXd u = mesh::interpolate(m, *loc, field, dim);
        EXPECT_LT((u - (A * p + b)).norm(), 1e-12);
    }
}

// Nodes, including box corners and boundary nodes, are found with weight 1 at that node
// (round-off 1e-10 from the Newton/barycentric solve at a vertex).
TEST_P(PointLocatorTest, NodesAreFound) {
    const mesh::Mesh m = distorted_grid(GetParam(), 3);
    const mesh::PointLocator locator(m);
    for (Index v = 0; v < m.num_nodes(); ++v) {
        const std::optional<mesh::Location> loc =
            locator.locate(m.rest_positions.row(v).transpose());
        ASSERT_TRUE(loc.has_value()) << "node " << v;
        for (Index a = 0; a < m.elements.cols(); ++a)
            EXPECT_NEAR(loc->weights[a], m.elements(loc->element, a) == v ? 1.0 : 0.0, 1e-10);
    }
}

// Points outside the box: locate returns nothing; locate_nearest returns non-negative weights
// summing to 1 whose position is the nearest point of the mesh, which for a box is p clamped
// to the box (1e-10: tolerance of the projected Gauss-Newton / simplex projection).
TEST_P(PointLocatorTest, OutsidePointsProjectToTheBox) {
    const mesh::Mesh m = distorted_grid(GetParam(), 5);
    const mesh::PointLocator locator(m);
    const Matrix box = mesh::bounding_box(m);
    const Eigen::VectorXd lo = box.row(0).transpose(), hi = box.row(1).transpose();
    const Eigen::VectorXd size = hi - lo;
    std::mt19937 rng(11);
    int outside = 0;
    while (outside < 300) {
        const Eigen::VectorXd p = random_point(rng, lo - size, hi + size);
        const Eigen::VectorXd q = p.cwiseMax(lo).cwiseMin(hi);
        if ((p - q).norm() < 1e-6) continue;
        ++outside;
        EXPECT_FALSE(locator.locate(p).has_value());
        const mesh::Location loc = locator.locate_nearest(p);
        ASSERT_GE(loc.element, 0);
        EXPECT_GE(loc.weights.minCoeff(), 0.0);
        EXPECT_NEAR(loc.weights.sum(), 1.0, 1e-14);
        EXPECT_LT((position_from_local(m, loc, 0.0) - q).norm(), 1e-10) << p.transpose();
    }
    // Far away: still the nearest corner.
    const Eigen::VectorXd far = hi + 1e3 * size;
    const mesh::Location loc = locator.locate_nearest(far);
    EXPECT_LT((position_from_local(m, loc, 0.0) - hi).norm(), 1e-9);
    // Inside, locate_nearest agrees with locate.
    const Eigen::VectorXd mid = 0.5 * (lo + hi) + 0.01 * size;
    EXPECT_EQ(locator.locate_nearest(mid).element, locator.locate(mid)->element);
}

// A point in a cavity is not located; its nearest point is on the cavity wall: the cavity is
// [1/3, 2/3]^dim and p = (0.5, 0.45, ...) is 0.45 - 1/3 from the nearest wall (y = 1/3).
TEST_P(PointLocatorTest, PointInCavityProjectsToItsWall) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    const auto in_block = [](const Eigen::VectorXd& c) {
        return (c.array() > 1.0 / 3).all() && (c.array() < 2.0 / 3).all();
    };
    const mesh::Mesh m = test::drop_elements(
        mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                        Eigen::VectorXi::Constant(dim, 6)),
        in_block);
    const mesh::PointLocator locator(m);
    Eigen::VectorXd p = Eigen::VectorXd::Constant(dim, 0.5);
    p[1] = 0.45;
    EXPECT_FALSE(locator.locate(p).has_value());
    const mesh::Location loc = locator.locate_nearest(p);
    Eigen::VectorXd expected = p;
    expected[1] = 1.0 / 3;
    EXPECT_LT((position_from_local(m, loc, 0.0) - expected).norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, PointLocatorTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const ::testing::TestParamInfo<ElementType>& param_info) {
                             return mesh::element_name(param_info.param);
                         });

// 100K queries on a distorted ~50K-element hex grid and tet grid. Measured about 0.25 s
// (hex) and 0.1 s (tet) in Release; the 2 s bound only catches a broken index (a linear scan
// would take minutes). "Slow" keeps this timing test out of the sanitizer run.
TEST(PointLocatorSlow, ManyQueriesAreFast) {
    for (const auto& [type, n] : {std::pair{ElementType::Hex8, 37}, {ElementType::Tet4, 20}}) {
        mesh::Mesh m = mesh::make_grid(type, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(),
                                       Eigen::Vector3i(n, n, n + 1));
        test::distort_interior(m, 0.3);
        const auto t0 = std::chrono::steady_clock::now();
        const mesh::PointLocator locator(m);
        std::mt19937 rng(5);
        int found = 0;
        for (int i = 0; i < 100000; ++i)
            found +=
                locator.locate(random_point(rng, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()))
                    .has_value();
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        EXPECT_EQ(found, 100000);
        EXPECT_LT(seconds, 2.0) << mesh::element_name(type) << " " << m.num_elements();
    }
}

TEST(PointLocator, BadInputIsAnError) {
    const mesh::Mesh m = mesh::make_grid(ElementType::Quad4, Eigen::Vector2d::Zero(),
                                         Eigen::Vector2d::Ones(), Eigen::Vector2i(2, 2));
    const mesh::PointLocator locator(m);
    EXPECT_THROW(locator.locate(Eigen::Vector3d::Zero()), Error);
    EXPECT_THROW(locator.locate(Eigen::Vector2d(std::nan(""), 0)), Error);
    const mesh::Location loc = *locator.locate(Eigen::Vector2d(0.3, 0.3));
    EXPECT_THROW(mesh::interpolate(m, loc, Vector::Zero(5), 2), Error);
    EXPECT_EQ(mesh::interpolate(m, loc, Vector::Ones(18), 2), Eigen::Vector2d::Ones());
    mesh::Mesh empty;
    empty.type = ElementType::Tri3;
    empty.rest_positions.resize(0, 2);
    empty.elements.resize(0, 3);
    EXPECT_THROW(mesh::PointLocator{empty}, Error);
}
