// examples/composite_fibres (Chen et al. 2019, Fig. 16, its second composite) at 32 x 32 cells:
// stiff inclined fibres in a soft matrix between stiff skins (contrast 1e6, clamped at the top,
// pulled down at the bottom) coarsened to one element, against the fine solve and the baselines
// on the same 4 coarse nodes.
#include "examples/example_test_util.hpp"

namespace coarsegrain::test {

TEST(ExamplesSlow, CompositeFibresStressOfTheSoftMatrixOnOneElement) {
    // 32 x 32 cells (the 64 x 64 image sampled at the cell centres: fibres 1.5 cells wide, skins
    // 2 cells thick), 6 levels down to one coarsest element.
    const ExampleRun r =
        run_example("composite_fibres",
                    {{"mesh", {{"grid", {{"cells", {32, 32}}}}}}, {"coarse", {{"levels", 6}}}});
    // Measured at 32 x 32 (64 x 64 in the README: the same to 2 digits). Dirac coarsest level:
    // energy error 0.0175, l2 3e-4, compliance ratio 0.9997; linear: energy error 0.264. The
    // bounds leave the same margins as composite_stress's.
    EXPECT_LT(r.error("mra-dirac", "energy_rel"), 0.025);
    EXPECT_NEAR(r.error("mra-dirac", "compliance_ratio"), 1.0, 1e-3);
    EXPECT_LT(r.error("mra-linear", "energy_rel"), 0.35);
    // The baselines are off by 32% (reuss) to 100% (naive, voigt) in l2, effective-tensor by
    // 64%; the Dirac coarse solve by 0.03%.
    EXPECT_LT(r.error("mra-dirac", "l2_rel"), 0.01 * stress_best_baseline_l2(r));
    // Fig. 16's claim, in the soft matrix (measured 4.0e-4 Dirac, 0.28 linear), and not in the
    // stiff phase (the whole square: 3.0 Dirac), as with the round particles.
    EXPECT_LT(stress_soft_error(r, "mra-dirac"), 0.005);
    EXPECT_LT(stress_soft_error(r, "mra-linear"), 0.4);
    EXPECT_GT(r.error("mra-dirac", "stress_rel"), 1.0);
}

}  // namespace coarsegrain::test
