/// @file examples/swinging_beam for half a period (30 of its 60 steps): the downswing.
#include <gtest/gtest.h>

#include "examples/example_test_util.hpp"

namespace coarsegrain::test {

// The accordion beam released under gravity 100 swings its tip down by 1.7, 43% of its length,
// corotated. The effective tensors follow the corotated fine swing (measured trajectory l2
// 0.16) where naive averaging, 180 times too stiff, hardly moves (0.997): at least 3 times
// closer. The hierarchy, stepped linear and RS-warped (0.015), and the linear fine model beside
// them (0.21) are reported.
TEST(ExamplesSlow, SwingingBeamEffectiveTensorsFollowTheCorotatedSwing) {
    const ExampleRun r = run_example(
        "swinging_beam", {{"dynamics", {{"steps", 30}, {"output_every", 3}}}},
        "effective-tensor,naive,mra-linear");
    ASSERT_EQ(r.summary.value("failed_methods", -1), 0);
    const double et = r.error("effective-tensor", "trajectory_l2_rel");
    const double naive = r.error("naive", "trajectory_l2_rel");
    EXPECT_LT(3 * et, naive);
    std::printf("  trajectory l2 against the corotated fine model: effective-tensor %.4f, naive "
                "%.4f, mra-linear + warp %.4f, linear fine %.4f\n",
                et, naive, r.error("mra-linear", "trajectory_l2_rel"),
                r.summary["fine"]["linear"]["errors"]["trajectory_l2_rel"].get<double>());
}

}  // namespace coarsegrain::test
