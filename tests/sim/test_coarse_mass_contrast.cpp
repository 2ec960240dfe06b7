// Coarse masses against the fine model when only the density is heterogeneous, on the layered
// column of layered_column.hpp: one stiffness, so that every coarse model has the same stiffness
// PᵀKP and differs from the others by its mass alone. bench/bench_coarse_mass prints the measured
// table (docs/coarse-mass.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "coarsegrain/mesh/grid.hpp"
#include "sim/layered_column.hpp"

using namespace coarsegrain;
using test::DensityPattern;

namespace {

/// The `count` lowest eigenvalues ω² of a model.
Vector lowest_eigenvalues(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                          int count) {
    return sim::modes(K, M, bc, count).eigenvalues;
}

/// Relative frequency error of axial mode n (1-based) of the 1D fixed-free bar of linear elements
/// of length h (consistent or lumped mass) against the same bar of length-h_fine elements with
/// consistent mass: k = (2n - 1) π / 2L is the discrete wave number of both (the free end is a
/// symmetry point of sin(k x)), and ω h / c = sqrt(6 (1 - cos kh) / (2 + cos kh)) (consistent)
/// or 2 sin(kh / 2) (lumped).
double bar_error_1d(int n, double h, double h_fine, bool lumped) {
    const double k = (2 * n - 1) * std::numbers::pi / (2 * test::kColumnLength);
    const auto consistent = [k](double s) {
        return std::sqrt(6 * (1 - std::cos(k * s)) / (2 + std::cos(k * s))) / (k * s);
    };
    const double coarse = lumped ? 2 * std::sin(k * h / 2) / (k * h) : consistent(h);
    return coarse / consistent(h_fine) - 1;
}

/// Mean shift along the axis of the mass that the consistent coarse mass (each coarse triangle's
/// fine mass at its centroid) moves from where the fine mass is: sum over fine elements of
/// m_e (x_q - x_e) / total mass, q the coarse triangle holding e (the meshes are nested, so a
/// fine centroid's triangle holds the whole element).
double consistent_mass_shift(const scene::FineModel& fine) {
    const mesh::Mesh coarse = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d(0, 0),
                                              Eigen::Vector2d(test::kColumnLength, 1),
                                              Eigen::Vector2i(test::kColumnCoarseCells, 2));
    const Matrix fine_centres = mesh::element_centroids(fine.mesh);
    const Matrix coarse_centres = mesh::element_centroids(coarse);
    double moment = 0, total = 0;
    for (Index e = 0; e < fine.mesh.num_elements(); ++e) {
        Eigen::Matrix2d edges;
        const auto X = [&](Index v) { return fine.mesh.rest_positions.row(v).transpose(); };
        edges << X(fine.mesh.elements(e, 1)) - X(fine.mesh.elements(e, 0)),
            X(fine.mesh.elements(e, 2)) - X(fine.mesh.elements(e, 0));
        const double m = fine.materials.of(e).density * std::abs(edges.determinant()) / 2;
        const Eigen::Vector2d p = fine_centres.row(e).transpose();
        Index holder = -1;
        for (Index q = 0; q < coarse.num_elements() && holder < 0; ++q) {
            const Eigen::Vector2d a = coarse.rest_positions.row(coarse.elements(q, 0)).transpose();
            Eigen::Matrix2d T;
            T << coarse.rest_positions.row(coarse.elements(q, 1)).transpose() - a,
                coarse.rest_positions.row(coarse.elements(q, 2)).transpose() - a;
            const Eigen::Vector2d l = T.inverse() * (p - a);
            if (l.minCoeff() > -1e-12 && l.sum() < 1 + 1e-12) holder = q;
        }
        EXPECT_GE(holder, 0) << "fine element " << e;
        moment += m * (coarse_centres(holder, 0) - p[0]);
        total += m;
    }
    return moment / total;
}

/// The centred pattern within one coarse cell, ξ in [0, 1]: density `contrast` on [1/4, 3/4], 1
/// elsewhere; ρ' = ρ / ρ̄ its density over its mean, a = 2 / (1 + contrast) outside and
/// b = 2 contrast / (1 + contrast) inside.
///
/// 12 Var(R), R(ξ) = ∫_0^ξ ρ': the energy error of a mode's best linear approximation over the
/// cell against uniform density (R = ξ, 12 Var = 1), at the same wave number (Galerkin's error).
/// In a 1D bar with one stiffness, φ'' = -ω² ρ φ / E, so φ' departs from its cell mean by
/// ω² φ h R(ξ) / E up to a constant, and the linear interpolant (the Ritz projection in 1D) misses
/// its variance: 24 (1/16 - a/32 + a²/192 + b²/192).
double centred_variance_factor(double contrast) {
    const double a = 2 / (1 + contrast), b = 2 * contrast / (1 + contrast);
    return 24 * (1.0 / 16 - a / 32 + a * a / 192 + b * b / 192);
}

/// 6 ∫ ρ' ξ (1 - ξ): the inertia of relative nodal motion, ∫ρ N_a N_b (a - b)² of the kinetic
/// energy of a linear field, against uniform density. The Galerkin mass has all of it, the
/// consistent mass with the mean density 1 (uniform), the lumped mass none:
/// ∫ρ (N_a v_a + N_b v_b)² = v_a² ∫ρN_a + v_b² ∫ρN_b - (v_a - v_b)² ∫ρ N_a N_b, and the first two
/// terms are the same in all three (the pattern is symmetric in the cell).
double centred_relative_inertia(double contrast) {
    return (66 * contrast + 30) / (48 * (1 + contrast));
}

/// The largest |error| over the compared axial modes.
double worst_error(const test::ColumnStudy& s, const std::string& mass) {
    double worst = 0;
    for (std::size_t i = 0; i < s.fine_hz.size(); ++i)
        worst = std::max(worst, std::abs(s.error(mass, i)));
    return worst;
}

/// The smallest MAC of the pairs.
double smallest_mac(const test::ColumnStudy& s, const std::string& mass) {
    const std::vector<double>& mac = s.coarse.at(mass).mac;
    return *std::min_element(mac.begin(), mac.end());
}

}  // namespace

// With one stiffness and nested meshes the coarse stiffness is PᵀKP (the effective tensors and
// the naive average are the material's tensor, to the harmonic solves' 1e-13), so the Galerkin
// mass PᵀMP makes the coarse model the Rayleigh-Ritz approximation of the fine one on span P:
// every coarse eigenvalue is at least the fine one of the same index (Poincaré). The lumped mass
// Pᵀ(M 1) is the Galerkin mass with its rows summed onto the diagonal, and M_lumped - M_galerkin
// is positive semi-definite (P >= 0 and P 1 = 1: Σ N_a v_a² >= (Σ N_a v_a)²), so its eigenvalues
// are at most the Galerkin ones, index by index. Both bounds hold with density contrast 100 on the
// column (axial modes) and on the same bar without its lateral hold (bending modes first),
// to the eigensolver's 1e-10 (margin 1e-9). At contrast 1 the consistent mass of the coarse
// triangles is the Galerkin mass: the coarse hat functions are piecewise linear on the nested fine
// mesh, so P carries them exactly and PᵀMP = ∫ρ N_a N_b of the coarse hat functions (to 1e-12).
// Without the lateral hold the lowest mode bends, and the two coarse triangles across the bar
// are far too stiff in bending: its frequency is 33% high with every mass (measured +32.8%
// Galerkin, +32.5% lumped, +28.8% consistent; asserted above 25%). The stiffness error hides the
// mass's: the consistent mass comes out "best" only because its misplaced centre of mass (see
// ConsistentMassMovesMassOffCentreInsideCoarseCells) lowers the frequency by 4 points (asserted
// more than 2; lumped within 1 point of Galerkin).
TEST(CoarseMassContrast, NestedGalerkinModelIsARayleighRitzApproximation) {
    for (const bool held : {true, false}) {
        SCOPED_TRACE(held ? "laterally held" : "free sides");
        const auto scene_of = [](const char* mass) {
            return test::column_scene(DensityPattern::OffCentre, 100, mass);
        };
        const scene::FineModel fine = held ? test::column_fine_model(scene_of("galerkin"))
                                           : scene::build_fine_model(scene_of("galerkin"));
        const SparseMatrix M =
            fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
        const coarsen::CoarseModel galerkin =
            coarsen::build_coarse_model(scene_of("galerkin"), fine, "effective-tensor");
        const Index n = galerkin.K.rows();
        const Matrix P = galerkin.to_fine * Matrix(Matrix::Identity(n, n));
        const Matrix PKP = P.transpose() * Matrix(fine.K) * P;
        EXPECT_LT((Matrix(galerkin.K) - PKP).norm(), 1e-10 * PKP.norm());
        const coarsen::CoarseModel naive =
            coarsen::build_coarse_model(scene_of("galerkin"), fine, "naive");
        EXPECT_LT((Matrix(naive.K) - PKP).norm(), 1e-10 * PKP.norm());

        const coarsen::CoarseModel lumped =
            coarsen::build_coarse_model(scene_of("lumped"), fine, "effective-tensor");
        const int count = 12;
        const Vector lf = lowest_eigenvalues(fine.K, M, fine.bc, count);
        const Vector lg = lowest_eigenvalues(galerkin.K, galerkin.mass(M), galerkin.bc, count);
        const Vector ll = lowest_eigenvalues(lumped.K, lumped.mass(M), lumped.bc, count);
        for (Index i = 0; i < count; ++i) {
            EXPECT_GE(lg[i], lf[i] * (1 - 1e-9)) << "mode " << i;
            EXPECT_LE(ll[i], lg[i] * (1 + 1e-9)) << "mode " << i;
        }
        if (!held) {
            const coarsen::CoarseModel consistent =
                coarsen::build_coarse_model(scene_of("consistent"), fine, "effective-tensor");
            const Vector lc =
                lowest_eigenvalues(consistent.K, consistent.mass(M), consistent.bc, 1);
            const auto error = [&](const Vector& l) { return std::sqrt(l[0] / lf[0]) - 1; };
            for (const Vector* l : {&lg, &ll, &lc}) EXPECT_GT(error(*l), 0.25);
            EXPECT_NEAR(error(ll), error(lg), 0.01);
            EXPECT_LT(error(lc), error(lg) - 0.02);
        }
    }
    const scene::Scene uniform = test::column_scene(DensityPattern::Centred, 1, "consistent");
    const scene::FineModel fine = test::column_fine_model(uniform);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const Matrix consistent =
        Matrix(coarsen::build_coarse_model(uniform, fine, "effective-tensor").mass(M));
    const Matrix galerkin = Matrix(
        coarsen::build_coarse_model(test::column_scene(DensityPattern::Centred, 1, "galerkin"),
                                    fine, "effective-tensor")
            .mass(M));
    EXPECT_LT((consistent - galerkin).norm(), 1e-12 * galerkin.norm());
}

// The material-adapted hierarchy's coarsest level is Galerkin in both operators on the same basis
// (A^1 = Φ K Φᵀ, M^1 = Φ M Φᵀ, level by level through the C̃^k), so its eigenvalues are at least
// the fine ones of the same index (to the eigensolver's 1e-12, dense; margin 1e-9), here on
// layers with contrast 1000 in E and 100 in density, 0.375 thick against coarsest cells 0.5 long
// (so that the cells mix them), for both refinements.
TEST(CoarseMassContrast, HierarchyFrequenciesAreUpperBounds) {
    const scene::Scene sc = scene::parse_scene(
        {{"dimension", 2},
         {"mesh",
          {{"grid", {{"min", {0, 0}}, {"max", {4, 1}}, {"cells", {32, 8}}, {"element", "quad"}}}}},
         {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.375}, {"ids", {1, 2}}}}}},
         {"materials",
          {{"1", {{"E", 1000.0}, {"nu", 0.3}, {"density", 100.0}}},
           {"2", {{"E", 1.0}, {"nu", 0.4}, {"density", 1.0}}}}},
         {"dirichlet", {{{"box", {{"min", {-1e-9, -1}}, {"max", {1e-9, 2}}}}}}},
         {"coarse", {{"levels", 3}}}},
        "layers.json", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const int count = 12;
    const Vector lf = lowest_eigenvalues(fine.K, M, fine.bc, count);
    for (const char* method : {"mra-linear", "mra-dirac"}) {
        const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, method);
        const Vector lc = lowest_eigenvalues(c.K, c.mass(M), c.bc, count);
        for (Index i = 0; i < count; ++i)
            EXPECT_GE(lc[i], lf[i] * (1 - 1e-9)) << method << " mode " << i;
    }
}

// Control: at contrast 1 the density is uniform in every coarse element, the consistent mass is
// the Galerkin mass, and the errors are the coarse discretization's alone: those of the 1D bar of
// linear elements (+(kh)²/24 consistent, -(kh)²/24 lumped to leading order, h = 0.5 against the
// fine 0.125; 4e-4 to 3.4e-2 on axial modes 1-5). The 2D coarse modes are not exactly uniform
// over the section, and their frequencies come out lower than the 1D ones by 1.7% to 4.7% of the
// error on modes 1-3 and up to 10% on mode 5 (measured); asserted within 12%. The Galerkin and
// consistent frequencies agree to the dense eigensolver's round-off (1e-12; margin 1e-10).
TEST(CoarseMassContrast, UniformDensityGivesTheBarsDiscretizationError) {
    const test::ColumnStudy s = test::column_study(DensityPattern::Centred, 1);
    for (std::size_t i = 0; i < s.fine_hz.size(); ++i) {
        const int n = static_cast<int>(i) + 1;
        EXPECT_NEAR(s.coarse.at("consistent").hz[i], s.coarse.at("galerkin").hz[i],
                    1e-10 * s.fine_hz[i]);
        for (const bool lumped : {true, false}) {
            const double expected = bar_error_1d(n, 0.5, 0.125, lumped);
            EXPECT_NEAR(s.error(lumped ? "lumped" : "galerkin", i), expected,
                        0.12 * std::abs(expected))
                << "mode " << n << (lumped ? " lumped" : " galerkin");
        }
    }
    EXPECT_GT(smallest_mac(s, "lumped"), 0.99);
    EXPECT_GT(smallest_mac(s, "galerkin"), 0.99);
}

// Heavy layers in the first quarter of every coarse cell (towards the clamp). The Galerkin and
// lumped masses keep the fine first moments (P reproduces affine fields), the consistent mass
// puts each coarse triangle's mass at its centroid, a mean shift d towards the free end. To first
// order that adds 2d/L to the kinetic energy of every low mode (δT = Σ m d (φ²)' and
// ∫(φ²)' / ∫φ² = 2/L for the fixed-free bar), so the consistent frequencies are those of the
// Galerkin model times 1 - d/L: -1.082% at contrast 10 (d = 0.087) and -1.502% at 100
// (d = 0.120), measured -1.076% and -1.501% on axial mode 1; asserted within 3% of d/L (the
// neglected terms are of order (d/L)² and (kh)² of the shift). Meanwhile the lumped and Galerkin
// errors on mode 1 stay those of the control (measured 0.024% to 0.037% in magnitude; asserted
// below 0.1%, a tenth of the consistent mass's shift).
TEST(CoarseMassContrast, ConsistentMassMovesMassOffCentreInsideCoarseCells) {
    for (double contrast : {10.0, 100.0}) {
        SCOPED_TRACE(contrast);
        const test::ColumnStudy s = test::column_study(DensityPattern::OffCentre, contrast);
        const double d = consistent_mass_shift(test::column_fine_model(
            test::column_scene(DensityPattern::OffCentre, contrast, "lumped")));
        const double predicted = -d / test::kColumnLength;
        const double shift = s.coarse.at("consistent").hz[0] / s.coarse.at("galerkin").hz[0] - 1;
        EXPECT_NEAR(shift, predicted, 0.03 * std::abs(predicted));
        EXPECT_LT(std::abs(s.error("lumped", 0)), 1e-3);
        EXPECT_LT(std::abs(s.error("galerkin", 0)), 1e-3);
        EXPECT_GT(smallest_mac(s, "galerkin"), 0.99);
    }
}

// Heavy layers in the middle half of every coarse cell. Galerkin's error is the Rayleigh-Ritz
// error of the linear coarse space, and the modes' curvature now sits in the heavy layers: its
// error grows against the control by 12 Var(R) (centred_variance_factor: 1.781 at contrast 10,
// 1.975 at 100; measured 1.79-1.82 and 1.98-2.02 on modes 1-3, the deviation growing with kh;
// asserted within 4%). The lumped and consistent masses lack all, and (1 - 1/S) of, the inertia
// of relative nodal motion that Galerkin has (S = centred_relative_inertia, 1.307 and 1.368), so
// to first order e_lumped = e_galerkin + S (e_lumped - e_galerkin)|contrast 1 and
// e_consistent = e_galerkin + (S - 1) (same): measured within 0.04-2.4% of these on modes 1-3
// (asserted 4%). The lumped error, of the opposite sign, partly cancels Galerkin's: at contrast 100
// the lumped mass is the most accurate of the three on every mode 1-5 and Galerkin the least
// (measured on mode 5: -3.0%, +3.4%, +5.8%; the smallest margin, mode 2: 0.33% against 0.40%).
// All modes still pair: MAC >= 0.992 Galerkin, 0.990 lumped, 0.995 consistent (asserted 0.99 for
// Galerkin, 0.98 for the others).
TEST(CoarseMassContrast, MassCentredInCoarseCellsWidensTheGalerkinError) {
    const test::ColumnStudy u = test::column_study(DensityPattern::Centred, 1);
    for (double contrast : {10.0, 100.0}) {
        SCOPED_TRACE(contrast);
        const test::ColumnStudy s = test::column_study(DensityPattern::Centred, contrast);
        const double growth = centred_variance_factor(contrast);
        const double S = centred_relative_inertia(contrast);
        for (std::size_t i = 0; i < 3; ++i) {
            const double g = s.error("galerkin", i);
            const double lumping = u.error("lumped", i) - u.error("galerkin", i);
            EXPECT_NEAR(g / u.error("galerkin", i), growth, 0.04 * growth) << "mode " << i + 1;
            EXPECT_NEAR(s.error("lumped", i), g + S * lumping, 0.04 * std::abs(g + S * lumping))
                << "mode " << i + 1;
            EXPECT_NEAR(s.error("consistent", i), g + (S - 1) * lumping,
                        0.04 * std::abs(g + (S - 1) * lumping))
                << "mode " << i + 1;
        }
        EXPECT_GT(smallest_mac(s, "galerkin"), 0.99);
        for (const char* mass : {"lumped", "consistent"}) EXPECT_GT(smallest_mac(s, mass), 0.98);
        if (contrast == 100)
            for (std::size_t i = 0; i < s.fine_hz.size(); ++i) {
                EXPECT_LT(std::abs(s.error("lumped", i)), std::abs(s.error("consistent", i)))
                    << "mode " << i + 1;
                EXPECT_LT(s.error("consistent", i), s.error("galerkin", i)) << "mode " << i + 1;
            }
    }
}

// A heavy last layer (a tip mass inside the last coarse cell). Its own shear modes come among the
// axial ones, and each coarse mass places them differently; next to a misplaced one an axial mode
// of the coarse model mixes with it. Galerkin keeps axial modes 1-5 within 2.6% at both contrasts
// (measured at most +2.55%, MAC >= 0.997; asserted 3%, 0.99). At contrast 100 the lumped mass
// loses mode 4 (-12.5%, MAC 0.73) and the consistent mass mode 5 (+9.3%, MAC 0.74): asserted
// worst errors above 6% and MACs below 0.9. At contrast 10 both stay within 5% (measured at most
// 3.6% and 5.0%; asserted 6%), but the consistent model's mode 5 already mixes (MAC 0.81;
// asserted below 0.9). On the tip-mass mode 1 the consistent mass, which
// puts the layer's mass at the last triangles' centroids (towards the clamp), is too high by
// 0.88% where lumped and Galerkin are within 0.1% (asserted 0.5% and 0.2%).
TEST(CoarseMassContrast, HeavyTipSeparatesGalerkinFromLumpedAndConsistent) {
    for (double contrast : {10.0, 100.0}) {
        SCOPED_TRACE(contrast);
        const test::ColumnStudy s = test::column_study(DensityPattern::Tip, contrast);
        EXPECT_LT(worst_error(s, "galerkin"), 0.03);
        EXPECT_GT(smallest_mac(s, "galerkin"), 0.99);
        if (contrast == 10) {
            for (const char* mass : {"lumped", "consistent"})
                EXPECT_LT(worst_error(s, mass), 0.06) << mass;
            EXPECT_LT(smallest_mac(s, "consistent"), 0.9);
        }
        if (contrast == 100) {
            for (const char* mass : {"lumped", "consistent"}) {
                EXPECT_GT(worst_error(s, mass), 0.06) << mass;
                EXPECT_LT(smallest_mac(s, mass), 0.9) << mass;
            }
            EXPECT_GT(s.error("consistent", 0), 0.005);
            EXPECT_LT(std::abs(s.error("lumped", 0)), 0.002);
            EXPECT_LT(std::abs(s.error("galerkin", 0)), 0.002);
        }
    }
}
