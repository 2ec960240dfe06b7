// Coarse-to-fine maps: the barycentric embedding and the quasi-static harmonic map (Kharevych et
// al. 2009, Sec. 4.3, Eq. 9-10).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "coarsegrain/homogenize/coarse_maps.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "homogenize/homogenize_test_util.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using nlohmann::json;
using test::grid;
using test::iso;

/// A heterogeneous scene (stiff discs/balls in a soft matrix, contrast 100) and its coarsening.
homogenize::Coarsening spheres(int dim, test::Setup& s) {
    const std::vector<double> lo(dim, 0.0), hi(dim, 1.0), clo(dim, -0.1), chi(dim, 1.1);
    const json centres =
        dim == 3 ? json{{0.3, 0.3, 0.3}, {0.7, 0.6, 0.4}} : json{{0.3, 0.3}, {0.7, 0.6}};
    s = test::setup(
        {{"mesh", grid(lo, hi, std::vector<int>(dim, dim == 3 ? 6 : 12), dim == 3 ? "tet" : "tri")},
         {"material_field",
          {{"spheres", {{"centres", centres}, {"radius", 0.2}, {"inside", 2}, {"outside", 1}}}}},
         {"materials", {{"1", iso(1.0, 0.3)}, {"2", iso(100.0, 0.35)}}},
         {"coarse",
          {{"mesh", grid(clo, chi, std::vector<int>(dim, 2), dim == 3 ? "tet" : "tri")}}}});
    return homogenize::coarsening(s.scene, s.fine, "effective-tensor");
}

homogenize::HarmonicMap harmonic_map(const homogenize::Coarsening& c) {
    const mesh::PointLocator locator(c.coarse);
    std::vector<Index> carrier;
    for (const mesh::Location& l : homogenize::locate_points(locator, c.fine.rest_positions))
        carrier.push_back(l.element);
    return homogenize::HarmonicMap(c.coarse, c.H, c.fine.rest_positions, c.h, carrier);
}

class HarmonicMapDim : public ::testing::TestWithParam<int> {};

// Linearized map: a coarse displacement that samples a combination of harmonic displacements plus
// a rigid motion is carried to the fine mesh as exactly that fine displacement, detail included
// (the barycentric embedding only interpolates it).
TEST_P(HarmonicMapDim, LinearizedMapReproducesHarmonicFields) {
    const int dim = GetParam();
    test::Setup s;
    const homogenize::Coarsening c = spheres(dim, s);
    const SparseMatrix L = harmonic_map(c).linearized();
    const Matrix mapped = L * c.H;
    // 1e-10 relative: one small LU per coarse element (condition number ~1e3).
    EXPECT_LT((mapped - c.h).norm(), 1e-10 * c.h.norm());
    const Matrix rigid_coarse = test::rigid_modes(c.coarse.rest_positions);
    const Matrix rigid_fine = test::rigid_modes(c.fine.rest_positions);
    EXPECT_LT((L * rigid_coarse - rigid_fine).norm(), 1e-10 * rigid_fine.norm());
    // The barycentric embedding misses the fine detail of the same fields.
    const mesh::PointLocator locator(c.coarse);
    const SparseMatrix E = homogenize::barycentric_embedding(
        c.coarse, homogenize::locate_points(locator, c.fine.rest_positions));
    EXPECT_GT((E * c.H - c.h).norm(), 1e-3 * c.h.norm());
    EXPECT_EQ(L.cols(), c.coarse.num_dofs());
    EXPECT_EQ(L.rows(), c.fine.num_dofs());
}

// Eq. 9-10 with a finite rotation: coarse nodes placed at Q (X + H s) + t put every fine node at
// Q (x0 + h s) + t, with R = Q^T solving Eq. 9 exactly.
TEST_P(HarmonicMapDim, DeformedPositionsFollowRotatedHarmonicCombinations) {
    const int dim = GetParam(), n = mandel_size(dim);
    test::Setup s;
    const homogenize::Coarsening c = spheres(dim, s);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Eigen::VectorXd coef(n);
    for (int J = 0; J < n; ++J) coef[J] = U(rng);
    // Scale to a 10% strain of the soft material (E = 1 => h ~ 1 per unit stress).
    coef *= 0.1 / (c.h * coef).cwiseAbs().maxCoeff();
    Matrix Q = Matrix::Identity(dim, dim);
    const double t = 0.6;  // about 34 degrees
    if (dim == 2) {
        Q << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
    } else {
        const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 0.5).normalized();
        Q = Eigen::AngleAxisd(t, axis).toRotationMatrix();
    }
    const Eigen::VectorXd shift = Eigen::VectorXd::LinSpaced(dim, 0.3, -0.2);
    auto place = [&](const Matrix& X, const Matrix& H) {
        const Vector u = H * coef;
        Matrix x(X.rows(), dim);
        for (Index v = 0; v < X.rows(); ++v)
            x.row(v) = (Q * (X.row(v).transpose() + u.segment(dim * v, dim)) + shift).transpose();
        return x;
    };
    const Matrix x = harmonic_map(c).deformed_positions(place(c.coarse.rest_positions, c.H));
    const Matrix expected = place(c.fine.rest_positions, c.h);
    // Newton converged to 1e-14 of the element size; small LUs: 1e-10 of the object size.
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-10);
}

INSTANTIATE_TEST_SUITE_P(HarmonicMap, HarmonicMapDim, ::testing::Values(2, 3));

// A homogeneous body under an affine coarse deformation (rotation times a stretch): the fine
// nodes follow the same affine map, because h is linear.
TEST(HarmonicMap, AffineDeformationOfAHomogeneousBodyIsReproduced) {
    const test::Setup s =
        test::setup({{"mesh", grid({0, 0, 0}, {2, 1, 1}, {6, 3, 3}, "hex")},
                     {"materials", {{"0", iso(10.0, 0.25)}}},
                     {"coarse", {{"mesh", grid({0, 0, 0}, {2, 1, 1}, {2, 1, 1}, "tet")}}}});
    const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    Eigen::Matrix3d F;
    F << 1.1, 0.05, 0.0, 0.05, 0.95, 0.02, 0.0, 0.02, 1.2;  // symmetric stretch
    F = Eigen::AngleAxisd(1.0, Eigen::Vector3d(0, 0, 1)).toRotationMatrix() * F;
    const Matrix x = harmonic_map(c).deformed_positions(c.coarse.rest_positions * F.transpose());
    EXPECT_LT((x - c.fine.rest_positions * F.transpose()).cwiseAbs().maxCoeff(), 1e-10);
}

// The barycentric embedding reproduces fields that are linear on the coarse mesh, also at fine
// nodes on the coarse mesh's boundary.
TEST(HarmonicMap, BarycentricEmbeddingReproducesLinearFields) {
    const mesh::Mesh coarse = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d(0, 0),
                                              Eigen::Vector2d(3, 1), Eigen::Vector2i(3, 2));
    const mesh::Mesh fine = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d(0, 0),
                                            Eigen::Vector2d(3, 1), Eigen::Vector2i(17, 7));
    Matrix A(2, 2);
    A << 0.3, -0.2, 0.7, 0.1;
    const Eigen::Vector2d b(0.5, -1.0);
    const mesh::PointLocator locator(coarse);
    const SparseMatrix E = homogenize::barycentric_embedding(
        coarse, homogenize::locate_points(locator, fine.rest_positions));
    const Vector u = E * test::linear_field(coarse.rest_positions, A, b);
    EXPECT_LT((u - test::linear_field(fine.rest_positions, A, b)).cwiseAbs().maxCoeff(), 1e-13);
}

}  // namespace
}  // namespace coarsegrain
