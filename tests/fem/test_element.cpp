#include <gtest/gtest.h>

#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/element.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

/// Reference corners of each element type (orderings of ElementType).
Matrix reference_corners(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return (Matrix(3, 2) << 0, 0, 1, 0, 0, 1).finished();
        case ElementType::Quad4:
            return (Matrix(4, 2) << 0, 0, 1, 0, 1, 1, 0, 1).finished();
        case ElementType::Tet4:
            return (Matrix(4, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
        case ElementType::Hex8:
            return (Matrix(8, 3) << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1,
                    0, 1, 1)
                .finished();
    }
    return {};
}

/// A distorted element: reference corners scaled, sheared and translated, each corner moved by
/// up to 0.15 (fixed seed). Not a parallelogram/parallelepiped for Q1.
Matrix distorted_corners(ElementType type, unsigned seed) {
    const Matrix R = reference_corners(type);
    const int dim = static_cast<int>(R.cols());
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Matrix A = Matrix::Identity(dim, dim);
    A(0, 0) = 1.7;
    A(0, 1) = 0.3;
    A(dim - 1, dim - 1) = 0.8;
    Matrix X = R * A.transpose();
    for (Index a = 0; a < X.rows(); ++a)
        for (int d = 0; d < dim; ++d) X(a, d) += 0.15 * U(rng) + 2.0;
    return X;
}

int mandel(ElementType type) { return mandel_size(mesh::element_dim(type)); }

class ElementTest : public ::testing::TestWithParam<ElementType> {};

// K_e is symmetric, the rigid motions are in its kernel, and it has exactly 3 (2D) / 6 (3D)
// zero eigenvalues, on a distorted element with a generic anisotropic tensor.
TEST_P(ElementTest, StiffnessIsSymmetricWithExactlyTheRigidKernel) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    for (unsigned seed = 1; seed <= 5; ++seed) {
        const Matrix X = distorted_corners(type, seed);
        const Matrix C = test::random_spd_tensor(mandel(type), seed);
        const Matrix K = fem::element_stiffness(type, X, C);
        // Symmetrized in the kernel: exactly symmetric.
        EXPECT_EQ((K - K.transpose()).norm(), 0.0);
        // Rigid motions: K R vanishes to round-off (1e-13 relative to |K| |R|).
        const Matrix R = test::rigid_modes(X);
        EXPECT_LT((K * R).norm(), 1e-13 * K.norm() * R.norm());
        // Eigenvalues: the rigid ones are round-off (< 1e-12 of the largest); the next is a
        // genuine deformation mode, orders of magnitude above (> 1e-4 of the largest).
        const Eigen::SelfAdjointEigenSolver<Matrix> eig(K);
        const Eigen::VectorXd lambda = eig.eigenvalues();
        const double lmax = lambda.maxCoeff();
        const int rigid = dim == 3 ? 6 : 3;
        EXPECT_EQ((lambda.array().abs() < 1e-12 * lmax).count(), rigid);
        EXPECT_GT(lambda[rigid], 1e-4 * lmax);
    }
}

// For a linear field u = A x the strain is uniform, so u^T K u = vol eps^T C eps exactly (P1:
// constant strain; Q1: the isoparametric map reproduces linear fields and 2^dim Gauss points
// integrate det J exactly, even on distorted elements). 1e-12 relative: round-off only.
TEST_P(ElementTest, UniformStrainEnergyIsExact) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    const Matrix X = distorted_corners(type, 7);
    const Matrix C = test::random_spd_tensor(mandel(type), 7);
    Matrix A(dim, dim);
    A.setRandom();
    const Vector u = test::linear_field(X, A, Eigen::VectorXd::Ones(dim));
    const Eigen::VectorXd e = test::mandel_strain(A);
    mesh::Mesh m;
    m.type = type;
    m.rest_positions = X;
    m.elements = IndexMatrix(1, X.rows());
    for (Index a = 0; a < X.rows(); ++a) m.elements(0, a) = a;
    const double vol = mesh::element_measure(m, 0);
    const double expected = vol * e.dot(C * e);
    const Matrix K = fem::element_stiffness(type, X, C);
    EXPECT_NEAR(u.dot(K * u), expected, 1e-12 * std::abs(expected));

    // B u gives the Mandel strain at any reference point.
    Eigen::VectorXd xi = Eigen::VectorXd::Constant(dim, 0.2);
    xi[0] = 0.1;
    const Matrix B = fem::strain_displacement(type, X, xi);
    EXPECT_LT((B * u - e).norm(), 1e-13 * e.norm());
}

// Q1 on a box with the bilinear (trilinear) field u = (x y, y z, z x) (2D: (x y, 0)), which Q1
// interpolates exactly: the strain varies linearly, and u^T K u must equal the analytic
// ∫ eps^T C eps over the box (2x2 Gauss is exact for the quadratic integrand on a box).
TEST(ElementQ1, BilinearFieldEnergyOnABoxMatchesTheIntegral) {
    const double a = 1.5, b = 0.7, c = 1.2;  // box sides
    for (const ElementType type : {ElementType::Quad4, ElementType::Hex8}) {
        const int dim = mesh::element_dim(type);
        Matrix X = reference_corners(type);
        X.col(0) *= a;
        X.col(1) *= b;
        if (dim == 3) X.col(2) *= c;
        const Matrix C = test::random_spd_tensor(mandel(type), 11);
        Vector u(X.size());
        for (Index n = 0; n < X.rows(); ++n) {
            const double x = X(n, 0), y = X(n, 1), z = dim == 3 ? X(n, 2) : 0.0;
            if (dim == 2) {
                u.segment(2 * n, 2) << x * y, 0.0;
            } else {
                u.segment(3 * n, 3) << x * y, y * z, z * x;
            }
        }
        // Analytic strain at (x, y, z) in Mandel form.
        const auto strain = [&](double x, double y, double z) {
            Eigen::VectorXd e(mandel(type));
            if (dim == 2) {
                e << y, 0.0, kSqrt2 * 0.5 * x;  // e11 = y, e12 = x/2
            } else {
                // u = (xy, yz, zx): e11 = y, e22 = z, e33 = x, e23 = y/2, e13 = z/2, e12 = x/2
                e << y, z, x, kSqrt2 * 0.5 * y, kSqrt2 * 0.5 * z, kSqrt2 * 0.5 * x;
            }
            return e;
        };
        // Integrate the quadratic energy density with 3 Gauss points per axis (exact).
        const test::Quadrature q = test::reference_quadrature(type, 3);
        double expected = 0;
        for (Index k = 0; k < q.points.rows(); ++k) {
            const double x = a * q.points(k, 0), y = b * q.points(k, 1);
            const double z = dim == 3 ? c * q.points(k, 2) : 0.0;
            const Eigen::VectorXd e = strain(x, y, z);
            expected += q.weights[k] * a * b * (dim == 3 ? c : 1.0) * e.dot(C * e);
        }
        const Matrix K = fem::element_stiffness(type, X, C);
        EXPECT_NEAR(u.dot(K * u), expected, 1e-12 * expected) << mesh::element_name(type);
    }
}

// Consistent and lumped mass: every component block sums to the element mass rho * vol, the
// row sums equal rho ∫ N_a (element_load_weights), the lumped mass is diagonal with those row
// sums, and components do not couple. 1e-13 relative: round-off.
TEST_P(ElementTest, MassSumsToTheElementMass) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    const int npe = mesh::nodes_per_element(type);
    const Matrix X = distorted_corners(type, 3);
    const double rho = 2.5;
    mesh::Mesh m;
    m.type = type;
    m.rest_positions = X;
    m.elements = IndexMatrix(1, npe);
    for (int a = 0; a < npe; ++a) m.elements(0, a) = a;
    const double mass = rho * mesh::element_measure(m, 0);
    const Eigen::VectorXd w = fem::element_load_weights(type, X);
    EXPECT_NEAR(w.sum() * rho, mass, 1e-13 * mass);
    for (const bool lumped : {false, true}) {
        const Matrix M = fem::element_mass(type, X, rho, lumped);
        ASSERT_EQ(M.rows(), npe * dim);
        EXPECT_EQ((M - M.transpose()).norm(), 0.0);
        for (int d = 0; d < dim; ++d) {
            double total = 0, cross = 0;
            for (int a = 0; a < npe; ++a)
                for (int b = 0; b < npe; ++b) {
                    total += M(dim * a + d, dim * b + d);
                    cross += std::abs(M(dim * a + d, dim * b + (d + 1) % dim));
                }
            EXPECT_NEAR(total, mass, 1e-13 * mass);
            EXPECT_EQ(cross, 0.0);
        }
        for (int a = 0; a < npe; ++a) EXPECT_NEAR(M.row(dim * a).sum(), rho * w[a], 1e-13 * mass);
        if (lumped) {
            EXPECT_EQ((M - Matrix(M.diagonal().asDiagonal())).norm(), 0.0);
        }
    }
    // Consistent mass is positive definite.
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(fem::element_mass(type, X, rho, false));
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
}

// Closed forms: the bilinear rectangle's consistent mass is rho A / 36 [4 2 1 2; 2 4 2 1; ...]
// and the P1 simplex's is rho vol / ((d+1)(d+2)) (1 + delta_ab). 1e-14 relative.
TEST(ElementMass, ClosedFormsOnRectangleAndSimplex) {
    const Matrix Xq = (Matrix(4, 2) << 0, 0, 2, 0, 2, 3, 0, 3).finished();
    const Matrix Mq = fem::element_mass(ElementType::Quad4, Xq, 1.5, false);
    Matrix expected(4, 4);
    expected << 4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4;
    expected *= 1.5 * 6.0 / 36.0;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) EXPECT_NEAR(Mq(2 * a + 1, 2 * b + 1), expected(a, b), 1e-14);

    const Matrix Xt = (Matrix(4, 3) << 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0, 3).finished();  // vol 1
    const Matrix Mt = fem::element_mass(ElementType::Tet4, Xt, 2.0, false);
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            EXPECT_NEAR(Mt(3 * a + 2, 3 * b + 2), 2.0 * (a == b ? 2.0 : 1.0) / 20.0, 1e-14);
}

// detJ of strain_displacement: P1 returns dim! times the measure; Q1 returns the Jacobian
// determinant of the reference map, here the box volume (constant on a box).
TEST(ElementGeometry, JacobianDeterminant) {
    double detJ = 0;
    const Matrix Xt = (Matrix(3, 2) << 0, 0, 2, 0, 0, 3).finished();  // area 3
    fem::strain_displacement(ElementType::Tri3, Xt, Eigen::Vector2d(0.3, 0.3), &detJ);
    EXPECT_NEAR(detJ, 6.0, 1e-14);
    Matrix Xh = reference_corners(ElementType::Hex8);
    Xh.col(0) *= 2.0;
    Xh.col(2) *= 0.5;
    fem::strain_displacement(ElementType::Hex8, Xh, Eigen::Vector3d(0.1, 0.7, 0.4), &detJ);
    EXPECT_NEAR(detJ, 1.0, 1e-14);
    EXPECT_EQ(fem::element_centre(ElementType::Tet4), Eigen::VectorXd::Constant(3, 0.25));
    EXPECT_EQ(fem::element_centre(ElementType::Quad4), Eigen::VectorXd::Constant(2, 0.5));
}

TEST(ElementErrors, InvertedAndWrongSizes) {
    Matrix X = reference_corners(ElementType::Tet4);
    X.row(1).swap(X.row(2));  // negative volume
    try {
        fem::element_stiffness(ElementType::Tet4, X, Matrix::Identity(6, 6));
        FAIL() << "no error for an inverted tet";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("inverted"), std::string::npos) << e.what();
    }
    Matrix flat = reference_corners(ElementType::Hex8);
    flat.col(2).setZero();
    EXPECT_THROW(fem::element_mass(ElementType::Hex8, flat, 1.0, false), Error);
    EXPECT_THROW(fem::element_stiffness(ElementType::Quad4, reference_corners(ElementType::Tri3),
                                        Matrix::Identity(3, 3)),
                 Error);
    EXPECT_THROW(fem::element_stiffness(ElementType::Tri3, reference_corners(ElementType::Tri3),
                                        Matrix::Identity(6, 6)),
                 Error);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, ElementTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

}  // namespace
