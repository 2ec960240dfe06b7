// Corotated elements (Kharevych et al. 2009, Sec. 4): rigid rotations of any angle store no
// energy, a rotated small strain gives the rotated linear force, and de Veubeke's frame is the
// stationary point of |û|², on every element type with a generic anisotropic tensor.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "coarsegrain/fem/corotation.hpp"
#include "coarsegrain/fem/element.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

/// Corners of each element type, scaled by (1.7, 1, 0.8), sheared and moved by up to 0.15 each
/// (fixed seed): a distorted element, not a parallelogram for Q1.
Matrix corotation_corners(ElementType type, unsigned seed) {
    Matrix R;
    switch (type) {
        case ElementType::Tri3:
            R = (Matrix(3, 2) << 0, 0, 1, 0, 0, 1).finished();
            break;
        case ElementType::Quad4:
            R = (Matrix(4, 2) << 0, 0, 1, 0, 1, 1, 0, 1).finished();
            break;
        case ElementType::Tet4:
            R = (Matrix(4, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
            break;
        case ElementType::Hex8:
            R = (Matrix(8, 3) << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0,
                 1, 1)
                    .finished();
            break;
    }
    const Index dim = R.cols();
    Matrix A = Matrix::Identity(dim, dim);
    A(0, 0) = 1.7;
    A(0, 1) = 0.3;
    A(dim - 1, dim - 1) = 0.8;
    Matrix X = R * A.transpose();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (Index a = 0; a < X.rows(); ++a)
        for (Index d = 0; d < dim; ++d) X(a, d) += 0.15 * U(rng) + 2.0;
    return X;
}

/// The rotation by `angle` about the unit `axis` (3D; 2D uses the angle only).
Matrix rotation(int dim, double angle, Eigen::Vector3d axis) {
    if (dim == 2)
        return (Matrix(2, 2) << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle))
            .finished();
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// Node rows mapped by x -> Q x + t.
Matrix moved(const Matrix& X, const Matrix& Q, const Eigen::VectorXd& t) {
    return (X * Q.transpose()).rowwise() + t.transpose();
}

/// An interleaved vector as npe x dim rows.
Matrix as_rows(const Vector& u, Index dim) {
    Matrix r(u.size() / dim, dim);
    for (Index a = 0; a < r.rows(); ++a) r.row(a) = u.segment(a * dim, dim).transpose();
    return r;
}

/// Each dim-block of v multiplied by Q.
Vector rotated_blocks(const Matrix& Q, const Vector& v) {
    const Index dim = Q.rows();
    Vector out(v.size());
    for (Index a = 0; a < v.size() / dim; ++a)
        out.segment(a * dim, dim) = Q * v.segment(a * dim, dim);
    return out;
}

class CorotationTest : public ::testing::TestWithParam<ElementType> {
  protected:
    int dim() const { return mesh::element_dim(GetParam()); }
    Matrix corners(unsigned seed = 1) const { return corotation_corners(GetParam(), seed); }
    Matrix stiffness(const Matrix& X) const {
        return fem::element_stiffness(GetParam(), X,
                                      test::random_spd_tensor(mandel_size(dim()), 3));
    }
};

constexpr fem::CorotationFrame kFrames[] = {fem::CorotationFrame::DeVeubeke,
                                            fem::CorotationFrame::Polar};

// A rigid motion x = Q X + t with Q of any angle up to 180 degrees: both frames find R = Q, the
// corotated displacement vanishes, and so do the energy and the force (relative to the force
// scale |K| |X|, 1e-10: the SVD and the products are backward stable, errors ~1e-15 |X|).
TEST_P(CorotationTest, RigidRotationsStoreNoEnergy) {
    const Matrix X = corners();
    const Matrix K = stiffness(X);
    const double scale = K.norm() * X.norm();
    const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(dim(), 0.3, -1.1);
    for (const double degrees : {0.0, 30.0, 90.0, 135.0, 179.9, 180.0})
        for (const Eigen::Vector3d& axis : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 2, -0.5)})
            for (const fem::CorotationFrame frame : kFrames) {
                const Matrix Q = rotation(dim(), degrees * std::numbers::pi / 180, axis);
                const fem::CorotatedElement e = fem::corotate(X, moved(X, Q, t), K, frame);
                SCOPED_TRACE(::testing::Message()
                             << degrees << " degrees, " << fem::corotation_frame_name(frame));
                EXPECT_LT((e.R - Q).norm(), 1e-12);
                EXPECT_LT(e.u_hat.norm(), 1e-12 * X.norm());
                EXPECT_LT(e.force.norm(), 1e-10 * scale);
                EXPECT_LT(std::abs(e.energy), 1e-20 * scale * X.norm());
            }
}

// x = Q (X + ε u) + t: the corotated force is the rotated linear force Q K (ε u) up to O(ε²)
// (the frame's error is O(ε), and it multiplies a strain of O(ε)): fitted order 2 (within 0.1)
// of |f - Q K ε u| over ε = 1e-2 .. 1e-4, for both frames and a 120-degree rotation.
TEST_P(CorotationTest, RotatedSmallStrainGivesTheRotatedLinearForce) {
    const Matrix X = corners();
    const Matrix K = stiffness(X);
    const Vector u = Vector::LinSpaced(X.size(), -1.0, 1.3).array().sin().matrix();
    const Matrix Q = rotation(dim(), 2 * std::numbers::pi / 3, {1, 1, 0.2});
    const Eigen::VectorXd t = Eigen::VectorXd::Constant(dim(), 0.7);
    for (const fem::CorotationFrame frame : kFrames) {
        std::vector<double> eps, errors;
        for (const double e : {1e-2, 1e-3, 1e-4}) {
            const Matrix x = moved(X + as_rows(e * u, dim()), Q, t);
            const fem::CorotatedElement c = fem::corotate(X, x, K, frame);
            eps.push_back(e);
            errors.push_back((c.force - rotated_blocks(Q, K * (e * u))).norm());
        }
        EXPECT_NEAR(test::fitted_slope(eps, errors), 2.0, 0.1) << fem::corotation_frame_name(frame);
    }
}

// de Veubeke's R minimizes Σ_a |Rᵀ(x_a - b) - (X_a - b_0)|², i.e. maximizes tr(Rᵀ A) over
// rotations: stationarity is the symmetry of Rᵀ A (its skew part vanishes; asserted to 1e-12 of
// |A|), and at a minimum Rᵀ A is positive semi-definite on the rotation's tangent space (here:
// any small rotation of R increases |û|²). Under a large general deformation.
TEST_P(CorotationTest, DeVeubekeFrameIsStationaryAndMinimal) {
    const Matrix X = corners();
    const Matrix x =
        corotation_corners(GetParam(), 7) * 1.3 + Matrix::Constant(X.rows(), dim(), 0.4);
    const Matrix X0 = X.rowwise() - X.colwise().mean();
    const Matrix x0 = x.rowwise() - x.colwise().mean();
    const Matrix A = x0.transpose() * X0;
    const Matrix R = fem::corotation_frame(X, x, fem::CorotationFrame::DeVeubeke);
    const Matrix RA = R.transpose() * A;
    EXPECT_LT((RA - RA.transpose()).norm(), 1e-12 * A.norm());
    EXPECT_LT((R.transpose() * R - Matrix::Identity(dim(), dim())).norm(), 1e-13);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-13);
    const auto residual = [&](const Matrix& Rt) { return (x0 * Rt - X0).squaredNorm(); };
    for (const Eigen::Vector3d& axis : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 1)})
        for (const double angle : {1e-3, -1e-3})
            EXPECT_GT(residual(R * rotation(dim(), angle, axis)), residual(R));
}

// At a rigidly rotated rest state (û = 0) the derivative of R multiplies K û = 0, so the tangent
// R K Rᵀ is the force's exact derivative there: central differences of the force agree to
// O(h²) (h = 1e-6 of the element size: asserted 1e-6 of |K|).
TEST_P(CorotationTest, TangentIsExactAtARotatedRestState) {
    const Matrix X = corners();
    const Matrix K = stiffness(X);
    const Matrix Q = rotation(dim(), 1.0, {0.3, -1, 0.5});
    const Matrix x = moved(X, Q, Eigen::VectorXd::Constant(dim(), -0.2));
    for (const fem::CorotationFrame frame : kFrames) {
        const Matrix tangent = fem::corotate(X, x, K, frame).tangent;
        Matrix fd(X.size(), X.size());
        const double h = 1e-6;
        for (Index j = 0; j < X.size(); ++j) {
            Matrix plus = x, minus = x;
            plus(j / dim(), j % dim()) += h;
            minus(j / dim(), j % dim()) -= h;
            fd.col(j) =
                (fem::corotate(X, plus, K, frame).force - fem::corotate(X, minus, K, frame).force) /
                (2 * h);
        }
        EXPECT_LT((fd - tangent).norm(), 1e-6 * K.norm()) << fem::corotation_frame_name(frame);
    }
}

// The force R K û holds R fixed. The full gradient of W = ½ ûᵀ K û adds ûᵀ K dRᵀ (x - b), and
// with dR = R Ω (Ω skew) its rest part -Σ_a (K û)_aᵀ Ω (X_a - b_0) vanishes for any frame:
// Σ_a (K û)_a (X_a - b_0)ᵀ is the element's integrated stress, a symmetric matrix. What remains,
// -Σ_a (K û)_aᵀ Ω û_a, is second order in the strain: under x = Q (X + ε u) + t the central
// differences of W differ from the force by O(ε²) (fitted order 2 within 0.15; the force itself is
// O(ε)), for both frames.
TEST_P(CorotationTest, ForceIsTheEnergyGradientToSecondOrderInTheStrain) {
    const Matrix X = corners();
    const Matrix K = stiffness(X);
    const Vector u = Vector::LinSpaced(X.size(), 0.5, -2.0).array().cos().matrix();
    const Matrix Q = rotation(dim(), 0.8, {0.2, 0.4, 1});
    for (const fem::CorotationFrame frame : kFrames) {
        std::vector<double> eps, errors;
        for (const double e : {4e-2, 2e-2, 1e-2}) {
            const Matrix x = moved(X + as_rows(e * u, dim()), Q, Eigen::VectorXd::Ones(dim()));
            const Vector force = fem::corotate(X, x, K, frame).force;
            Vector gradient(X.size());
            const double h = 1e-7;
            for (Index j = 0; j < X.size(); ++j) {
                Matrix plus = x, minus = x;
                plus(j / dim(), j % dim()) += h;
                minus(j / dim(), j % dim()) -= h;
                gradient[j] = (fem::corotate(X, plus, K, frame).energy -
                               fem::corotate(X, minus, K, frame).energy) /
                              (2 * h);
            }
            eps.push_back(e);
            errors.push_back((gradient - force).norm());
        }
        EXPECT_NEAR(test::fitted_slope(eps, errors), 2.0, 0.15)
            << fem::corotation_frame_name(frame);
    }
}

// Where the frames differ: a box of a x 1 (x 1) cells under the simple shear x += γ y. The polar
// decomposition of F = I + γ e_x e_yᵀ rotates by atan(γ/2) whatever the element's shape; de
// Veubeke's frame is the rotation factor of F J with J ∝ diag(a², 1, 1), which rotates by
// atan(γ/(a² + 1)): the same on a square or cube, and following the long axis (which the shear
// leaves in place) on an elongated element: 23.2 degrees apart for a = 4, γ = 1. Analytic angles
// to 1e-12.
TEST(Corotation, FramesDifferOnElongatedElements) {
    for (const ElementType type : {ElementType::Quad4, ElementType::Hex8})
        for (const double a : {1.0, 2.0, 4.0})
            for (const double gamma : {0.1, 1.0}) {
                const int dim = mesh::element_dim(type);
                const Matrix unit = type == ElementType::Quad4
                                        ? (Matrix(4, 2) << 0, 0, 1, 0, 1, 1, 0, 1).finished()
                                        : (Matrix(8, 3) << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0,
                                           1, 1, 0, 1, 1, 1, 1, 0, 1, 1)
                                              .finished();
                Matrix X = unit;
                X.col(0) *= a;
                Matrix x = X;
                x.col(0) += gamma * X.col(1);
                const auto angle = [&](fem::CorotationFrame frame) {
                    const Matrix R = fem::corotation_frame(X, x, frame);
                    return std::atan2(R(1, 0), R(0, 0));  // rotation about z, counter-clockwise
                };
                SCOPED_TRACE(::testing::Message()
                             << "dim " << dim << ", a " << a << ", γ " << gamma);
                EXPECT_NEAR(angle(fem::CorotationFrame::Polar), -std::atan(gamma / 2), 1e-12);
                EXPECT_NEAR(angle(fem::CorotationFrame::DeVeubeke), -std::atan(gamma / (a * a + 1)),
                            1e-12);
            }
}

INSTANTIATE_TEST_SUITE_P(Elements, CorotationTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

}  // namespace
