// Rotation-strain post-warping (Chen et al. 2019, Sec. 4.3, Eq. 13): the Cayley map is the
// rotation by 2 atan(θ/2), RS keeps symmetric gradients and turns skew ones into Cay - I, the
// warp turns a linearized rotation of any angle into the exact rigid rotation by that angle on
// every element type, leaves small gradients unchanged to first order, honours the Dirichlet
// values and is the minimizer of its objective for any pattern of prescribed components.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

/// The generator of rotations about the unit vector n: [n]× in 3D (J x = n × x), the quarter
/// turn [[0, -1], [1, 0]] in 2D.
Matrix warp_generator(int dim, const Eigen::Vector3d& n) {
    if (dim == 2) return (Matrix(2, 2) << 0, -1, 1, 0).finished();
    const Eigen::Vector3d a = n.normalized();
    return (Matrix(3, 3) << 0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0).finished();
}

/// The rotation by `angle` about the unit vector n (Eigen's angle-axis in 3D, cos/sin in 2D).
Matrix warp_rotation(int dim, double angle, const Eigen::Vector3d& n) {
    if (dim == 2)
        return (Matrix(2, 2) << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle))
            .finished();
    return Eigen::AngleAxisd(angle, n.normalized()).toRotationMatrix();
}

/// RS(G) by its definition, Cay[W](I + E) - I with Cay(W) = (I - W/2)^{-1}(I + W/2) by an LU
/// solve (the library uses a closed form).
Matrix warp_rs_definition(const Matrix& G) {
    const Index n = G.rows();
    const Matrix I = Matrix::Identity(n, n);
    const Matrix W = 0.5 * (G - G.transpose()), E = 0.5 * (G + G.transpose());
    const Matrix cay = (I - 0.5 * W).partialPivLu().solve(I + 0.5 * W);
    return cay * (I + E) - I;
}

/// A grid over [0, 2] x [0, 1.5] (x [0, 1]) with 6 x 4 (x 3) cells, optionally with its
/// interior nodes moved by up to 25% of the spacing (Q1) or 12% (P1).
mesh::Mesh warp_grid(ElementType type, bool distorted) {
    mesh::Mesh m = mesh::element_dim(type) == 2
                       ? mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1.5),
                                         Eigen::Vector2i(6, 4))
                       : mesh::make_grid(type, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 1.5, 1),
                                         Eigen::Vector3i(6, 4, 3));
    if (distorted) test::distort_interior(m, mesh::is_simplex(type) ? 0.12 : 0.25, 5);
    return m;
}

/// The interleaved field u(x) = A (x - x0) at every node.
Vector warp_affine(const mesh::Mesh& m, const Matrix& A, const Eigen::VectorXd& x0) {
    return test::linear_field(m.rest_positions, A, -A * x0);
}

/// The nodes with x_axis = value.
std::vector<Index> warp_plane(const mesh::Mesh& m, int axis, double value) {
    std::vector<Index> nodes;
    for (Index v = 0; v < m.num_nodes(); ++v)
        if (std::abs(m.rest_positions(v, axis) - value) < 1e-12) nodes.push_back(v);
    return nodes;
}

// The Cayley map of θ times a rotation generator is the rotation by φ = 2 atan(θ/2) about the
// same axis: orthogonal with determinant 1, equal to Eigen's angle-axis rotation and to the
// definition (I - A/2)^{-1}(I + A/2) by an LU solve, all to 1e-14 (entries of size 1, a few
// roundings in the closed form), for angles up to θ = 10 (φ = 157°).
TEST(RsWarpCayley, IsTheRotationByTwiceTheArctangentOfHalfTheAngle) {
    for (const int dim : {2, 3})
        for (const Eigen::Vector3d& n : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, -2, 0.5)})
            for (const double theta : {0.0, 0.1, 1.0, 1.5, 3.0, 10.0}) {
                const Matrix J = warp_generator(dim, n);
                const Matrix R = fem::cayley(theta * J);
                const Matrix I = Matrix::Identity(dim, dim);
                EXPECT_LT((R.transpose() * R - I).cwiseAbs().maxCoeff(), 1e-14);
                EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
                const double phi = 2.0 * std::atan(0.5 * theta);
                EXPECT_LT((R - warp_rotation(dim, phi, n)).cwiseAbs().maxCoeff(), 1e-14)
                    << "dim " << dim << ", theta " << theta;
                const Matrix definition =
                    (I - 0.5 * theta * J).partialPivLu().solve(I + 0.5 * theta * J);
                EXPECT_LT((R - definition).cwiseAbs().maxCoeff(), 1e-14);
            }
    test::expect_error([] { fem::cayley(Matrix::Identity(3, 3)); }, "not skew");
    test::expect_error([] { fem::cayley(Matrix::Zero(4, 4)); }, "expected 2x2 or 3x3");
}

// RS(0) = 0 exactly; a symmetric gradient is returned unchanged (the closed form adds
// Cay - I = 0 exactly: 1e-15 relative allows for an implementation that forms I + E); a skew
// gradient θJ gives Cay(θJ) - I, the rotation by 2 atan(θ/2) minus I (1e-14); a general
// gradient matches the definition Cay[W](I + E) - I by an LU solve (1e-14 times |G|²).
TEST(RsWarpTransform, KeepsStrainAndTurnsSkewPartsIntoCayleyRotations) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (const int dim : {2, 3}) {
        EXPECT_EQ(fem::rs_transform(Matrix::Zero(dim, dim)), Matrix::Zero(dim, dim));
        Matrix G(dim, dim);
        for (Index i = 0; i < G.size(); ++i) G.data()[i] = 0.8 * U(rng);
        const Matrix sym = G + G.transpose();
        EXPECT_LE((fem::rs_transform(sym) - sym).norm(), 1e-15 * sym.norm());
        const Eigen::Vector3d n(0.3, 1, -0.4);
        for (const double theta : {0.2, 1.5, 4.0}) {
            const Matrix expected =
                warp_rotation(dim, 2 * std::atan(0.5 * theta), n) - Matrix::Identity(dim, dim);
            EXPECT_LT((fem::rs_transform(theta * warp_generator(dim, n)) - expected)
                          .cwiseAbs()
                          .maxCoeff(),
                      1e-14);
        }
        EXPECT_LT((fem::rs_transform(G) - warp_rs_definition(G)).norm(),
                  1e-14 * (1 + G.squaredNorm()));
    }
    test::expect_error([] { fem::rs_transform(Matrix::Zero(2, 3)); }, "expected 2x2 or 3x3");
}

struct RsWarpCase {
    ElementType type;
    bool distorted;
};

class RsWarpRotation : public ::testing::TestWithParam<RsWarpCase> {};

// The linearized rigid rotation by θ about an axis through the node x0, u = θ J (x - x0) (what
// linear elasticity gives for an infinitesimal rotation scaled up to θ), has the constant
// gradient θJ, whose RS transform is R_φ - I with φ = 2 atan(θ/2). The field (R_φ - I)(x - x0)
// is linear, so P1 and Q1 (also on distorted quads and hexes, whose isoparametric space holds
// the linear fields) represent it, its gradient equals the RS target at every quadrature point
// and it vanishes at x0: with x0 the one prescribed node (zero, consistent with the rotation,
// and enough to make each component's Laplacian definite) it is the exact minimizer. The warp
// reproduces the rigid rotation by φ to 1e-12 relative (direct solve of a few hundred unknowns
// whose Laplacian has a condition number of about 1e3; measured below 2e-15) and so keeps
// every distance to x0.
// That is the accuracy of the Cayley map: the rotation comes out by φ = θ - θ³/12 + O(θ⁵)
// instead of θ, 73.74° for θ = 1.5 (85.94°), 53.13° for θ = 1 (57.30°), 28.07° for θ = 0.5.
TEST_P(RsWarpRotation, LinearizedRotationBecomesTheRigidRotationByTheCayleyAngle) {
    const auto [type, distorted] = GetParam();
    const mesh::Mesh m = warp_grid(type, distorted);
    const int dim = m.dim();
    const Index centre = 3 + 7 * (2 + (dim == 3 ? 5 : 0));  // grid node (3, 2[, 1])
    const Eigen::VectorXd x0 = m.rest_positions.row(centre).transpose();
    fem::Dirichlet bc;
    bc.fix_nodes({centre}, Eigen::VectorXd::Zero(dim));
    const fem::RsWarp warp(m, bc);
    EXPECT_EQ(warp.num_factorizations(), 1);
    const Eigen::Vector3d axis(1, 2, 2);
    for (const double theta : {0.5, 1.0, 1.5}) {
        const Matrix J = warp_generator(dim, axis);
        const Vector u = warp_affine(m, theta * J, x0);
        const double phi = 2 * std::atan(0.5 * theta);
        const Matrix R = warp_rotation(dim, phi, axis);
        const Vector exact = warp_affine(m, R - Matrix::Identity(dim, dim), x0);
        const Vector w = warp(u);
        EXPECT_LT((w - exact).lpNorm<Eigen::Infinity>(), 1e-12 * exact.lpNorm<Eigen::Infinity>())
            << "theta " << theta;
        for (Index v = 0; v < m.num_nodes(); ++v) {
            const Eigen::VectorXd r = m.rest_positions.row(v).transpose() - x0;
            EXPECT_NEAR((r + w.segment(dim * v, dim)).norm(), r.norm(), 1e-12);
        }
    }
}

std::string warp_case_name(const ::testing::TestParamInfo<RsWarpCase>& param_info) {
    return mesh::element_name(param_info.param.type) +
           (param_info.param.distorted ? "_distorted" : "_grid");
}

INSTANTIATE_TEST_SUITE_P(
    AllTypes, RsWarpRotation,
    ::testing::Values(RsWarpCase{ElementType::Tri3, false}, RsWarpCase{ElementType::Tri3, true},
                      RsWarpCase{ElementType::Quad4, false}, RsWarpCase{ElementType::Quad4, true},
                      RsWarpCase{ElementType::Tet4, false}, RsWarpCase{ElementType::Tet4, true},
                      RsWarpCase{ElementType::Hex8, false}, RsWarpCase{ElementType::Hex8, true}),
    warp_case_name);

// A beam clamped along a whole edge on the rotation axis (every node of the edge x = y = 0
// prescribed to 0) rotates rigidly too: the exact answer vanishes on the axis, so the clamp is
// consistent; 1e-12 relative as above (measured below 1e-14), θ = 1.5 about z.
TEST(RsWarpRotationClamped, EdgeOnTheAxis) {
    for (const ElementType type : {ElementType::Tet4, ElementType::Hex8}) {
        const mesh::Mesh m = warp_grid(type, true);
        std::vector<Index> edge;
        for (const Index v : warp_plane(m, 0, 0.0))
            if (std::abs(m.rest_positions(v, 1)) < 1e-12) edge.push_back(v);
        ASSERT_EQ(edge.size(), 4u);
        fem::Dirichlet bc;
        bc.fix_nodes(edge, Eigen::Vector3d::Zero());
        const fem::RsWarp warp(m, bc);
        const Eigen::Vector3d axis(0, 0, 1), x0(0, 0, 0);
        const double theta = 1.5;
        const Vector u = warp_affine(m, theta * warp_generator(3, axis), x0);
        const Matrix R = warp_rotation(3, 2 * std::atan(0.5 * theta), axis);
        const Vector exact = warp_affine(m, R - Matrix::Identity(3, 3), x0);
        EXPECT_LT((warp(u) - exact).lpNorm<Eigen::Infinity>(),
                  1e-12 * exact.lpNorm<Eigen::Infinity>());
    }
}

class RsWarpSmall : public ::testing::TestWithParam<ElementType> {};

// RS(εA) = εA + O(ε²), so a linear field u = ε A (x - x0) with a general gradient A (neither
// symmetric nor skew) is left unchanged to first order: with the face x = 0 clamped to u's own
// (nonzero) values, |warp(u) - u| = O(ε²), i.e. O(ε) relative to |u|. Measured at ε = 1e-2 and
// 1e-3, the difference shrinks by 100: the ratio is 1/100 (1 + O(ε)), asserted within 1%
// (measured within 1e-5 on every type). At ε = 1e-2 the relative difference is below ε
// (measured 0.4 ε to 0.75 ε) and above 1e-4 ε (the warp is not the identity).
TEST_P(RsWarpSmall, SmallGradientIsUnchangedToFirstOrder) {
    const mesh::Mesh m = warp_grid(GetParam(), true);
    const int dim = m.dim();
    Matrix A(dim, dim);
    if (dim == 2)
        A << 0.7, -1.1, 0.4, 0.3;
    else
        A << 0.7, -1.1, 0.2, 0.4, 0.3, -0.8, 0.5, 0.6, -0.2;
    const Eigen::VectorXd x0 = Eigen::VectorXd::LinSpaced(dim, 0.3, 0.5);
    const std::vector<Index> face = warp_plane(m, 0, 0.0);
    const auto difference = [&](double eps, double& size) {
        const Vector u = warp_affine(m, eps * A, x0);
        fem::Dirichlet bc;
        for (const Index v : face) bc.fix_nodes({v}, u.segment(dim * v, dim));
        const fem::RsWarp warp(m, bc);
        size = u.norm();
        return (warp(u) - u).norm();
    };
    double size = 0, unused = 0;
    const double coarse = difference(1e-2, size), fine = difference(1e-3, unused);
    EXPECT_LT(coarse, 1e-2 * size);
    EXPECT_GT(coarse, 1e-6 * size);
    EXPECT_NEAR(fine / coarse, 0.01, 1e-4) << "differences " << coarse << ", " << fine;
}

INSTANTIATE_TEST_SUITE_P(AllTypes, RsWarpSmall,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const ::testing::TestParamInfo<ElementType>& param_info) {
                             return mesh::element_name(param_info.param);
                         });

/// The first variation of the warp's objective on a P1 mesh at v in the direction d,
/// Σ_T |T| (∇v - RS(∇u)) : ∇d, with gradients from each simplex's edge vectors and RS by its
/// definition; `scale` gets the Cauchy-Schwarz bound |RS(∇u)|_L2 |∇d|_L2 of a term of it.
double warp_first_variation(const mesh::Mesh& m, const Vector& u, const Vector& v, const Vector& d,
                            double& scale) {
    const int dim = m.dim();
    double sum = 0, rs2 = 0, d2 = 0;
    for (Index e = 0; e < m.num_elements(); ++e) {
        Matrix D(dim, dim), dU(dim, dim), dV(dim, dim), dD(dim, dim);
        const auto node = [&](int a) { return m.elements(e, a); };
        for (int a = 1; a <= dim; ++a) {
            D.col(a - 1) =
                (m.rest_positions.row(node(a)) - m.rest_positions.row(node(0))).transpose();
            dU.col(a - 1) = u.segment(dim * node(a), dim) - u.segment(dim * node(0), dim);
            dV.col(a - 1) = v.segment(dim * node(a), dim) - v.segment(dim * node(0), dim);
            dD.col(a - 1) = d.segment(dim * node(a), dim) - d.segment(dim * node(0), dim);
        }
        const Matrix Dinv = D.inverse();
        const double measure = std::abs(D.determinant()) / (dim == 2 ? 2.0 : 6.0);
        const Matrix rs = warp_rs_definition(dU * Dinv);
        const Matrix grad_d = dD * Dinv;
        sum += measure * (dV * Dinv - rs).cwiseProduct(grad_d).sum();
        rs2 += measure * rs.squaredNorm();
        d2 += measure * grad_d.squaredNorm();
    }
    scale = std::sqrt(rs2 * d2);
    return sum;
}

/// A smooth field with gradients of size 1 (large rotations and strains).
Vector warp_bent_field(const mesh::Mesh& m) {
    const int dim = m.dim();
    Vector u(m.num_dofs());
    for (Index v = 0; v < m.num_nodes(); ++v) {
        const auto x = m.rest_positions.row(v);
        const double s = x.sum();
        for (int i = 0; i < dim; ++i)
            u[dim * v + i] = 0.6 * std::sin(1.3 * x[0] + 0.5 * i * s) + 0.3 * i * x[dim - 1] * s;
    }
    return u;
}

// Whatever the pattern of prescribed components (whole nodes on two faces with nonzero values;
// one component per symmetry plane, three factorizations in 3D; whole nodes plus one more
// component elsewhere, two), the warp takes the prescribed values exactly and is the minimizer
// of ∫ |∇v - RS(∇u)|²: the objective's first variation in random directions that keep the
// prescribed DOFs vanishes to 1e-13 of its Cauchy-Schwarz scale (evaluated independently,
// gradients from edge vectors and RS by its definition; measured below 4e-16: round-off of sums
// of a few thousand terms and of the back-substitution), while that of the unwarped u does not
// (the largest of three directions above 1e-2 of the scale; measured 0.04 to 0.11).
TEST(RsWarpDirichlet, PrescribedValuesAndMinimizerForAnyPattern) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (const ElementType type : {ElementType::Tri3, ElementType::Tet4}) {
        const mesh::Mesh m = warp_grid(type, true);
        const int dim = m.dim();
        const Vector u = warp_bent_field(m);
        struct Pattern {
            fem::Dirichlet bc;
            int factorizations;
        };
        std::vector<Pattern> patterns(3);
        patterns[0].bc.fix_nodes(warp_plane(m, 0, 0.0), Eigen::VectorXd::LinSpaced(dim, 0.1, -0.2));
        patterns[0].bc.fix_nodes(warp_plane(m, 0, 2.0), Eigen::VectorXd::LinSpaced(dim, 0.5, 0.3));
        patterns[0].factorizations = 1;
        for (int i = 0; i < dim; ++i)
            patterns[1].bc.fix_component(warp_plane(m, i, 0.0), dim, i, 0.05 * (i + 1));
        patterns[1].factorizations = dim;
        patterns[2].bc.fix_nodes(warp_plane(m, 0, 0.0), Eigen::VectorXd::Zero(dim));
        patterns[2].bc.fix_component(warp_plane(m, 1, 1.5), dim, dim - 1, -0.25);
        patterns[2].factorizations = 2;
        for (const Pattern& p : patterns) {
            const fem::RsWarp warp(m, p.bc);
            EXPECT_EQ(warp.num_factorizations(), p.factorizations);
            const Vector w = warp(u);
            for (std::size_t k = 0; k < p.bc.dofs.size(); ++k)
                EXPECT_EQ(w[p.bc.dofs[k]], p.bc.values[static_cast<Index>(k)]);
            double largest_unwarped = 0;
            for (int trial = 0; trial < 3; ++trial) {
                // A smooth direction, so that the Cauchy-Schwarz scale is not far from sharp.
                Eigen::VectorXd a(dim);
                for (int k = 0; k < dim; ++k) a[k] = 2 * U(rng);
                const double phase = 3 * U(rng);
                Vector d(m.num_dofs());
                for (Index v = 0; v < m.num_nodes(); ++v)
                    for (int i = 0; i < dim; ++i)
                        d[dim * v + i] = std::sin(m.rest_positions.row(v).dot(a) + phase + i);
                for (const Index i : p.bc.dofs) d[i] = 0;
                double scale = 0;
                const double warped = warp_first_variation(m, u, w, d, scale);
                EXPECT_LT(std::abs(warped), 1e-13 * scale);
                largest_unwarped = std::max(
                    largest_unwarped, std::abs(warp_first_variation(m, u, u, d, scale)) / scale);
            }
            EXPECT_GT(largest_unwarped, 1e-2);
        }
    }
}

// Bad input: a u of the wrong size or not finite; no prescribed DOF at all; one component
// prescribed nowhere (a clamp of x alone); a second, disjoint grid that nothing holds. Each
// error names the warp, and the singular ones the part or component.
TEST(RsWarpDirichlet, RejectsSizeMismatchAndFloatingParts) {
    const mesh::Mesh m = warp_grid(ElementType::Quad4, false);
    fem::Dirichlet clamp;
    clamp.fix_nodes(warp_plane(m, 0, 0.0), Eigen::Vector2d::Zero());
    const fem::RsWarp warp(m, clamp);
    EXPECT_EQ(warp.num_dofs(), m.num_dofs());
    test::expect_error([&] { warp(Vector::Zero(m.num_dofs() + 2)); }, "RsWarp: u has");
    Vector nan = Vector::Zero(m.num_dofs());
    nan[3] = std::nan("");
    test::expect_error([&] { warp(nan); }, "RsWarp: u has a non-finite entry");
    test::expect_error([&] { fem::RsWarp(m, fem::Dirichlet{}); }, "RsWarp: no node");
    fem::Dirichlet only_x;
    only_x.fix_component(warp_plane(m, 0, 0.0), 2, 0, 0.0);
    test::expect_error([&] { fem::RsWarp(m, only_x); }, "has its y component prescribed");
    fem::Dirichlet out_of_range;
    out_of_range.fix_nodes({m.num_nodes()}, Eigen::Vector2d::Zero());
    test::expect_error([&] { fem::RsWarp(m, out_of_range); }, "RsWarp: Dirichlet DOF");

    // Two copies of the grid side by side, sharing no node; only the first is clamped.
    mesh::Mesh two = m;
    const Index nv = m.num_nodes(), ne = m.num_elements();
    two.rest_positions.resize(2 * nv, 2);
    two.rest_positions << m.rest_positions, m.rest_positions.rowwise() + Eigen::RowVector2d(3, 0);
    two.elements.resize(2 * ne, 4);
    two.elements << m.elements, m.elements.array() + nv;
    two.material_ids = IndexVector::Zero(2 * ne);
    two.grid.reset();
    test::expect_error([&] { fem::RsWarp(two, clamp); },
                       fmt::format("RsWarp: no node of the connected part of the mesh containing "
                                   "node {} ({} nodes)",
                                   nv, nv));
}

}  // namespace
