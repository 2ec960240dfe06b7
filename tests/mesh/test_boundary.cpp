#include <gtest/gtest.h>

#include <chrono>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "mesh/drop_elements.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

Eigen::VectorXd facet_centre(const mesh::Mesh& m, const mesh::Boundary& b, Index f) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(m.dim());
    for (Index a = 0; a < b.facets.cols(); ++a)
        c += m.rest_positions.row(b.facets(f, a)).transpose();
    return c / static_cast<double>(b.facets.cols());
}

mesh::Mesh box_grid(ElementType type, double distortion) {
    const int dim = mesh::element_dim(type);
    Eigen::VectorXd lo = Eigen::VectorXd::Constant(dim, -0.5), hi(dim);
    Eigen::VectorXi cells(dim);
    for (int d = 0; d < dim; ++d) {
        hi[d] = 1.0 + 0.5 * d;
        cells[d] = 3 + d;
    }
    mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    if (distortion > 0) test::distort_interior(m, distortion);
    return m;
}

// Every facet's normal points from its owner's centroid towards the facet: for convex
// elements the facet centre minus the owner centroid has a positive component along the
// outward normal.
void expect_normals_point_away_from_owner(const mesh::Mesh& m, const mesh::Boundary& b) {
    const Matrix centres = mesh::element_centroids(m);
    for (Index f = 0; f < b.size(); ++f) {
        const Eigen::VectorXd d = facet_centre(m, b, f) - centres.row(b.owner[f]).transpose();
        EXPECT_GT(b.normals.row(f).dot(d), 0.0) << "facet " << f;
        EXPECT_NEAR(b.normals.row(f).norm(), 1.0, 1e-14);
    }
}

}  // namespace

class BoundaryTest : public ::testing::TestWithParam<ElementType> {};

// A box grid: the facets tile the box surface (areas sum to it, up to round-off 1e-12
// relative), each facet lies in one face of the box with that face's outward normal, the
// facet count is the number of cell faces on the surface, and the closed surface has zero
// total vector area (1e-12 of the surface: round-off of a sum of O(100) terms).
TEST_P(BoundaryTest, BoxGridFacetsTileTheSurface) {
    const ElementType type = GetParam();
    for (double distortion : {0.0, 0.3}) {
        const mesh::Mesh m = box_grid(type, distortion);
        const int dim = m.dim();
        const mesh::Boundary b = mesh::boundary(m);
        const Matrix box = mesh::bounding_box(m);
        const Eigen::VectorXd ext = (box.row(1) - box.row(0)).transpose();

        const Eigen::Vector3i n(3, 4, 5);
        Index expected_facets = 0;
        double surface = 0;
        if (dim == 2) {
            expected_facets = 2 * (n[0] + n[1]);
            surface = 2 * (ext[0] + ext[1]);
        } else {
            expected_facets = 2 * (n[0] * n[1] + n[1] * n[2] + n[0] * n[2]);
            surface = 2 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[0] * ext[2]);
        }
        if (type == ElementType::Tet4) expected_facets *= 2;  // each cell face is 2 triangles
        EXPECT_EQ(b.size(), expected_facets);
        EXPECT_NEAR(b.areas.sum(), surface, 1e-12 * surface);

        Eigen::VectorXd total = Eigen::VectorXd::Zero(dim);
        for (Index f = 0; f < b.size(); ++f) total += b.areas[f] * b.normals.row(f).transpose();
        EXPECT_LT(total.norm(), 1e-12 * surface);

        for (Index f = 0; f < b.size(); ++f) {
            // Find the box face containing the facet and compare normals exactly (axis vectors).
            int matches = 0;
            for (int d = 0; d < dim; ++d)
                for (int side = 0; side < 2; ++side) {
                    bool on = true;
                    for (Index a = 0; a < b.facets.cols(); ++a)
                        on = on && m.rest_positions(b.facets(f, a), d) == box(side, d);
                    if (!on) continue;
                    ++matches;
                    const Eigen::VectorXd expected =
                        (side == 0 ? -1.0 : 1.0) * Eigen::VectorXd::Unit(dim, d);
                    EXPECT_LT((b.normals.row(f).transpose() - expected).norm(), 1e-14);
                }
            EXPECT_EQ(matches, 1) << "facet " << f;
            EXPECT_EQ(b.component[f], 0);
        }
        EXPECT_EQ(b.num_components, 1);
        expect_normals_point_away_from_owner(m, b);

        // The owner and local facet reproduce the facet's nodes from the element.
        for (Index f = 0; f < b.size(); ++f) {
            const Index e = b.owner[f];
            for (Index a = 0; a < b.facets.cols(); ++a) {
                bool found = false;
                for (Index c = 0; c < m.elements.cols(); ++c)
                    found |= m.elements(e, c) == b.facets(f, a);
                EXPECT_TRUE(found);
            }
        }

        // Boundary nodes are exactly the nodes on the box surface.
        const std::vector<Index> nodes = mesh::boundary_nodes(b);
        Index on_surface = 0;
        for (Index v = 0; v < m.num_nodes(); ++v) {
            bool s = false;
            for (int d = 0; d < dim; ++d)
                s = s || m.rest_positions(v, d) == box(0, d) || m.rest_positions(v, d) == box(1, d);
            on_surface += s;
        }
        EXPECT_EQ(static_cast<Index>(nodes.size()), on_surface);
        EXPECT_TRUE(std::is_sorted(nodes.begin(), nodes.end()));
    }
}

// A box with a cubic (square) cavity: two components, 0 the outer box surface and 1 the cavity
// surface; the cavity's normals point into the cavity, its area is that of the removed block
// (1e-12 relative), and the total vector area of each closed component is zero.
TEST_P(BoundaryTest, CavityIsASecondComponent) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi = Eigen::VectorXd::Ones(dim);
    const Eigen::VectorXi cells = Eigen::VectorXi::Constant(dim, 6);
    // The block [1/3, 2/3]^dim (2 cells per axis) is removed.
    const auto in_block = [](const Eigen::VectorXd& c) {
        return (c.array() > 1.0 / 3).all() && (c.array() < 2.0 / 3).all();
    };
    const mesh::Mesh m = test::drop_elements(mesh::make_grid(type, lo, hi, cells), in_block);
    const mesh::Boundary b = mesh::boundary(m);
    ASSERT_EQ(b.num_components, 2);

    const Eigen::VectorXd centre = Eigen::VectorXd::Constant(dim, 0.5);
    std::array<double, 2> area{0, 0};
    std::array<Eigen::VectorXd, 2> vector_area{Eigen::VectorXd::Zero(dim),
                                               Eigen::VectorXd::Zero(dim)};
    for (Index f = 0; f < b.size(); ++f) {
        const Eigen::VectorXd c = facet_centre(m, b, f);
        const bool on_box = ((c.array() == 0.0) || (c.array() == 1.0)).any();
        EXPECT_EQ(b.component[f], on_box ? 0 : 1) << "facet " << f;
        if (!on_box) {
            EXPECT_GT(b.normals.row(f).dot(centre - c), 0.0);
        }
        area[b.component[f]] += b.areas[f];
        vector_area[b.component[f]] += b.areas[f] * b.normals.row(f).transpose();
    }
    const double outer = dim == 2 ? 4.0 : 6.0;
    const double inner = dim == 2 ? 4.0 / 3 : 6.0 / 9;
    EXPECT_NEAR(area[0], outer, 1e-12 * outer);
    EXPECT_NEAR(area[1], inner, 1e-12 * inner);
    EXPECT_LT(vector_area[0].norm(), 1e-12 * outer);
    EXPECT_LT(vector_area[1].norm(), 1e-12 * inner);
    expect_normals_point_away_from_owner(m, b);

    const std::vector<Index> all = mesh::boundary_nodes(b);
    const std::vector<Index> outer_nodes = mesh::boundary_nodes(b, 0);
    const std::vector<Index> cavity_nodes = mesh::boundary_nodes(b, 1);
    EXPECT_EQ(all.size(), outer_nodes.size() + cavity_nodes.size());
    // Cavity surface nodes: (2+1)^2 - 1 = 8 in 2D, 3^3 - 1 = 26 in 3D.
    EXPECT_EQ(cavity_nodes.size(), dim == 2 ? 8u : 26u);
    EXPECT_THROW(mesh::boundary_nodes(b, 2), Error);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, BoundaryTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const ::testing::TestParamInfo<ElementType>& param_info) {
                             return mesh::element_name(param_info.param);
                         });

// Two holes of different sizes: after the outer boundary, the larger hole (12 edges) comes
// before the smaller one (4 edges).
TEST(Boundary, CavitiesAreNumberedBySize) {
    const mesh::Mesh grid = mesh::make_grid(ElementType::Quad4, Eigen::Vector2d(0, 0),
                                            Eigen::Vector2d(10, 5), Eigen::Vector2i(10, 5));
    const auto in_holes = [](const Eigen::VectorXd& c) {
        const bool small = c[0] > 2 && c[0] < 3 && c[1] > 2 && c[1] < 3;
        const bool large = c[0] > 5 && c[0] < 8 && c[1] > 1 && c[1] < 4;
        return small || large;
    };
    const mesh::Mesh m = test::drop_elements(grid, in_holes);
    const mesh::Boundary b = mesh::boundary(m);
    ASSERT_EQ(b.num_components, 3);
    std::array<int, 3> count{0, 0, 0};
    for (Index f = 0; f < b.size(); ++f) ++count[b.component[f]];
    EXPECT_EQ(count[0], 30);  // 2 (10 + 5)
    EXPECT_EQ(count[1], 12);
    EXPECT_EQ(count[2], 4);
}

// Component 0 is chosen by the extreme node, not by size: a mesh of two parts, a single quad
// at x in [-5, -4] and a 10 x 5 grid, numbers the single quad's 4 edges first.
TEST(Boundary, OuterComponentHoldsTheExtremeNode) {
    mesh::Mesh m = mesh::make_grid(ElementType::Quad4, Eigen::Vector2d(0, 0),
                                   Eigen::Vector2d(10, 5), Eigen::Vector2i(10, 5));
    const Index nv = m.num_nodes(), ne = m.num_elements();
    m.rest_positions.conservativeResize(nv + 4, 2);
    m.rest_positions.bottomRows(4) << -5, 0, -4, 0, -4, 1, -5, 1;
    m.elements.conservativeResize(ne + 1, 4);
    m.elements.row(ne) << nv, nv + 1, nv + 2, nv + 3;
    m.material_ids = IndexVector::Zero(ne + 1);
    const mesh::Boundary b = mesh::boundary(m);
    ASSERT_EQ(b.num_components, 2);
    for (Index f = 0; f < b.size(); ++f) EXPECT_EQ(b.component[f], b.owner[f] == ne ? 0 : 1);
}

// Three triangles on one edge: not a manifold mesh, reported instead of silently guessed.
TEST(Boundary, NonManifoldEdgeIsAnError) {
    mesh::Mesh m;
    m.type = ElementType::Tri3;
    m.rest_positions.resize(5, 2);
    m.rest_positions << 0, 0, 1, 0, 0.5, 1, 0.5, -1, 0.5, 2;
    m.elements.resize(3, 3);
    m.elements << 0, 1, 2, 1, 0, 3, 0, 1, 4;
    m.material_ids = IndexVector::Zero(3);
    EXPECT_THROW(mesh::boundary(m), Error);
    m.elements(2, 2) = 7;
    EXPECT_THROW(mesh::boundary(m), Error);  // node out of range
}

// Extraction is linear-time: a 216K-element tet grid (1.3M local facets) takes well under a
// second in Release (measured about 0.1 s); the bound is loose for slow or busy machines.
TEST(Boundary, LargeTetGridIsFast) {
    const mesh::Mesh m = mesh::make_grid(ElementType::Tet4, Eigen::Vector3d::Zero(),
                                         Eigen::Vector3d::Ones(), Eigen::Vector3i(20, 30, 60));
    const auto t0 = std::chrono::steady_clock::now();
    const mesh::Boundary b = mesh::boundary(m);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(b.size(), 4 * (20 * 30 + 30 * 60 + 20 * 60));
    EXPECT_EQ(b.num_components, 1);
    EXPECT_LT(seconds, 3.0);
}

namespace coarsegrain {
namespace {

// element_neighbours: the relation is symmetric, neighbours share a whole facet, and the facets
// without a neighbour are exactly the boundary's.
TEST(ElementNeighbours, SymmetricThroughWholeFacetsAndBoundaryElsewhere) {
    for (const mesh::ElementType type : {mesh::ElementType::Tri3, mesh::ElementType::Quad4,
                                         mesh::ElementType::Tet4, mesh::ElementType::Hex8}) {
        const int dim = mesh::element_dim(type);
        const mesh::Mesh m =
            mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                            Eigen::VectorXi::Constant(dim, 3));
        const IndexMatrix n = mesh::element_neighbours(m);
        ASSERT_EQ(n.rows(), m.num_elements());
        const int facet_nodes = type == mesh::ElementType::Hex8   ? 4
                                : type == mesh::ElementType::Tet4 ? 3
                                                                  : 2;
        Index open = 0;
        for (Index e = 0; e < n.rows(); ++e)
            for (Index f = 0; f < n.cols(); ++f) {
                const Index o = n(e, f);
                if (o < 0) {
                    ++open;
                    continue;
                }
                EXPECT_TRUE((n.row(o).array() == e).any()) << mesh::element_name(type);
                int shared = 0;
                for (Index a = 0; a < m.elements.cols(); ++a)
                    shared += (m.elements.row(o).array() == m.elements(e, a)).any();
                EXPECT_EQ(shared, facet_nodes) << mesh::element_name(type);
            }
        EXPECT_EQ(open, mesh::boundary(m).size()) << mesh::element_name(type);
    }
}

// element_components joins facet neighbours of equal label only: a strip of 5 quads labelled
// 0 0 -1 0 1 has the components {0, 1}, {3} and {4}.
TEST(ElementComponents, FacetNeighboursOfOneLabel) {
    const mesh::Mesh m = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d::Zero(),
                                         Eigen::Vector2d(5, 1), Eigen::Vector2i(5, 1));
    IndexVector labels(5);
    labels << 0, 0, -1, 0, 1;
    Index count = 0;
    const IndexVector c = mesh::element_components(m, labels, count);
    EXPECT_EQ(count, 3);
    IndexVector expected(5);
    expected << 0, 0, -1, 1, 2;
    EXPECT_EQ(c, expected);
    test::expect_error([&] { mesh::element_components(m, IndexVector::Zero(4), count); },
                       "4 labels for 5 elements");
}

}  // namespace
}  // namespace coarsegrain
