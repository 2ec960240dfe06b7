#include <gtest/gtest.h>

#include "test_util.hpp"

#include <cmath>
#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;
using test::expect_error;
using material::PlaneMode;

namespace {


const int kPlane[3] = {0, 1, 5};  // the (11, 22, 12) rows of the 3D Mandel tensor

// The compliance of the 3D isotropic tensor has the textbook entries 1/E, -nu/E and, for
// Mandel shear, (1 + nu)/E = 1/(2 mu). 1e-14 relative: one 6x6 inverse.
TEST(Isotropic, ComplianceHasTheTextbookEntries) {
    const double E = 210.0, nu = 0.28;
    const material::Material m = material::isotropic(3, E, nu, 7.8);
    const Matrix S = m.C.inverse();
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(S(i, i), 1.0 / E, 1e-14 / E);
        for (int j = 0; j < 3; ++j) {
            if (i != j) {
                EXPECT_NEAR(S(i, j), -nu / E, 1e-14 / E);
            }
        }
        EXPECT_NEAR(S(3 + i, 3 + i), (1.0 + nu) / E, 1e-14 / E);
    }
    EXPECT_EQ(m.E, E);
    EXPECT_EQ(m.nu, nu);
    EXPECT_EQ(m.density, 7.8);
}

// Plane strain is the (11, 22, 12) block of the 3D tensor (exact copy); plane stress is the
// Schur complement that eliminates sigma_33 = 0 (1e-13 relative).
TEST(Isotropic, PlaneStrainIsABlockAndPlaneStressIsTheCondensation) {
    const double E = 3.0, nu = 0.35;
    const material::Material m3 = material::isotropic(3, E, nu, 1.0);
    const material::Material strain = material::isotropic(2, E, nu, 1.0);
    const material::Material stress = material::isotropic(2, E, nu, 1.0, PlaneMode::Stress);
    Matrix Cpp(3, 3), Cpz(3, 1);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            EXPECT_EQ(strain.C(i, j), m3.C(kPlane[i], kPlane[j]));
            Cpp(i, j) = m3.C(kPlane[i], kPlane[j]);
        }
        Cpz(i, 0) = m3.C(kPlane[i], 2);
    }
    const Matrix condensed = Cpp - Cpz * Cpz.transpose() / m3.C(2, 2);
    EXPECT_LT((material::tensor(stress, 2) - condensed).norm(), 1e-13 * condensed.norm());
    // Only the 2D block is used: the rest of the storage is zero.
    EXPECT_EQ((stress.C.bottomRightCorner<3, 3>().norm()), 0.0);
    EXPECT_EQ(stress.mode, PlaneMode::Stress);
}

TEST(Isotropic, ValidationMessagesNameTheValue) {
    expect_error([] { material::isotropic(3, -3, 0.3, 1); }, "E = -3 must be > 0");
    expect_error([] { material::isotropic(3, 1, 0.5, 1); }, "nu = 0.5 must satisfy -1 < nu < 0.5");
    expect_error([] { material::isotropic(2, 1, -1, 1); }, "nu = -1 must satisfy -1 < nu < 0.5");
    expect_error([] { material::isotropic(3, 1, 0.3, 0); }, "density = 0 must be > 0");
    expect_error([] { material::isotropic(4, 1, 0.3, 1); }, "dimension 4 must be 2 or 3");
    expect_error([] { material::isotropic(3, std::nan(""), 0.3, 1); }, "E = nan must be > 0");
}

TEST(Anisotropic, AcceptsSpdAndSetsMeanAxisModulus) {
    // Orthotropic 3D compliance with moduli E1..E3: the directional moduli along the axes are
    // exactly E_i, so E is their mean (1e-12 relative: one LLT solve per axis).
    const double E1 = 10, E2 = 4, E3 = 2, n12 = 0.2, n13 = 0.1, n23 = 0.25;
    Matrix S = Matrix::Zero(6, 6);
    S(0, 0) = 1 / E1, S(1, 1) = 1 / E2, S(2, 2) = 1 / E3;
    S(0, 1) = S(1, 0) = -n12 / E1;
    S(0, 2) = S(2, 0) = -n13 / E1;
    S(1, 2) = S(2, 1) = -n23 / E2;
    S(3, 3) = 1 / 3.0, S(4, 4) = 1 / 2.0, S(5, 5) = 1 / 5.0;  // 1/(2 G_ij), Mandel
    const Matrix C = S.inverse();
    const material::Material m = material::anisotropic(3, 0.5 * (C + C.transpose()), 2.0);
    EXPECT_NEAR(material::directional_young(material::tensor(m, 3), Eigen::Vector3d::UnitX()), E1,
                1e-12 * E1);
    EXPECT_NEAR(material::directional_young(material::tensor(m, 3), Eigen::Vector3d::UnitY()), E2,
                1e-12 * E2);
    EXPECT_NEAR(m.E, (E1 + E2 + E3) / 3, 1e-12 * E1);
    EXPECT_TRUE(std::isnan(m.nu));
}

TEST(Anisotropic, ValidationMessagesNameTheValue) {
    Matrix C = Matrix::Identity(3, 3);
    C(0, 1) = 0.5;  // not symmetric
    expect_error([&] { material::anisotropic(2, C, 1); }, "C(0,1) = 0.5 and C(1,0) = 0");
    Matrix D = Matrix::Identity(3, 3);
    D(2, 2) = -3;  // symmetric, indefinite
    expect_error([&] { material::anisotropic(2, D, 1); }, "eigenvalues are -3, 1, 1 (ratio -3)");
    // Positive but 13 decades apart: the criterion is relative, and the message says so.
    Matrix F = Matrix::Identity(3, 3);
    F(0, 0) = 1e-13;
    expect_error([&] { material::anisotropic(2, F, 1); },
                 "smallest / largest eigenvalue > 1e-12, but its eigenvalues are 1e-13, 1, 1 "
                 "(ratio 1e-13)");
    expect_error([&] { material::anisotropic(3, D, 1); }, "must be 6x6 (Mandel), got 3x3");
    expect_error([&] { material::anisotropic(2, Matrix::Identity(3, 3), -1); },
                 "density = -1 must be > 0");
}

// Voigt -> Mandel multiplies shear rows and columns by √2 (so the normal-shear coupling gains √2
// and the shear-shear block 2); the round trip is the identity; and the strain energy is the
// same in both notations (engineering shear strains in Voigt). 1e-14 relative.
TEST(Notation, VoigtMandelRoundTripAndEnergy) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-1, 1);
    for (const int n : {3, 6}) {
        Matrix Cv(n, n);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j <= i; ++j) Cv(i, j) = Cv(j, i) = U(rng);
        const Matrix Cm = material::voigt_to_mandel(Cv);
        const int s = n == 6 ? 3 : 2;  // first shear index
        EXPECT_NEAR(Cm(0, s), kSqrt2 * Cv(0, s), 1e-15);
        EXPECT_NEAR(Cm(s, s), 2 * Cv(s, s), 1e-15);
        EXPECT_LT((material::mandel_to_voigt(Cm) - Cv).norm(), 1e-14 * Cv.norm());
        Eigen::VectorXd eps_m(n), eps_v(n);
        for (int i = 0; i < n; ++i) eps_m[i] = U(rng);
        eps_v = eps_m;
        eps_v.tail(n - s) *= kSqrt2;  // gamma = 2 e = √2 (√2 e)
        EXPECT_NEAR(eps_m.dot(Cm * eps_m), eps_v.dot(Cv * eps_v), 1e-14);
    }
    EXPECT_THROW(material::voigt_to_mandel(Matrix::Identity(4, 4)), Error);
}

// The directional Young's modulus of an isotropic 3D (or 2D plane-stress) tensor is E in every
// direction; a 2D plane-strain tensor gives E / (1 - nu^2). 1e-12 relative.
TEST(Notation, DirectionalYoungOfIsotropicIsE) {
    const double E = 5.0, nu = 0.3;
    const Matrix C3 = material::tensor(material::isotropic(3, E, nu, 1), 3);
    const Matrix Cs = material::tensor(material::isotropic(2, E, nu, 1, PlaneMode::Stress), 2);
    const Matrix Ce = material::tensor(material::isotropic(2, E, nu, 1), 2);
    std::mt19937 rng(2);
    std::normal_distribution<double> N;
    for (int k = 0; k < 10; ++k) {
        const Eigen::Vector3d d(N(rng), N(rng), N(rng));
        EXPECT_NEAR(material::directional_young(C3, d), E, 1e-12 * E);
        EXPECT_NEAR(material::directional_young(Cs, d.head<2>()), E, 1e-12 * E);
        EXPECT_NEAR(material::directional_young(Ce, d.head<2>()), E / (1 - nu * nu), 1e-12 * E);
    }
    expect_error([&] { material::directional_young(C3, Eigen::Vector2d(1, 0)); },
                 "direction has 2 components, expected 3");
    expect_error([&] { material::directional_young(C3, Eigen::Vector3d::Zero()); },
                 "the direction is zero");
}

TEST(Assign, MapsIdsAndNamesTheMissingOne) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d(0, 0),
                                   Eigen::Vector2d(4, 1), Eigen::Vector2i(4, 1));
    m.material_ids << 7, 3, 7, 3;
    const material::Material a = material::isotropic(2, 1, 0.3, 1);
    const material::Material b = material::isotropic(2, 2, 0.3, 1);
    const material::ElementMaterials mats = material::assign(m, {{3, a}, {7, b}, {9, a}});
    ASSERT_EQ(mats.size(), 4);
    EXPECT_EQ(mats.dim, 2);
    EXPECT_EQ(mats.table.size(), 2u);  // only the ids that occur
    EXPECT_EQ(mats.of(0).E, 2.0);
    EXPECT_EQ(mats.of(1).E, 1.0);
    m.material_ids << 7, 5, 5, 5;
    expect_error(
        [&] {
            material::assign(m, {{3, a}, {7, b}});
        },
        "material id 5 is used by 3 element(s) but has no material (defined ids: 3, 7)");

    const material::ElementMaterials u = material::uniform(m, a);
    EXPECT_EQ(u.size(), 4);
    EXPECT_EQ(u.table.size(), 1u);
    EXPECT_EQ(u.of(3).E, 1.0);
}

}  // namespace
