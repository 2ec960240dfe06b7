// The averaging baselines (naive Lamé, Voigt, Reuss) over exact intersections.
#include <gtest/gtest.h>

#include <array>

#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/material/material.hpp"
#include "homogenize/homogenize_test_util.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using nlohmann::json;
using test::grid;
using test::iso;

// One coarse cell (the 6 Kuhn tets of [0,1]^3) over a fine cube whose half x < 1/2 is material 1.
// Kuhn tet s is the region where the coordinates are ordered as its path adds the axes; the part
// with x < 1/2 is 1/8 of it where x is the largest coordinate, 1/2 where it is the middle one and
// 7/8 where it is the smallest, so the fractions of material 1 are known in closed form.
constexpr std::array<double, 6> kFraction = {1.0 / 8, 1.0 / 8, 1.0 / 2, 7.0 / 8, 1.0 / 2, 7.0 / 8};

test::Setup half_and_half(const json& m1, const json& m2) {
    return test::setup(
        {{"mesh", grid({0, 0, 0}, {1, 1, 1}, {4, 4, 4}, "tet")},
         {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.5}, {"ids", {1, 2}}}}}},
         {"materials", {{"1", m1}, {"2", m2}}},
         {"coarse", {{"mesh", grid({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, "tet")}}}});
}

TEST(Baselines, VoigtAndReussAreTheClosedFormAverages) {
    const test::Setup s = half_and_half(iso(100.0, 0.3, 2.0), iso(1.0, 0.45, 1.0));
    const Matrix C1 = material::isotropic(3, 100.0, 0.3, 2.0).C,
                 C2 = material::isotropic(3, 1.0, 0.45, 1.0).C;
    const homogenize::Coarsening voigt = homogenize::coarsening(s.scene, s.fine, "voigt");
    const homogenize::Coarsening reuss = homogenize::coarsening(s.scene, s.fine, "reuss");
    const homogenize::Coarsening naive = homogenize::coarsening(s.scene, s.fine, "naive");
    for (Index q = 0; q < 6; ++q) {
        const double f = kFraction[q];
        const Matrix V = f * C1 + (1 - f) * C2;
        const Matrix R = (f * C1.inverse() + (1 - f) * C2.inverse()).inverse();
        // 1e-12: the overlaps are exact to round-off (aligned meshes).
        EXPECT_LT((voigt.C[q] - V).norm(), 1e-12 * V.norm()) << "coarse element " << q;
        EXPECT_LT((reuss.C[q] - R).norm(), 1e-12 * R.norm()) << "coarse element " << q;
        // In 3D the isotropic tensor is linear in (lambda, mu): the naive average is Voigt's.
        EXPECT_LT((naive.C[q] - V).norm(), 1e-12 * V.norm()) << "coarse element " << q;
        // Arithmetic mean >= harmonic mean of SPD matrices: Voigt - Reuss is PSD.
        const Eigen::SelfAdjointEigenSolver<Matrix> eig(Matrix(voigt.C[q] - reuss.C[q]));
        EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-12 * V.norm());
        // The coarse mass is the fine mass inside the tet: rho1 f + rho2 (1 - f) times 1/6.
        EXPECT_NEAR(voigt.element_mass[q], (2.0 * f + 1.0 * (1 - f)) / 6, 1e-14);
    }
}

// In 2D plane stress the tensor is not linear in (lambda, mu) (lambda* = 2 lambda mu /
// (lambda + 2 mu)), so the naive average differs from Voigt's; check it against the closed form.
TEST(Baselines, NaivePlaneStressAveragesLameParameters) {
    const test::Setup s = test::setup(
        {{"mesh", grid({0, 0}, {1, 1}, {8, 8}, "tri")},
         {"plane", "stress"},
         {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.5}, {"ids", {1, 2}}}}}},
         {"materials", {{"1", iso(100.0, 0.3)}, {"2", iso(1.0, 0.45)}}},
         {"coarse", {{"mesh", grid({0, 0}, {1, 1}, {1, 1}, "tri")}}}});
    const homogenize::Coarsening naive = homogenize::coarsening(s.scene, s.fine, "naive");
    const homogenize::Coarsening voigt = homogenize::coarsening(s.scene, s.fine, "voigt");
    // Triangle 0 of the square is y <= x, a quarter of it has x < 1/2; triangle 1 (y >= x) has
    // three quarters there.
    auto lame = [](double E, double nu) {
        return std::pair{E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))};
    };
    const auto [l1, m1] = lame(100.0, 0.3);
    const auto [l2, m2] = lame(1.0, 0.45);
    for (Index q = 0; q < 2; ++q) {
        const double f = q == 0 ? 0.25 : 0.75;
        const double l = f * l1 + (1 - f) * l2, mu = f * m1 + (1 - f) * m2;
        const double ls = 2 * l * mu / (l + 2 * mu);
        Matrix expected(3, 3);
        expected << ls + 2 * mu, ls, 0, ls, ls + 2 * mu, 0, 0, 0, 2 * mu;
        EXPECT_LT((naive.C[q].topLeftCorner(3, 3) - expected).norm(), 1e-12 * expected.norm());
        EXPECT_GT((naive.C[q] - voigt.C[q]).norm(), 1e-3 * expected.norm());
    }
}

TEST(Baselines, HomogeneousObjectGivesItsTensor) {
    const test::Setup s = half_and_half(iso(7.0, 0.2), iso(7.0, 0.2));
    const Matrix C = material::isotropic(3, 7.0, 0.2, 1.0).C;
    for (const char* method : {"naive", "voigt", "reuss"}) {
        const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, method);
        for (const Mandel6& Cq : c.C) EXPECT_LT((Cq - C).norm(), 1e-12 * C.norm()) << method;
    }
}

TEST(Baselines, NaiveNeedsIsotropicMaterials) {
    Matrix C = material::isotropic(3, 5.0, 0.3, 1.0).C;
    C(0, 1) = C(1, 0) = 1.0;
    json rows = json::array();
    for (Index i = 0; i < 6; ++i) {
        json row = json::array();
        for (Index j = 0; j < 6; ++j) row.push_back(C(i, j));
        rows.push_back(row);
    }
    const test::Setup s = half_and_half({{"C_mandel", rows}, {"density", 1.0}}, iso(1.0, 0.3));
    test::expect_error([&] { homogenize::coarsening(s.scene, s.fine, "naive"); },
                       "naive average: needs isotropic fine materials");
}

}  // namespace
}  // namespace coarsegrain
