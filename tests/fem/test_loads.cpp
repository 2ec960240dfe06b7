#include <gtest/gtest.h>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

mesh::Mesh box_grid(ElementType type) {
    const int dim = mesh::element_dim(type);
    if (dim == 2)
        return mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1),
                               Eigen::Vector2i(6, 4));
    return mesh::make_grid(type, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 1, 0.5),
                           Eigen::Vector3i(4, 3, 2));
}

class LoadTest : public ::testing::TestWithParam<ElementType> {};

// Gravity on a distorted mesh with two densities: the consistent nodal forces equal the
// consistent mass matrix applied to the uniform field g (sum_b M_ab = rho ∫ N_a, an
// independent path through assembly), and they sum to the total weight. 1e-13 relative.
TEST_P(LoadTest, GravityIsMassTimesAcceleration) {
    mesh::Mesh m = box_grid(GetParam());
    test::distort_interior(m, 0.2);
    const int dim = m.dim();
    material::layers(m, 0, 0.0, 0.5, {1, 2});
    const material::ElementMaterials mats = material::assign(
        m,
        {{1, material::isotropic(dim, 1, 0.3, 3.0)}, {2, material::isotropic(dim, 1, 0.3, 0.5)}});
    Eigen::VectorXd g = Eigen::VectorXd::LinSpaced(dim, -9.81, 2.0);
    const Vector f = fem::gravity_load(m, mats, g);
    Vector g_field(m.num_dofs());
    for (Index v = 0; v < m.num_nodes(); ++v) g_field.segment(dim * v, dim) = g;
    const Vector Mg = fem::mass_matrix(m, mats, fem::MassType::Consistent) * g_field;
    EXPECT_LT((f - Mg).norm(), 1e-13 * Mg.norm());
    double mass = 0;
    for (Index e = 0; e < m.num_elements(); ++e)
        mass += mats.of(e).density * mesh::element_measure(m, e);
    for (int d = 0; d < dim; ++d) {
        double total = 0;
        for (Index v = 0; v < m.num_nodes(); ++v) total += f[dim * v + d];
        EXPECT_NEAR(total, mass * g[d], 1e-13 * mass * g.norm());
    }
    EXPECT_THROW(fem::gravity_load(m, mats, Eigen::VectorXd::Zero(dim + 1)), Error);
}

// Traction on the x = max face (mesh::boundary, facets_in_box): the nodal forces sum to t times the
// face area, and on a regular grid each facet gives t * area / (nodes per facet) to each of its
// nodes: corner nodes of a 2D edge get t h / 2, interior nodes t h (1e-14 relative).
TEST_P(LoadTest, TractionSumsToTractionTimesArea) {
    const mesh::Mesh m = box_grid(GetParam());
    const int dim = m.dim();
    const mesh::Boundary b = mesh::boundary(m);
    const std::vector<Index> face = test::plane_facets(m, b, 0, 2.0);
    const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(dim, 1.5, -0.5);
    const Vector f = fem::traction_load(m, b, face, t);
    const double area = dim == 2 ? 1.0 : 0.5;
    for (int d = 0; d < dim; ++d) {
        double total = 0;
        for (Index v = 0; v < m.num_nodes(); ++v) total += f[dim * v + d];
        EXPECT_NEAR(total, t[d] * area, 1e-14 * t.norm());
    }
    // Nodal share: the number of facets a node is in times the facet share.
    const double facet_area = area / static_cast<double>(face.size());
    std::vector<int> count(static_cast<std::size_t>(m.num_nodes()), 0);
    for (const Index k : face)
        for (Index a = 0; a < b.facets.cols(); ++a) ++count[b.facets(k, a)];
    for (Index v = 0; v < m.num_nodes(); ++v)
        EXPECT_NEAR(f[dim * v], t[0] * facet_area / b.facets.cols() * count[v], 1e-14);
    // Only the facets listed are loaded.
    const Vector none = fem::traction_load(m, b, {}, t);
    EXPECT_EQ(none.norm(), 0.0);
    EXPECT_THROW(fem::traction_load(m, b, {b.size()}, t), Error);
}

// A single planar trapezoidal quad facet (not a parallelogram): the weights are ∫ N_a over the
// bilinear facet, which sum to the trapezoid area (2x2 Gauss is exact: the area element is
// linear in each reference coordinate). The side with the longer edge gets more: for a
// trapezoid with parallel sides 2 (y = 0) and 1 (y = 1), the nodes of the long side get
// (2 * 2 + 1) / 12 = 5/12 each and those of the short side (2 + 2 * 1) / 12 = 4/12.
TEST(TractionLoad, TrapezoidalQuadFacet) {
    mesh::Mesh m;
    m.type = ElementType::Hex8;
    m.rest_positions.resize(4, 3);
    m.rest_positions << 0, 0, 0, 2, 0, 0, 1.5, 1, 0, 0.5, 1, 0;
    mesh::Boundary b;
    b.facets.resize(1, 4);
    b.facets << 0, 1, 2, 3;
    const Vector f = fem::traction_load(m, b, {0}, Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(f[2] + f[5] + f[8] + f[11], 1.5, 1e-14);
    EXPECT_NEAR(f[2], 5.0 / 12.0, 1e-14);
    EXPECT_NEAR(f[5], 5.0 / 12.0, 1e-14);
    EXPECT_NEAR(f[8], 4.0 / 12.0, 1e-14);
    EXPECT_NEAR(f[11], 4.0 / 12.0, 1e-14);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, LoadTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

}  // namespace
