// The fibre block (examples/fibre_block), a composite of the kind of Chen et al. 2019, Table 1,
// with twice the example's element size (about 4.6K fine DOFs; the same 512-tet coarse box):
// four stiff fibres (contrast 1e3) embedded in a soft block clamped at one end. The coarse box
// does not mesh them; the material-adapted hierarchy whose coarsest level is that box, through a
// middle box of half the element size, is compared with the effective tensors and the averages on
// the same coarse mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "examples/example_test_util.hpp"

namespace {

using nlohmann::json;

TEST(ExamplesSlow, FibreBlockHierarchyBeatsTheEffectiveTensorsOnOneCoarseMesh) {
    const coarsegrain::test::ExampleRun run =
        coarsegrain::test::run_example("fibre_block", json::object(), "all", 2.0);
    ASSERT_TRUE(run.summary.contains("methods")) << run.out;

    // Measured: mra-linear l2 0.0002, energy 0.0089, compliance ratio 0.9999; the effective
    // tensors 0.189, 8.27, 0.975; the averages no closer (naive and Voigt 0.954 in l2, Reuss
    // 0.509). The hierarchy's coarsest level spans a space of the coarse box's nodes adapted to
    // the fibres: it must beat every method on that box in every error, by an order of magnitude
    // in l2 (a margin of 50 below the measured ratio of about 900).
    for (const char* other : {"effective-tensor", "naive", "voigt", "reuss", "mra-dirac"}) {
        SCOPED_TRACE(other);
        EXPECT_LT(run.error("mra-linear", "l2_rel"), 0.1 * run.error(other, "l2_rel"));
        EXPECT_LT(run.error("mra-linear", "energy_rel"), run.error(other, "energy_rel"));
        EXPECT_LT(std::abs(run.error("mra-linear", "compliance_ratio") - 1),
                  std::abs(run.error(other, "compliance_ratio") - 1));
    }
    // Each level's solve is the Galerkin projection onto a space that contains the coarser
    // levels' (Eq. 4): the energy error falls from level to level.
    for (const char* method : {"mra-linear", "mra-dirac"}) {
        coarsegrain::test::expect_error_falls_with_level(run, method);
        coarsegrain::test::expect_galerkin_projection(run, method);
    }
}

}  // namespace
