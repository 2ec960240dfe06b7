// Splitting quad/hex meshes into simplices on the same nodes.
#include <gtest/gtest.h>

#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/simplex_split.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

// Splitting a hex (quad) grid gives exactly make_grid's tet (triangle) grid, element for element,
// and each simplex keeps the material id of its hex.
TEST(SimplexSplit, GridsSplitIntoTheSimplexGrids) {
    for (const auto& [from, to] : {std::pair{mesh::ElementType::Hex8, mesh::ElementType::Tet4},
                                   std::pair{mesh::ElementType::Quad4, mesh::ElementType::Tri3}}) {
        const int dim = mesh::element_dim(from);
        const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim),
                              hi = Eigen::VectorXd::LinSpaced(dim, 1, 2);
        const Eigen::VectorXi cells = Eigen::VectorXi::LinSpaced(dim, 2, 4);
        mesh::Mesh m = mesh::make_grid(from, lo, hi, cells);
        for (Index e = 0; e < m.num_elements(); ++e) m.material_ids[e] = 7 * e;
        const mesh::Mesh s = mesh::simplex_split(m);
        const mesh::Mesh expected = mesh::make_grid(to, lo, hi, cells);
        const int per = mesh::simplices_per_element(from);
        EXPECT_EQ(s.type, to);
        EXPECT_EQ(s.rest_positions, m.rest_positions);
        EXPECT_EQ(s.elements, expected.elements);
        for (Index t = 0; t < s.num_elements(); ++t) EXPECT_EQ(s.material_ids[t], 7 * (t / per));
    }
}

// A distorted hex mesh (boundary nodes in place): the tets are positively oriented (validated by
// the split), fill the box exactly, and the split is conforming (each hex face is cut into two
// triangles shared by both neighbours, so the boundary has twice as many facets as the hex
// mesh's and stays in one piece).
TEST(SimplexSplit, DistortedHexesFillTheBoxConformingly) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                                   Eigen::Vector3d(1, 2, 1), Eigen::Vector3i(3, 4, 2));
    test::distort_interior(m, 0.2, 5);
    const mesh::Mesh s = mesh::simplex_split(m);
    double volume = 0;
    for (Index t = 0; t < s.num_elements(); ++t) volume += mesh::element_measure(s, t);
    EXPECT_NEAR(volume, 2.0, 1e-13);  // the box 1 x 2 x 1, round-off of 144 tets
    EXPECT_EQ(mesh::boundary(s).size(), 2 * mesh::boundary(m).size());
    EXPECT_EQ(mesh::boundary(s).num_components, 1);
}

// Two hexes sharing a face with differently oriented local axes would cut it along different
// diagonals: rejected.
TEST(SimplexSplit, InconsistentHexAxesAreRejected) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                                   Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(2, 1, 1));
    // Renumber the second hex by a quarter turn about the x axis (still positively oriented):
    // corners (0,0,0) (1,0,0) (1,1,0) (0,1,0) (0,0,1) ... -> y' = z, z' = 1 - y.
    const auto h = m.elements.row(1).eval();
    m.elements.row(1) << h[3], h[2], h[6], h[7], h[0], h[1], h[5], h[4];
    mesh::validate(m, "rotated");
    test::expect_error([&] { mesh::simplex_split(m); }, "not conforming");
}

}  // namespace
}  // namespace coarsegrain
