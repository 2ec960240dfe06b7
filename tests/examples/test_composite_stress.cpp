// examples/composite_stress and examples/composite_fibres (Chen et al. 2019, Fig. 16: its two
// composites) at 32 x 32 cells: a bimaterial square (stiff particles, or stiff fibres inclined at
// 35 degrees, in a soft matrix between stiff skins, contrast 1e6, clamped at the top, pulled down
// at the bottom) coarsened to one element, against the fine solve and the baselines on the same
// 4 coarse nodes.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "examples/example_test_util.hpp"

namespace coarsegrain::test {
namespace {

/// Relative L2 error of the coarsest level's stress over the softest material (the elements of
/// the smallest E), from the method's coarsest_stress.csv (columns x, y, area, E, fine_xx,
/// fine_yy, fine_xy, fine_von_mises, coarse_xx, coarse_yy, coarse_xy, coarse_von_mises).
double stress_soft_error(const ExampleRun& r, const std::string& method) {
    std::ifstream in(r.out + "/" + method + "/coarsest_stress.csv");
    std::string line;
    std::getline(in, line);
    std::vector<std::vector<double>> rows;
    double E_min = 1e300;
    while (std::getline(in, line)) {
        std::vector<double> v;
        std::stringstream cells(line);
        for (std::string cell; std::getline(cells, cell, ',');) v.push_back(std::stod(cell));
        EXPECT_EQ(v.size(), 12u) << line;
        if (v.size() != 12u) return 1e300;
        E_min = std::min(E_min, v[3]);
        rows.push_back(v);
    }
    EXPECT_GT(rows.size(), 0u) << method << "/coarsest_stress.csv";
    double diff2 = 0, norm2 = 0;
    for (const std::vector<double>& v : rows) {
        if (v[3] != E_min) continue;
        const auto frobenius2 = [](double xx, double yy, double xy) {
            return xx * xx + yy * yy + 2 * xy * xy;
        };
        norm2 += v[2] * frobenius2(v[4], v[5], v[6]);
        diff2 += v[2] * frobenius2(v[8] - v[4], v[9] - v[5], v[10] - v[6]);
    }
    return norm2 > 0 ? std::sqrt(diff2 / norm2) : 1e300;
}

/// The smallest l2 error of the baselines on the same 4 coarse nodes (2 triangles).
double stress_best_baseline_l2(const ExampleRun& r) {
    double best = 1e300;
    for (const char* m : {"effective-tensor", "naive", "voigt", "reuss"})
        best = std::min(best, r.error(m, "l2_rel"));
    return best;
}

/// Runs a Fig. 16 example at 32 x 32 cells (the 64 x 64 image sampled at the cell centres),
/// 6 levels down to one coarsest element, and checks Fig. 16's claim with the same bounds for
/// both composites (measured values in the callers).
void expect_soft_matrix_stress_on_one_element(const std::string& example) {
    const ExampleRun r = run_example(
        example, {{"mesh", {{"grid", {{"cells", {32, 32}}}}}}, {"coarse", {{"levels", 6}}}});
    // Both hierarchies are Galerkin projections (compliance ratio 1 - energy_rel^2) whose error
    // falls level by level (nested spaces). 1e-7: a contrast of 1e6 on 32 x 32 cells makes
    // cond(K) ~1e9, and the identity's round-off measured up to 2.3e-9 (against ~1e-11 at
    // contrast 5e4).
    for (const char* mra : {"mra-dirac", "mra-linear"}) {
        expect_galerkin_projection(r, mra, 1e-7);
        expect_error_falls_with_level(r, mra);
    }
    // The coarse solves against every baseline on the same 4 nodes, in l2: Dirac far better
    // (measured 4e-4 and 3e-4 against at least 0.18), linear better too.
    const double best_baseline = stress_best_baseline_l2(r);
    EXPECT_LT(r.error("mra-dirac", "l2_rel"), 0.01 * best_baseline) << example;
    EXPECT_LT(r.error("mra-linear", "l2_rel"), best_baseline) << example;
    // Fig. 16's claim, in the soft matrix: the coarsest level's stress there is the fine one
    // (no visible difference in the paper's figure; asserted: 0.5% in L2).
    EXPECT_LT(stress_soft_error(r, "mra-dirac"), 0.005) << example;
    // Not in the stiff phase: there stress = 1e6 x a strain that is tiny in the fine solution,
    // so the small strain error of the coarse basis dominates the L2 stress error over the
    // whole square (stress_rel above 1, the READMEs' finding; not asserted).
}

}  // namespace

TEST(ExamplesSlow, CompositeStressOfTheSoftMatrixOnOneElement) {
    // Particles of radius 1.5 to 3.5 cells, skins 2 cells thick. Measured at 32 x 32 (64 x 64
    // in the README: the same to 2 digits). Dirac coarsest level: energy error 0.0179, l2 4e-4,
    // compliance ratio 0.9997; linear: energy error 0.266. Baselines off by 18%
    // (effective-tensor) to 100% (naive, voigt: the stiff skins make their 2 triangles rigid) in
    // l2. Soft-matrix stress 4e-4 Dirac, 0.29 linear; whole square 8.9 Dirac, 3.1 linear.
    expect_soft_matrix_stress_on_one_element("composite_stress");
}

TEST(ExamplesSlow, CompositeFibresStressOfTheSoftMatrixOnOneElement) {
    // Fibres 1.5 cells wide. Measured at 32 x 32: Dirac energy error 0.0175, l2 3e-4,
    // compliance ratio 0.9997; linear: energy error 0.264. Baselines off by 32% (reuss) to 100%
    // (naive, voigt) in l2, effective-tensor by 64%. Soft-matrix stress 4.0e-4 Dirac, 0.28
    // linear; whole square 3.0 Dirac.
    expect_soft_matrix_stress_on_one_element("composite_fibres");
}

}  // namespace coarsegrain::test
