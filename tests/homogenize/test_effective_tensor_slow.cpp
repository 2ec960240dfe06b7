// Heavier effective-tensor scenes (Kharevych et al. 2009, Sec. 5 and Fig. 4-5): the accordion
// beam, the cracked bar, laminates against the exact (Backus) laminate tensor, and a layered
// cube whose layers are parallel to the clamped face (where the method can lose to Reuss).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "homogenize/homogenize_test_util.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using nlohmann::json;
using test::box;
using test::grid;
using test::iso;

const std::vector<std::string> kMethods = {"effective-tensor", "naive", "voigt", "reuss"};

/// Every method's figures on a scene (printed), by method name.
std::map<std::string, test::Comparison> compare_methods(const test::Setup& s, const char* title) {
    const Vector u = scene::solve_static(s.fine, {}).u;
    std::map<std::string, test::Comparison> out;
    std::printf("%s\n  %-17s %10s %12s\n", title, "method", "l2_rel", "compliance");
    for (const std::string& m : kMethods) {
        out[m] = test::compare(s.fine, u, homogenize::build_coarse_model(s.scene, s.fine, m));
        std::printf("  %-17s %10.4f %12.4f\n", m.c_str(), out[m].l2_rel, out[m].compliance_ratio);
    }
    // Voigt >= Reuss on every element (arithmetic against harmonic mean of SPD tensors), so
    // K_voigt >= K_reuss on the same coarse mesh, load and conditions, and the coarse
    // compliance f_c.K^{-1} f_c of Voigt is at most Reuss's (1e-12: round-off).
    EXPECT_LE(out["voigt"].coarse_compliance, out["reuss"].coarse_compliance * (1 + 1e-12))
        << title;
    // Isotropic materials in 3D: naive = Voigt (the tensor is linear in lambda, mu); 1e-9: the
    // same coarse system up to the round-off of the averages and solves.
    EXPECT_NEAR(out["naive"].coarse_compliance, out["voigt"].coarse_compliance,
                1e-9 * out["voigt"].coarse_compliance)
        << title;
    return out;
}

// Fig. 5, the accordion: a 4x1x1 beam of layers across its axis (E = 1e5 / 1e2, contrast 1000),
// clamped at x = 0 and hanging under gravity, on a coarse mesh of 8 x 3 x 3 cells (3 across the
// thickness). Measured: effective-tensor l2 0.094, compliance 0.969; naive and Voigt l2 0.995,
// compliance 0.005 (Lamé averaging equals Voigt for isotropic layers in 3D); Reuss l2 0.48.
TEST(EffectiveTensorSlow, AccordionBeam) {
    const test::Setup s = test::setup(
        {{"mesh", grid({0, 0, 0}, {4, 1, 1}, {32, 8, 8}, "hex")},
         {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.25}, {"ids", {1, 2}}}}}},
         {"materials", {{"1", iso(1e5, 0.3)}, {"2", iso(1e2, 0.45)}}},
         {"dirichlet", json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})})},
         {"loads", {{"gravity", {0, 0, -9.81}}}},
         {"coarse", {{"mesh", grid({0, 0, 0}, {4, 1, 1}, {8, 3, 3}, "tet")}}}});
    auto r = compare_methods(s, "accordion beam (contrast 1000, 8x3x3 coarse cells)");
    EXPECT_LT(3 * r["effective-tensor"].l2_rel, r["naive"].l2_rel);
    EXPECT_LT(3 * r["effective-tensor"].l2_rel, r["voigt"].l2_rel);
    EXPECT_NEAR(r["effective-tensor"].compliance_ratio, 1.0, 0.15);
    EXPECT_LT(r["naive"].compliance_ratio, 0.1);
}

// Fig. 4, a crack: a 4x1 bar (E = 1e4) cut from below by a thin slice of soft material (E = 1,
// 1/16 wide, 0.8 deep, between x = 1.97 and 2.03), clamped at x = 0 under gravity, on 3 x 1
// coarse cells whose nodes are far from the slice. The fine bar bends at the slice; the
// effective tensors carry it (measured tip deflection 0.87 of the fine one), averages do not
// (0.05). Reuss overshoots (3.3x): it spreads the soft slice's compliance over the whole cell.
TEST(EffectiveTensorSlow, CrackedBarBendsOnACoarseMesh) {
    scene::Scene sc =
        scene::parse_scene({{"mesh", grid({0, 0}, {4, 1}, {128, 32}, "quad")},
                            {"materials", {{"1", iso(1e4, 0.3)}, {"2", iso(1.0, 0.3)}}},
                            {"dirichlet", json::array({box({-1e-9, -1}, {1e-9, 2})})},
                            {"loads", {{"gravity", {0, -9.81}}}},
                            {"coarse", {{"mesh", grid({0, 0}, {4, 1}, {3, 1}, "tri")}}}},
                           "crack.json", "");
    const Matrix centres = mesh::element_centroids(sc.mesh);
    for (Index e = 0; e < sc.mesh.num_elements(); ++e)
        sc.mesh.material_ids[e] =
            std::abs(centres(e, 0) - 2.0) < 1.0 / 32 && centres(e, 1) < 0.8 ? 2 : 1;
    const scene::FineModel fine = scene::build_fine_model(sc);
    const Vector u = scene::solve_static(fine, {}).u;
    const Index tip = fine.mesh.num_nodes() - 1;  // corner (4, 1)
    std::printf("cracked bar: tip deflection / fine\n");
    std::map<std::string, double> ratio;
    for (const std::string& m : kMethods) {
        const coarsen::CoarseModel model = homogenize::build_coarse_model(sc, fine, m);
        const Vector uc = model.to_fine * test::solve_coarse(model);
        ratio[m] = uc[2 * tip + 1] / u[2 * tip + 1];
        std::printf("  %-17s %8.3f\n", m.c_str(), ratio[m]);
    }
    EXPECT_NEAR(ratio["effective-tensor"], 1.0, 0.3);
    EXPECT_LT(ratio["naive"], 0.2);
    EXPECT_LT(ratio["voigt"], 0.2);
}

/// Exact tensor of a laminate with layers normal to z in equal fractions (Backus averaging in
/// Mandel form): with I = (xx, yy, xy) and O = (zz, yz, xz), C*_OO = <C_OO^{-1}>^{-1},
/// C*_OI = C*_OO <C_OO^{-1} C_OI>, C*_II = <C_II - C_IO C_OO^{-1} C_OI> + <C_IO C_OO^{-1}>
/// C*_OO <C_OO^{-1} C_OI>.
Matrix laminate_tensor(const Matrix& C1, const Matrix& C2) {
    const std::array<int, 3> I = {0, 1, 5}, O = {2, 3, 4};
    auto block = [](const Matrix& C, const std::array<int, 3>& r, const std::array<int, 3>& c) {
        Matrix B(3, 3);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) B(i, j) = C(r[i], c[j]);
        return B;
    };
    auto mean = [](const Matrix& a, const Matrix& b) { return Matrix(0.5 * (a + b)); };
    const Matrix S1 = block(C1, O, O).inverse(), S2 = block(C2, O, O).inverse();
    const Matrix OO = mean(S1, S2).inverse();
    const Matrix a = mean(S1 * block(C1, O, I), S2 * block(C2, O, I));
    const Matrix b = mean(block(C1, I, O) * S1, block(C2, I, O) * S2);
    const Matrix II = mean(block(C1, I, I) - block(C1, I, O) * S1 * block(C1, O, I),
                           block(C2, I, I) - block(C2, I, O) * S2 * block(C2, O, I)) +
                      b * OO * a;
    const Matrix OI = OO * a;
    Matrix C(6, 6);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            C(I[i], I[j]) = II(i, j);
            C(O[i], O[j]) = OO(i, j);
            C(O[i], I[j]) = C(I[j], O[i]) = OI(i, j);
        }
    return C;
}

/// Relative deviation from the Backus tensor of the interior coarse cell of a laminate.
struct LaminateDeviation {
    double out_of_plane;  ///< worst entry of the zz/yz/xz block over that block's norm
    double in_plane;      ///< worst entry of the xx/yy/xy block over that block's norm
    double worst_tet;     ///< worst single tet, |C_q - B| / |B|
};

/// Layers normal to z (E = contrast, nu 0.3 / E = 1, nu2; 1 fine cell per layer) on an
/// n x n x 3 box, coarse cells of 1x1x1 spanning `periods` layer periods; the volume average of
/// the 6 tets of the centre cell (middle of x, y and z) against the exact laminate tensor.
LaminateDeviation laminate_deviation(int n, int periods, double contrast, double nu2) {
    const test::Setup s = test::setup(
        {{"mesh", grid({0, 0, 0}, {1.0 * n, 1.0 * n, 3}, {4 * n, 4 * n, 6 * periods}, "tet")},
         {"material_field",
          {{"layers", {{"axis", "z"}, {"thickness", 0.5 / periods}, {"ids", {1, 2}}}}}},
         {"materials", {{"1", iso(contrast, 0.3)}, {"2", iso(1.0, nu2)}}},
         {"coarse", {{"mesh", grid({0, 0, 0}, {1.0 * n, 1.0 * n, 3}, {n, n, 3}, "tet")}}}});
    const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    const Matrix B = laminate_tensor(material::isotropic(3, contrast, 0.3, 1.0).C,
                                     material::isotropic(3, 1.0, nu2, 1.0).C);
    const Index cell = n / 2 + n * (n / 2 + n * 1);
    Matrix avg = Matrix::Zero(6, 6);
    LaminateDeviation d{0, 0, 0};
    for (Index q = 6 * cell; q < 6 * cell + 6; ++q) {
        avg += c.coarse_measures[q] * c.C[q];
        d.worst_tet = std::max(d.worst_tet, (c.C[q] - B).norm() / B.norm());
    }
    avg /= c.coarse_measures.segment(6 * cell, 6).sum();
    const std::array<int, 3> O = {2, 3, 4}, I = {0, 1, 5};
    Matrix B_OO(3, 3), B_II(3, 3);
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            d.out_of_plane = std::max(d.out_of_plane, std::abs(avg(O[a], O[b]) - B(O[a], O[b])));
            d.in_plane = std::max(d.in_plane, std::abs(avg(I[a], I[b]) - B(I[a], I[b])));
            B_OO(a, b) = B(O[a], O[b]);
            B_II(a, b) = B(I[a], I[b]);
        }
    d.out_of_plane /= B_OO.norm();
    d.in_plane /= B_II.norm();
    return d;
}

// Laminates: layers normal to z on a 3x3x3 box, coarse cells of 1x1x1 spanning 1, 2 or 4 layer
// periods. For the interior coarse cell, the volume average of its 6 tets' effective tensors has
// the out-of-plane block (C_zzzz, C_yzyz, C_xzxz and their couplings) of the exact laminate
// tensor. Measured: 2e-14 to 6e-12 relative (to the out-of-plane block, growing with the
// contrast like the round-off of the fine solve) for layers whose tensors are proportional
// (equal Poisson ratios), for every contrast and period count, hence the bound 1e-8; with
// different Poisson ratios (0.3 / 0.45, printed here, see the next test) the same entries
// deviate by 2e-3 to 1e-2. The in-plane entries (6e-3 to 0.2) and the individual tets (0.15 to
// 1) deviate more.
TEST(EffectiveTensorSlow, LaminateOutOfPlaneEntriesAreExact) {
    std::printf("laminate, interior coarse cell: relative deviation from the Backus tensor\n");
    std::printf("  %8s %6s %6s %12s %12s %12s\n", "contrast", "nu2", "periods", "out-of-plane",
                "in-plane", "worst tet");
    for (const double contrast : {10.0, 100.0, 1000.0})
        for (const double nu2 : {0.3, 0.45})
            for (const int periods : {1, 2, 4}) {
                if (nu2 != 0.3 && contrast != 100.0) continue;
                const LaminateDeviation d = laminate_deviation(3, periods, contrast, nu2);
                std::printf("  %8g %6.2f %6d %12.2e %12.2e %12.2e\n", contrast, nu2, periods,
                            d.out_of_plane, d.in_plane, d.worst_tet);
                if (nu2 == 0.3) {
                    EXPECT_LT(d.out_of_plane, 1e-8)
                        << "contrast " << contrast << ", " << periods << " periods";
                }
            }
}

// Why the Poisson ratios matter. With proportional layer tensors C(z) = s(z) C0, the strain
// ε = C(z)^-1 Σ of a uniform stress Σ = C0 ε0 with ε0 out-of-plane (zero xx, yy, xy) is
// s(z)^-1 ε0: it varies with z alone and has no in-plane part, so it is compatible, and P1
// tets aligned with the layers represent it exactly. The harmonic displacements of the
// out-of-plane stresses are then the laminate's own fields in the whole finite box, and Eq. 8
// reproduces the out-of-plane block exactly. With different Poisson ratios the laminate field
// needs in-plane stresses that alternate from layer to layer, which the traction-free (in-plane)
// lateral faces of the box do not allow: a boundary layer that reaches the interior cell and
// decays as the box grows laterally. Measured (contrast 100, nu2 0.45, 1 period per cell):
// 9.8e-3, 7.2e-3, 4.2e-3 on 3x3, 5x5, 7x7 boxes.
TEST(EffectiveTensorSlow, LaminateOutOfPlaneDeviationIsALateralBoundaryEffect) {
    const double d3 = laminate_deviation(3, 1, 100.0, 0.45).out_of_plane;
    const double d7 = laminate_deviation(7, 1, 100.0, 0.45).out_of_plane;
    std::printf("laminate, nu2 0.45: out-of-plane deviation %.2e (3x3 box), %.2e (7x7 box)\n", d3,
                d7);
    EXPECT_GT(d3, 1e-3);  // not round-off: a real deviation
    EXPECT_LT(d7, 0.6 * d3);
}

/// The layered unit cube: layers normal to x (E = 1e5 / 1e2, nu = 0.3 / 0.45) of the given
/// thickness, 16^3 hexes, clamped at x = 0 (parallel to the layers) under gravity along -z, on
/// n^3 coarse cells of 6 tets.
test::Setup layered_cube(double thickness, int n) {
    return test::setup({{"mesh", grid({0, 0, 0}, {1, 1, 1}, {16, 16, 16}, "hex")},
                        {"material_field",
                         {{"layers", {{"axis", "x"}, {"thickness", thickness}, {"ids", {1, 2}}}}}},
                        {"materials", {{"1", iso(1e5, 0.3)}, {"2", iso(1e2, 0.45)}}},
                        {"dirichlet", json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})})},
                        {"loads", {{"gravity", {0, 0, -9.81}}}},
                        {"coarse", {{"mesh", grid({0, 0, 0}, {1, 1, 1}, {n, n, n}, "tet")}}}});
}

// A layered cube with the layers parallel to its clamped face: every method, on three coarse
// meshes. On 3^3 cells of 1/8-thick layers the effective tensors are best (measured l2 0.095,
// compliance 0.991; Reuss 0.129 / 0.947; naive = Voigt 0.9955 / 0.0045). On 1^3 and 2^3 cells
// of 1/4-thick layers they are too soft and the Reuss average wins (measured effective-tensor
// l2 0.47 / 0.56, compliance 1.44 / 1.65; Reuss l2 0.23 / 0.37). The coarse tets of a cell hold
// the two materials in different proportions, so Eq. 8 gives them strongly different tensors,
// and how the coarse solve combines them (not like a volume average) decides the result, as in
// SpringsInSeriesGiveTheSeriesStiffness on a single cell; the directional Young's modulus of a
// single tet exceeds the stiffest layer's 50-fold. A limitation of the method, documented
// in docs/guide.md from the table this test prints; it is not asserted (an improvement of the
// method must not fail the test). Asserted: every tensor is positive definite (Eq. 8 of an SPD
// fine tensor with an invertible mollifier), the effective tensors win on the finer layers
// (and, in compare_methods, the Voigt model is stiffer than the Reuss one).
TEST(EffectiveTensorSlow, LayeredCubeParallelToTheClampedFace) {
    struct Case {
        double thickness;
        int cells;
    };
    std::map<std::pair<double, int>, std::map<std::string, test::Comparison>> r;
    for (const Case k : {Case{0.125, 3}, Case{0.25, 1}, Case{0.25, 2}}) {
        const test::Setup s = layered_cube(k.thickness, k.cells);
        const std::string title =
            fmt::format("layered cube, layers {} thick parallel to the clamped face, {}^3 cells",
                        k.thickness, k.cells);
        r[{k.thickness, k.cells}] = compare_methods(s, title.c_str());
        const homogenize::Coarsening c =
            homogenize::coarsening(s.scene, s.fine, "effective-tensor");
        double E_z = 0;
        for (const Mandel6& C : c.C) {
            const Matrix C6 = C.topLeftCorner(6, 6);
            const Eigen::SelfAdjointEigenSolver<Matrix> eig(C6);
            EXPECT_GT(eig.eigenvalues()[0], 0.0);
            E_z = std::max(E_z, material::directional_young(C6, Eigen::Vector3d(0, 0, 1)));
        }
        // A single coarse tet can be far stiffer along z than the stiffest layer (E = 1e5):
        // measured 5.4e6 (1/8 layers, 3^3 cells), 2.4e7 (1^3), 3.8e7 (2^3).
        std::printf("  largest E_z of a coarse tet %.3g\n", E_z);
    }
    auto& fine_layers = r[{0.125, 3}];
    for (const char* m : {"naive", "voigt", "reuss"})
        EXPECT_LT(fine_layers["effective-tensor"].l2_rel, fine_layers[m].l2_rel) << m;
    EXPECT_NEAR(fine_layers["effective-tensor"].compliance_ratio, 1.0, 0.05);
}

}  // namespace
}  // namespace coarsegrain
