#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "coarsegrain/mesh/bvh.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

template <int D>
mesh::Box<D> random_box(std::mt19937& rng, double max_size) {
    std::uniform_real_distribution<double> U(0.0, 1.0);
    Eigen::Matrix<double, D, 1> lo, size;
    for (int d = 0; d < D; ++d) {
        lo[d] = U(rng);
        size[d] = max_size * U(rng);
    }
    return mesh::Box<D>(lo, lo + size);
}

// Random boxes of mixed sizes (many leaves, deep tree), random queries: the tree reports
// exactly the boxes a brute-force scan finds, each once. One query touches a box only on a face
// (closed boxes: reported).
template <int D>
void check_against_brute_force() {
    std::mt19937 rng(21 + D);
    std::vector<mesh::Box<D>> boxes;
    for (int i = 0; i < 600; ++i) boxes.push_back(random_box<D>(rng, i % 10 == 0 ? 0.5 : 0.05));
    const mesh::AabbTree<D> tree(boxes);
    ASSERT_EQ(tree.size(), 600);
    std::vector<mesh::Box<D>> queries;
    for (int q = 0; q < 200; ++q) queries.push_back(random_box<D>(rng, 0.2));
    Eigen::Matrix<double, D, 1> touch_lo = boxes[7].min(), touch_hi = boxes[7].max();
    touch_lo[0] = touch_hi[0] = boxes[7].max()[0];
    queries.emplace_back(touch_lo, touch_hi);
    for (const auto& q : queries) {
        std::vector<Index> expected;
        for (Index i = 0; i < 600; ++i)
            if (boxes[i].intersects(q)) expected.push_back(i);
        EXPECT_EQ(tree.overlapping(q), expected);
    }
    const auto last = tree.overlapping(queries.back());
    EXPECT_NE(std::find(last.begin(), last.end(), 7), last.end());
}

}  // namespace

TEST(Bvh, QueriesMatchBruteForce2D) { check_against_brute_force<2>(); }
TEST(Bvh, QueriesMatchBruteForce3D) { check_against_brute_force<3>(); }

TEST(Bvh, EmptyTreeAndEmptyQueryFindNothing) {
    const mesh::AabbTree<3> empty(std::vector<mesh::Box<3>>{});
    EXPECT_TRUE(
        empty.overlapping(mesh::Box<3>(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones())).empty());
    const mesh::AabbTree<2> one({mesh::Box<2>(Eigen::Vector2d::Zero(), Eigen::Vector2d::Ones())});
    EXPECT_TRUE(one.overlapping(mesh::Box<2>()).empty());  // default box is empty
    EXPECT_EQ(one.overlapping(mesh::Box<2>(Eigen::Vector2d::Ones(), Eigen::Vector2d::Ones())),
              std::vector<Index>{0});
}

// Element boxes of a grid: each element's box is spanned by its corners.
TEST(Bvh, ElementBoxesSpanTheCorners) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(2, 2, 1));
    test::distort_interior(m, 0.3);
    const auto boxes = mesh::element_boxes<3>(m);
    ASSERT_EQ(static_cast<Index>(boxes.size()), m.num_elements());
    for (Index e = 0; e < m.num_elements(); ++e) {
        const Matrix X = m.element_positions(e);
        EXPECT_EQ(boxes[e].min(), X.colwise().minCoeff().transpose());
        EXPECT_EQ(boxes[e].max(), X.colwise().maxCoeff().transpose());
    }
    test::expect_error([&] { mesh::element_boxes<2>(m); }, "a 3D mesh of tet elements");
}
