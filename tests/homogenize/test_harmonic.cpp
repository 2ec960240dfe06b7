// Global harmonic displacements (Kharevych et al. 2009, Eq. 6), mollifiers (Sec. 3.5), sampling
// at coarse nodes (Sec. 3.2) and the coarse normals of Sec. 4.2.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/homogenize/harmonic.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "fem/fem_test_util.hpp"
#include "mesh/drop_elements.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using homogenize::mandel_pair;

mesh::Mesh distorted_grid(mesh::ElementType type, const Eigen::VectorXd& lo,
                          const Eigen::VectorXd& hi, const Eigen::VectorXi& cells) {
    mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    test::distort_interior(m, 0.25, 7);
    return m;
}

/// The uniform stress E^{ab} as a dim x dim matrix.
Matrix unit_stress(int dim, int J) {
    const auto [a, b] = mandel_pair(dim, J);
    Matrix E = Matrix::Zero(dim, dim);
    E(a, b) += 0.5;
    E(b, a) += 0.5;
    return E;
}

/// Nodal forces of the tractions E^{ab} n on the outer boundary, assembled facet by facet with
/// fem::traction_load (independent of the harmonic module's own load assembly).
Matrix outer_traction_loads(const mesh::Mesh& m, const mesh::Boundary& b) {
    const int dim = m.dim(), n = mandel_size(dim);
    Matrix F = Matrix::Zero(m.num_dofs(), n);
    for (Index f = 0; f < b.size(); ++f) {
        if (b.component[f] != 0) continue;
        for (int J = 0; J < n; ++J)
            F.col(J) +=
                fem::traction_load(m, b, {f}, unit_stress(dim, J) * b.normals.row(f).transpose());
    }
    return F;
}

class HarmonicHomogeneous : public ::testing::TestWithParam<mesh::ElementType> {};

// On a homogeneous body the uniform stress E^{ab} is the exact solution of Eq. 6, so h_ab is
// linear with strain C^{-1} E^{ab}, which P1 reproduces exactly (NOTES.md): every fine mollifier
// is C^{-1} (Mandel) to round-off, on a distorted mesh and for a generic anisotropic C.
TEST_P(HarmonicHomogeneous, LinearWithStrainCInverseE) {
    const mesh::ElementType type = GetParam();
    const int dim = mesh::element_dim(type), n = mandel_size(dim);
    const mesh::Mesh m = dim == 3
                             ? distorted_grid(type, Eigen::Vector3d(0, 0, 0),
                                              Eigen::Vector3d(2, 1, 1.5), Eigen::Vector3i(5, 3, 4))
                             : distorted_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1),
                                              Eigen::Vector2i(8, 5));
    const Matrix C = test::random_spd_tensor(n, 3, 4.0) * 1e3;
    const auto mats = material::uniform(m, material::anisotropic(dim, C, 1.0));
    const mesh::Boundary b = mesh::boundary(m);
    const Matrix h =
        homogenize::harmonic_displacements(m, b, fem::stiffness_matrix(m, mats), b.normals);
    const Matrix Cinv = C.inverse();
    const std::vector<Mandel6> G = homogenize::mollifiers(m, h);
    double worst = 0;
    for (const Mandel6& Gp : G) worst = std::max(worst, (Gp.topLeftCorner(n, n) - Cinv).norm());
    // 1e-10: a direct solve of a well-conditioned system of < 1000 DOFs, then P1 gradients.
    EXPECT_LT(worst, 1e-10 * Cinv.norm());

    // Zeroth and first moments vanish (the rigid motions are removed).
    Vector w = Vector::Zero(m.num_nodes());
    for (Index e = 0; e < m.num_elements(); ++e)
        for (Index a = 0; a < m.elements.cols(); ++a)
            w[m.elements(e, a)] +=
                mesh::element_measure(m, e) / static_cast<double>(m.elements.cols());
    const Eigen::VectorXd centre = m.rest_positions.transpose() * w / w.sum();
    const Matrix R = test::rigid_modes(m.rest_positions.rowwise() - centre.transpose());
    Matrix WR = R;
    for (Index v = 0; v < m.num_nodes(); ++v) WR.middleRows(dim * v, dim) *= w[v];
    const Matrix moments = WR.transpose() * h;
    // Round-off relative to |W R| |h|.
    EXPECT_LT(moments.norm(), 1e-12 * WR.norm() * h.norm());
}

INSTANTIATE_TEST_SUITE_P(Harmonic, HarmonicHomogeneous,
                         ::testing::Values(mesh::ElementType::Tet4, mesh::ElementType::Tri3),
                         [](const auto& p) { return mesh::element_name(p.param); });

// Heterogeneous body with a cavity: K h_ab equals the nodal forces of the traction E^{ab} n on
// the outer boundary (assembled independently), and nothing on the cavity: the cavity is
// traction-free (Sec. 4.2). With the exact normals the load is self-equilibrated, so the pinned
// solve adds no reaction and the identity holds to round-off at every DOF.
TEST(Harmonic, EquilibriumWithOuterTractionsAndFreeCavity) {
    mesh::Mesh m =
        test::drop_elements(mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                            Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(6, 6, 6)),
                            [](const Eigen::VectorXd& c) {
                                return (c.array() > 1.0 / 3).all() && (c.array() < 2.0 / 3).all();
                            });
    material::layers(m, 2, 0.0, 1.0 / 6, {1, 2});
    const auto mats = material::assign(m, {{1, material::isotropic(3, 100.0, 0.3, 1.0)},
                                           {2, material::isotropic(3, 1.0, 0.45, 1.0)}});
    const mesh::Boundary b = mesh::boundary(m);
    ASSERT_EQ(b.num_components, 2);  // outer boundary and the cavity
    const SparseMatrix K = fem::stiffness_matrix(m, mats);
    const Matrix h = homogenize::harmonic_displacements(m, b, K, b.normals);
    const Matrix F = outer_traction_loads(m, b);
    // 1e-9: residual of a direct solve with contrast 100 (condition number ~1e5), relative.
    EXPECT_LT((K * h - F).norm(), 1e-9 * F.norm());
}

// Mixed variant (Sec. 3.8): h vanishes on the fixed DOFs and balances the tractions elsewhere.
TEST(Harmonic, MixedVanishesOnFixedDofsAndBalancesTheRest) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d(0, 0),
                                   Eigen::Vector2d(3, 1), Eigen::Vector2i(12, 4));
    material::layers(m, 0, 0.0, 0.5, {1, 2});
    const auto mats = material::assign(m, {{1, material::isotropic(2, 50.0, 0.3, 1.0)},
                                           {2, material::isotropic(2, 1.0, 0.3, 1.0)}});
    const mesh::Boundary b = mesh::boundary(m);
    std::vector<Index> fixed;
    for (Index v : mesh::nodes_in_box(m, Eigen::Vector2d(-1, -1), Eigen::Vector2d(1e-9, 2)))
        for (int d = 0; d < 2; ++d) fixed.push_back(2 * v + d);
    const SparseMatrix K = fem::stiffness_matrix(m, mats);
    const Matrix h = homogenize::harmonic_displacements(m, b, K, b.normals, fixed);
    const Matrix F = outer_traction_loads(m, b);
    Matrix r = K * h - F;
    for (Index d : fixed) {
        EXPECT_EQ(h.row(d).norm(), 0.0);
        r.row(d).setZero();  // reactions of the fixed DOFs
    }
    EXPECT_LT(r.norm(), 1e-10 * F.norm());  // direct solve, ~300 DOFs, contrast 50
    EXPECT_GT(h.norm(), 0.0);
}

// The normals of Sec. 4.2 on a coarse mesh of the same box are the fine normals themselves: the
// nearest coarse facet of every fine facet lies in the same face, also at the box's edges.
TEST(Harmonic, CoarseNormalsOfTheSameBoxAreTheFineNormals) {
    const mesh::Mesh fine = mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                            Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(8, 4, 4));
    const mesh::Mesh coarse = distorted_grid(mesh::ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                             Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(3, 2, 2));
    const mesh::Boundary fb = mesh::boundary(fine);
    const Matrix N = homogenize::coarse_boundary_normals(fine, fb, coarse);
    EXPECT_LT((N - fb.normals).cwiseAbs().maxCoeff(), 1e-14);  // unit normals of a box: exact
}

// A coarse square rotated by 5 degrees around a fine square: every fine edge takes the normal of
// the coarse side it faces, rotated by 5 degrees.
TEST(Harmonic, CoarseNormalsOfARotatedCageAreTheCageNormals) {
    const mesh::Mesh fine = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d(-1, -1),
                                            Eigen::Vector2d(1, 1), Eigen::Vector2i(8, 8));
    mesh::Mesh coarse = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d(-1.3, -1.3),
                                        Eigen::Vector2d(1.3, 1.3), Eigen::Vector2i(2, 2));
    const double t = 5.0 * M_PI / 180.0;
    Eigen::Matrix2d Q;
    Q << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
    coarse.rest_positions = coarse.rest_positions * Q.transpose();
    const mesh::Boundary fb = mesh::boundary(fine);
    const Matrix N = homogenize::coarse_boundary_normals(fine, fb, coarse);
    for (Index f = 0; f < fb.size(); ++f) {
        const Eigen::Vector2d expected = Q * Eigen::Vector2d(fb.normals.row(f).transpose());
        EXPECT_LT((N.row(f).transpose() - expected).norm(), 1e-14) << "fine facet " << f;
    }
}

// Sampling (Sec. 3.2) reproduces affine fields exactly, by interpolation inside the fine mesh and
// by barycentric extrapolation outside; the distance to a box-shaped mesh is known exactly.
TEST(Harmonic, SamplingReproducesAffineFieldsInsideAndOutside) {
    for (const mesh::ElementType type : {mesh::ElementType::Tet4, mesh::ElementType::Tri3}) {
        const int dim = mesh::element_dim(type), n = mandel_size(dim);
        const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi = Eigen::VectorXd::Ones(dim);
        const mesh::Mesh m = distorted_grid(type, lo, hi, Eigen::VectorXi::Constant(dim, 4));
        std::mt19937 rng(5);
        std::uniform_real_distribution<double> U(-1.0, 1.0);
        Matrix h(m.num_dofs(), n);
        std::vector<Matrix> A(n);
        std::vector<Eigen::VectorXd> c(n);
        for (int J = 0; J < n; ++J) {
            A[J] = Matrix::NullaryExpr(dim, dim, [&] { return U(rng); });
            c[J] = Eigen::VectorXd::NullaryExpr(dim, [&] { return U(rng); });
            h.col(J) = test::linear_field(m.rest_positions, A[J], c[J]);
        }
        Matrix P(40, dim);
        for (Index i = 0; i < P.rows(); ++i)
            for (int d = 0; d < dim; ++d) P(i, d) = 0.5 + 0.7 * U(rng);  // in [-0.2, 1.2]
        const mesh::PointLocator locator(m);
        Vector dist;
        const Matrix H = homogenize::sample_harmonic(m, locator, h, P, &dist);
        for (Index i = 0; i < P.rows(); ++i) {
            const Eigen::VectorXd p = P.row(i).transpose();
            for (int J = 0; J < n; ++J)
                EXPECT_LT((H.block(dim * i, J, dim, 1) - (A[J] * p + c[J])).norm(), 1e-12);
            const double expected = (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
            EXPECT_NEAR(dist[i], expected, 1e-12);
        }
    }
}

// Bad input: a non-simplicial mesh and mismatched sizes are named.
TEST(Harmonic, BadInputIsRejected) {
    const mesh::Mesh hex = mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                                           Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(1, 1, 1));
    const mesh::Boundary b = mesh::boundary(hex);
    test::expect_error(
        [&] { homogenize::harmonic_displacements(hex, b, SparseMatrix(24, 24), b.normals); },
        "simplicial");
    const mesh::Mesh tet = mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                           Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(1, 1, 1));
    const mesh::Boundary bt = mesh::boundary(tet);
    test::expect_error(
        [&] { homogenize::harmonic_displacements(tet, bt, SparseMatrix(3, 3), bt.normals); },
        "K is 3x3");
    test::expect_error([&] { homogenize::mollifiers(tet, Matrix::Zero(24, 5)); }, "24x5");
}

}  // namespace
}  // namespace coarsegrain
