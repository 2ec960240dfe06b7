#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using material::PlaneMode;
using mesh::ElementType;

namespace {

mesh::Mesh distorted(ElementType type) {
    const int dim = mesh::element_dim(type);
    mesh::Mesh m = mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                                   Eigen::VectorXi::Constant(dim, 3));
    test::distort_interior(m, 0.1);
    return m;
}

/// Mandel vector of a symmetric dim x dim tensor.
Eigen::VectorXd mandel_vector(const Matrix& t) {
    Eigen::VectorXd v(mandel_size(static_cast<int>(t.rows())));
    if (t.rows() == 2) {
        v << t(0, 0), t(1, 1), kSqrt2 * t(0, 1);
    } else {
        v << t(0, 0), t(1, 1), t(2, 2), kSqrt2 * t(1, 2), kSqrt2 * t(0, 2), kSqrt2 * t(0, 1);
    }
    return v;
}

class StressTest : public ::testing::TestWithParam<ElementType> {};

// A linear displacement (uniform strain plus a rotation) on a distorted mesh with a generic
// anisotropic tensor gives strain sym(A) and stress C sym(A) in every element (1e-12 relative:
// no solve involved), and the strain energy 1/2 u^T K u equals 1/2 vol eps^T C eps.
TEST_P(StressTest, UniformStrainGivesCEpsInEveryElement) {
    const mesh::Mesh m = distorted(GetParam());
    const int dim = m.dim();
    const Matrix C = test::random_spd_tensor(mandel_size(dim), 4);
    const material::ElementMaterials mats = material::uniform(m, material::anisotropic(dim, C, 1));
    Matrix A(dim, dim);
    A.setRandom();
    const Vector u = test::linear_field(m.rest_positions, A, Eigen::VectorXd::Ones(dim));
    const Eigen::VectorXd e = mandel_vector(0.5 * (A + A.transpose()));
    const Eigen::VectorXd sigma = C * e;
    const fem::ElementStress s = fem::element_stress(m, mats, u);
    ASSERT_EQ(s.stress.rows(), m.num_elements());
    for (Index el = 0; el < m.num_elements(); ++el) {
        EXPECT_LT((s.strain.row(el).transpose() - e).norm(), 1e-12 * e.norm());
        EXPECT_LT((s.stress.row(el).transpose() - sigma).norm(), 1e-12 * sigma.norm());
    }
    const double energy = fem::strain_energy(fem::stiffness_matrix(m, mats), u);
    EXPECT_NEAR(energy, 0.5 * e.dot(sigma), 1e-12 * e.dot(sigma));  // unit box: vol = 1
}

INSTANTIATE_TEST_SUITE_P(AllTypes, StressTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

/// Von Mises stress of element 0 of a unit grid of `type` under the linear field u = A x.
double von_mises(ElementType type, const material::Material& mat, const Matrix& A) {
    const int dim = mesh::element_dim(type);
    const mesh::Mesh m = mesh::make_grid(type, Eigen::VectorXd::Zero(dim),
                                         Eigen::VectorXd::Ones(dim), Eigen::VectorXi::Ones(dim));
    const Vector u = test::linear_field(m.rest_positions, A, Eigen::VectorXd::Zero(dim));
    return fem::element_stress(m, material::uniform(m, mat), u).von_mises[0];
}

// Von Mises checks against stress states known in closed form (1e-12 relative):
// - 3D uniaxial stress sigma (strain diag(1, -nu, -nu) sigma / E): VM = |sigma|.
// - 3D pure shear tau: VM = √3 |tau|.
// - 2D plane stress uniaxial: VM = |sigma|.
// - 2D plane strain, strain e11 only: sigma = (lambda + 2mu, lambda, lambda) e11, so
//   VM = |sigma11 - sigma22| = 2 mu |e11| (sigma_zz = lambda e11 enters).
// - 2D anisotropic (sigma_zz = 0 by convention) under e11 only: VM of (C00, C10, 0; shear C20).
TEST(VonMises, ClosedFormStressStates) {
    const double E = 4.0, nu = 0.3, sigma = -2.5, tau = 0.7;
    const double mu = E / (2 * (1 + nu));
    const Matrix uniaxial3 = Eigen::Vector3d(1, -nu, -nu).asDiagonal() * (sigma / E);
    EXPECT_NEAR(von_mises(ElementType::Hex8, material::isotropic(3, E, nu, 1), uniaxial3),
                std::abs(sigma), 1e-12);
    EXPECT_NEAR(von_mises(ElementType::Tet4, material::isotropic(3, E, nu, 1), uniaxial3),
                std::abs(sigma), 1e-12);
    Matrix shear = Matrix::Zero(3, 3);
    shear(0, 1) = shear(1, 0) = tau / (2 * mu);  // e12 = tau / (2 mu)
    EXPECT_NEAR(von_mises(ElementType::Hex8, material::isotropic(3, E, nu, 1), shear),
                std::sqrt(3.0) * tau, 1e-12);

    const Matrix uniaxial2 = Eigen::Vector2d(1, -nu).asDiagonal() * (sigma / E);
    EXPECT_NEAR(von_mises(ElementType::Quad4, material::isotropic(2, E, nu, 1, PlaneMode::Stress),
                          uniaxial2),
                std::abs(sigma), 1e-12);
    const double e11 = 1e-2;
    const Matrix stretch = (Matrix(2, 2) << e11, 0, 0, 0).finished();
    EXPECT_NEAR(von_mises(ElementType::Tri3, material::isotropic(2, E, nu, 1), stretch),
                2 * mu * e11, 1e-12);

    const Matrix C = test::random_spd_tensor(3, 8);
    const double s11 = C(0, 0) * e11, s22 = C(1, 0) * e11, s12 = C(2, 0) * e11 / kSqrt2;
    const double expected = std::sqrt(s11 * s11 - s11 * s22 + s22 * s22 + 3 * s12 * s12);
    EXPECT_NEAR(von_mises(ElementType::Quad4, material::anisotropic(2, C, 1), stretch), expected,
                1e-12 * expected);
}

TEST(StressErrors, WrongSizes) {
    const mesh::Mesh m = distorted(ElementType::Tri3);
    const material::ElementMaterials mats = material::uniform(m, material::isotropic(2, 1, 0.3, 1));
    EXPECT_THROW(fem::element_stress(m, mats, Vector::Zero(3)), Error);
    EXPECT_THROW(fem::strain_energy(SparseMatrix(4, 4), Vector::Zero(3)), Error);
}

}  // namespace
