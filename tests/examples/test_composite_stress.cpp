// examples/composite_stress (Chen et al. 2019, Fig. 16) at 32 x 32 cells: a bimaterial square
// (stiff particles in a soft matrix between stiff skins, contrast 1e6, clamped at the top,
// pulled down at the bottom) coarsened to one element, against the fine solve and the baselines
// on the same 4 coarse nodes.
#include "examples/example_test_util.hpp"

namespace coarsegrain::test {

TEST(ExamplesSlow, CompositeStressOfTheSoftMatrixOnOneElement) {
    // 32 x 32 cells (the 64 x 64 image sampled at the cell centres: particles of radius 1.5 to
    // 3.5 cells, skins 2 cells thick), 6 levels down to one coarsest element.
    const ExampleRun r =
        run_example("composite_stress",
                    {{"mesh", {{"grid", {{"cells", {32, 32}}}}}}, {"coarse", {{"levels", 6}}}});
    // Measured at 32 x 32 (64 x 64 in the README: the same to 2 digits). Dirac coarsest level:
    // energy error 0.0179, l2 4e-4, compliance ratio 0.9997; linear: energy error 0.266.
    EXPECT_LT(r.error("mra-dirac", "energy_rel"), 0.025);
    EXPECT_NEAR(r.error("mra-dirac", "compliance_ratio"), 1.0, 1e-3);
    EXPECT_LT(r.error("mra-linear", "energy_rel"), 0.35);
    // Every baseline is off by 18% (effective-tensor) to 100% (naive, voigt: the stiff skins
    // make their 2 triangles rigid) in l2; the Dirac coarse solve by 0.04%.
    EXPECT_LT(r.error("mra-dirac", "l2_rel"), 0.01 * stress_best_baseline_l2(r));
    // Fig. 16's claim, in the soft matrix: the coarsest level's stress there is the fine one
    // (measured 4e-4 Dirac, 0.29 linear).
    EXPECT_LT(stress_soft_error(r, "mra-dirac"), 0.005);
    EXPECT_LT(stress_soft_error(r, "mra-linear"), 0.4);
    // Not in the stiff phase: there stress = 1e6 x a strain that is tiny in the fine solution,
    // so the small strain error of the coarse basis dominates the L2 stress error over the
    // whole square (measured 8.9 Dirac, 3.1 linear). This documents the finding of the README.
    EXPECT_GT(r.error("mra-dirac", "stress_rel"), 1.0);
}

}  // namespace coarsegrain::test
