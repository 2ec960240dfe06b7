// A large-deflection cantilever against CalculiX's geometrically nonlinear static solve
// (tests/data/calculix/cantilever_nlgeom.json, scripts/calculix/make_nlgeom_reference.py: 40x4x4
// C3D8 bricks, *STEP, NLGEOM, a total-Lagrangian St. Venant-Kirchhoff model, bending strains up
// to 2.7%, tip rotation 0.41 rad, axial shortening 5.3% of the length). Corotated linear
// elasticity is another model of the same physics: at these strains the two agree to the
// strain's order, so the tip's bending must agree within 3% and its axial shortening within 10%,
// which the linear model misses entirely.
#include <gtest/gtest.h>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "fem/calculix_reference.hpp"

using namespace coarsegrain;

namespace {

class CorotatedCalculixTest : public ::testing::TestWithParam<fem::CorotationFrame> {};

TEST_P(CorotatedCalculixTest, CantileverTipMatchesNlgeom) {
    const nlohmann::json ref = test::read_reference("cantilever_nlgeom");
    const mesh::Mesh m = test::reference_mesh(ref);
    const material::ElementMaterials mats = test::reference_materials(ref, m);
    const auto [f, bc] = test::reference_conditions(ref, m, mats);
    const Index tip = ref["probes"]["tip_centre"]["node"].get<Index>();
    ASSERT_LT((m.rest_positions.row(tip) - Eigen::RowVector3d(10, 0.25, 0.25)).norm(), 1e-12);

    // The same discrete linear problem as ccx's, to its printed digits.
    const Vector linear = test::solve_reference(ref, m, mats, fem::stiffness_matrix(m, mats));
    const Vector ccx_linear = test::ccx_displacements(ref, 3);
    EXPECT_LE((linear - ccx_linear).lpNorm<Eigen::Infinity>(),
              1e-6 * ccx_linear.lpNorm<Eigen::Infinity>());

    const fem::CorotatedModel model(m, mats, fem::Formulation::Standard, GetParam());
    sim::CorotationOptions o;
    o.frame = GetParam();
    const auto& factors = ref["load_factors"];
    for (const std::size_t i : {std::size_t{4}, factors.size() - 1}) {
        const double lambda = factors[i].get<double>();
        const sim::CorotatedSolution s = sim::solve_corotated_static(model, lambda * f, bc, o, {});
        const auto& nl = ref["nlgeom_displacements"][i][static_cast<std::size_t>(tip)];
        const double ux = nl[0].get<double>(), uz = nl[2].get<double>();
        const Eigen::Vector3d u = s.u.segment<3>(3 * tip);
        std::printf(
            "  load %.1f: tip (%.5f, %.5f) against ccx (%.5f, %.5f), linear uz %.5f; "
            "%d Newton iterations\n",
            lambda, u[0], u[2], ux, uz, lambda * linear[3 * tip + 2], s.report.iterations);
        EXPECT_NEAR(u[2], uz, 0.03 * std::abs(uz)) << "load factor " << lambda;
        EXPECT_NEAR(u[0], ux, 0.10 * std::abs(ux)) << "load factor " << lambda;
        // Linear elasticity: no shortening at all (Poisson's effects only, round-off here).
        EXPECT_LT(std::abs(linear[3 * tip]), 1e-3 * std::abs(ux));
    }
}

INSTANTIATE_TEST_SUITE_P(Frames, CorotatedCalculixTest,
                         ::testing::Values(fem::CorotationFrame::DeVeubeke,
                                           fem::CorotationFrame::Polar),
                         [](const ::testing::TestParamInfo<fem::CorotationFrame>& p) {
                             return fem::corotation_frame_name(p.param);
                         });

}  // namespace
