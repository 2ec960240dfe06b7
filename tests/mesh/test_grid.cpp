#include <gtest/gtest.h>

#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;

class GridTest : public ::testing::TestWithParam<mesh::ElementType> {};

// Every element of every grid is positively oriented and the measures sum to the box volume
// (exact up to round-off: 1e-12 relative).
TEST_P(GridTest, ElementsArePositiveAndFillTheBox) {
    const mesh::ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    Eigen::VectorXd lo = Eigen::VectorXd::Constant(dim, -0.5), hi(dim);
    Eigen::VectorXi cells(dim);
    for (int d = 0; d < dim; ++d) {
        hi[d] = 1.0 + d;
        cells[d] = 3 + d;
    }
    const mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    EXPECT_NO_THROW(mesh::validate(m, "grid"));
    double total = 0;
    for (Index e = 0; e < m.num_elements(); ++e) {
        const double v = mesh::element_measure(m, e);
        EXPECT_GT(v, 0.0);
        total += v;
    }
    const double expected = (hi - lo).prod();
    EXPECT_NEAR(total, expected, 1e-12 * expected);
    EXPECT_EQ(m.num_nodes(), (cells.array() + 1).prod());
}

INSTANTIATE_TEST_SUITE_P(AllTypes, GridTest,
                         ::testing::Values(mesh::ElementType::Tri3, mesh::ElementType::Quad4,
                                           mesh::ElementType::Tet4, mesh::ElementType::Hex8));
