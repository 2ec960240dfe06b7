// Natural frequencies against closed forms, and the modal assurance criterion.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/sim/modes.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

/// A prismatic bar [0, L] x [0, 1]^2 of hexes, clamped at x = 0: K, M (consistent) and the clamp.
struct ClampedBar {
    mesh::Mesh mesh;
    SparseMatrix K, M;
    fem::Dirichlet bc;
};

ClampedBar clamped_bar(double L, int nx, int n, double E, double nu, fem::Formulation formulation) {
    ClampedBar b;
    b.mesh = mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                             Eigen::Vector3d(L, 1, 1), Eigen::Vector3i(nx, n, n));
    const material::ElementMaterials mats =
        material::uniform(b.mesh, material::isotropic(3, E, nu, 1.0));
    b.K = fem::stiffness_matrix(b.mesh, mats, formulation);
    b.M = fem::mass_matrix(b.mesh, mats, fem::MassType::Consistent);
    std::vector<Index> clamped;
    for (Index v = 0; v < b.mesh.num_nodes(); ++v)
        if (b.mesh.rest_positions(v, 0) < 1e-12) clamped.push_back(v);
    b.bc.fix_nodes(clamped, Eigen::Vector3d::Zero());
    return b;
}

/// Frequencies of the modes that move along x only (|u_y|, |u_z| round-off): the axial ones.
std::vector<double> axial_frequencies(const sim::Modes& m) {
    std::vector<double> f;
    for (Index j = 0; j < m.vectors.cols(); ++j) {
        double lateral = 0;
        for (Index i = 0; i < m.vectors.rows(); ++i)
            if (i % 3 != 0) lateral = std::max(lateral, std::abs(m.vectors(i, j)));
        if (lateral < 1e-8 * m.vectors.col(j).lpNorm<Eigen::Infinity>())
            f.push_back(m.frequencies_hz[j]);
    }
    return f;
}

}  // namespace

// A fixed-free bar with nu = 0 vibrates axially at f_n = (2n - 1) c / (4L), c = sqrt(E / rho):
// with nu = 0 a field u_x(x) has no lateral stress, so the discrete axial modes are those of the
// 1D bar of linear elements with consistent mass, whose frequency is f_n (1 + (k h)² / 24 +
// O(h⁴)) with k = (2n - 1) π / 2L. Asserted: the first two axial frequencies converge with a
// fitted order within 0.1 of 2 over nx = 8..64, and at nx = 64 their error is that leading term
// to 2% of itself (2.5e-5 and 2.3e-4).
TEST(Modes, AxialFrequenciesOfAFixedFreeBar) {
    const double L = 8, E = 3.0;
    const double c = std::sqrt(E);
    std::vector<double> h, err1, err2;
    for (int nx : {8, 16, 32, 64}) {
        const ClampedBar b = clamped_bar(L, nx, 1, E, 0.0, fem::Formulation::Standard);
        const std::vector<double> f = axial_frequencies(sim::modes(b.K, b.M, b.bc, 24));
        ASSERT_GE(f.size(), 2u) << "nx " << nx;
        const double exact1 = c / (4 * L), exact2 = 3 * c / (4 * L);
        h.push_back(L / nx);
        err1.push_back(std::abs(f[0] - exact1) / exact1);
        err2.push_back(std::abs(f[1] - exact2) / exact2);
    }
    EXPECT_NEAR(test::fitted_slope(h, err1), 2.0, 0.1);
    EXPECT_NEAR(test::fitted_slope(h, err2), 2.0, 0.1);
    for (const auto& [n, err] : {std::pair{1, err1.back()}, std::pair{3, err2.back()}}) {
        const double kh = n * std::numbers::pi / (2 * L) * h.back();
        EXPECT_NEAR(err, kh * kh / 24, 0.02 * kh * kh / 24) << "mode 2n - 1 = " << n;
    }
}

// The first bending frequency of a slender cantilever (L / h = 20, nu = 0) against
// Euler-Bernoulli's f = β² / (2π) sqrt(E I / (ρ A L⁴)), β = 1.8751, I = h⁴/12, A = h². The
// incompatible-mode hex bends without shear locking, and the frequency converges at second order
// (measured differences between successive meshes, nx = 10..80: -9.0e-4, -2.3e-4, -5.7e-5 of
// f). It converges to a value below Euler-Bernoulli's by Timoshenko's shear and rotary inertia,
// about (1/2) β² (r/L)² (1 + E / (κ G)) = 0.12% (r² = I / A, κ = 5/6); measured, Richardson
// extrapolated: -0.145%. Asserted: fitted order of the differences >= 1.8, the extrapolated
// frequency below Euler-Bernoulli's by less than 0.3%. The square section's two bending
// frequencies are equal (1e-8).
TEST(Modes, CantileverBendingTendsToEulerBernoulli) {
    const double L = 20, E = 1000.0;
    const double beta = 1.87510407, I = 1.0 / 12, A = 1.0;
    const double exact =
        beta * beta / (2 * std::numbers::pi) * std::sqrt(E * I / (A * std::pow(L, 4)));
    std::vector<double> f;
    for (int nx : {10, 20, 40, 80}) {
        const ClampedBar b = clamped_bar(L, nx, 2, E, 0.0, fem::Formulation::Incompatible);
        const sim::Modes m = sim::modes(b.K, b.M, b.bc, 2);
        EXPECT_NEAR(m.frequencies_hz[1], m.frequencies_hz[0], 1e-8 * m.frequencies_hz[0]);
        f.push_back(m.frequencies_hz[0]);
    }
    const std::vector<double> h = {L / 20, L / 40, L / 80};  // the finer mesh of each pair
    const std::vector<double> d = {std::abs(f[1] - f[0]), std::abs(f[2] - f[1]),
                                   std::abs(f[3] - f[2])};
    EXPECT_GE(test::fitted_slope(h, d), 1.8);
    const double extrapolated = f[3] + (f[3] - f[2]) / 3;  // Richardson, order 2
    const double error = (extrapolated - exact) / exact;
    RecordProperty("extrapolated_error", std::to_string(error));
    EXPECT_LT(error, 0.0);
    EXPECT_GT(error, -3e-3);
}

// MAC: 1 for parallel shapes whatever their scale and sign, 0 for orthogonal ones; the pairing
// takes the candidate of largest MAC for each reference column.
TEST(Modes, MacPairsParallelShapes) {
    Matrix ref(4, 2), cand(4, 3);
    ref << 1, 0, 2, 0, 0, 1, 0, 1;
    cand << 0, -3, 1, 0, -6, 0, 5, 0, 0, 5, 0, 0;
    EXPECT_NEAR(sim::mac(ref.col(0), cand.col(1)), 1.0, 1e-15);
    EXPECT_NEAR(sim::mac(ref.col(0), cand.col(0)), 0.0, 1e-15);
    const std::vector<sim::ModePair> p = sim::pair_modes(ref, cand);
    EXPECT_EQ(p[0].coarse, 1);
    EXPECT_EQ(p[1].coarse, 0);
    EXPECT_NEAR(p[1].mac, 1.0, 1e-15);
    test::expect_error([] { sim::mac(Vector::Zero(3), Vector::Ones(3)); }, "zero vector");
}
