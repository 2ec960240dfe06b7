// Corotated statics (sim::solve_corotated_static): Newton's method reaches its stated residual,
// a prescribed rigid rotation of a clamped face turns the whole body rigidly (linear elasticity
// stretches it), and as the load goes to zero the corotated solution tends to the linear one at
// first order in the load.
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "sim/layered_bar.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

/// The fine model of the layered bar with its gravity scaled by `g` (E = 1 and 1000 layers).
scene::FineModel layered_bar_model(double g) {
    nlohmann::json j = test::layered_bar_json();
    j["loads"]["gravity"] = {0.0, -g};
    return scene::build_fine_model(scene::parse_scene(j, "bar.json", "."));
}

fem::CorotatedModel corotated(const scene::FineModel& m, fem::CorotationFrame frame) {
    return fem::CorotatedModel(m.mesh, m.materials, fem::Formulation::Standard, frame);
}

class CorotatedStaticTest : public ::testing::TestWithParam<fem::CorotationFrame> {};

TEST_P(CorotatedStaticTest, ConvergesToTheStatedResidual) {
    // Gravity 0.05 folds the bar's soft layers: its tip moves by 0.62, 31% of the length.
    const scene::FineModel m = layered_bar_model(0.05);
    const fem::CorotatedModel model = corotated(m, GetParam());
    sim::CorotationOptions o;
    o.frame = GetParam();
    const sim::CorotatedSolution sol = sim::solve_corotated_static(model, m.f, m.bc, o, {});
    // Recompute the residual independently of the solver's bookkeeping.
    const IndexVector free = fem::free_dofs(m.mesh.num_dofs(), m.bc);
    const double r0 =
        Vector((m.f - model.evaluate(Vector::Zero(m.mesh.num_dofs())).force)(free)).norm();
    const double r = Vector((m.f - model.evaluate(sol.u).force)(free)).norm();
    EXPECT_LE(r, o.tolerance * r0);
    EXPECT_NEAR(sol.report.residual, r / r0, 1e-12);
    EXPECT_LT(sol.report.round_off, o.tolerance);  // the tolerance decided, not round-off
    // Newton's method with the consistent Jacobian: quadratic convergence, a handful of
    // iterations per increment (measured: 6 in one increment).
    EXPECT_LE(sol.report.iterations, 12);
    for (const Index d : m.bc.dofs) EXPECT_EQ(sol.u[d], 0.0);
    // A large deflection: the linear model's differs by more than 5%.
    const Vector linear = fem::solve_static(m.K, m.f, m.bc, {});
    EXPECT_GT((sol.u - linear).norm(), 0.05 * linear.norm());
    std::printf("  %s: %d Newton iterations, %d increments, %d bisections, residual %.2e\n",
                fem::corotation_frame_name(GetParam()).c_str(), sol.report.iterations,
                sol.report.increments, sol.report.bisections, sol.report.residual);
}

TEST_P(CorotatedStaticTest, PrescribedRigidRotationTurnsTheBodyRigidly) {
    // Clamp the face x = 0 at the displacement of a rotation by 150 degrees about the origin;
    // without load the equilibrium is that rigid rotation of the whole bar (zero energy).
    const scene::FineModel m = layered_bar_model(0);
    const double angle = 150 * M_PI / 180;
    Matrix Q(2, 2);
    Q << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    fem::Dirichlet bc;
    Vector rigid(m.mesh.num_dofs());
    for (Index v = 0; v < m.mesh.num_nodes(); ++v) {
        const Eigen::VectorXd X = m.mesh.rest_positions.row(v).transpose();
        rigid.segment(2 * v, 2) = Q * X - X;
        if (X[0] < 1e-9) bc.fix_nodes({v}, rigid.segment(2 * v, 2));
    }
    const fem::CorotatedModel model = corotated(m, GetParam());
    sim::CorotationOptions o;
    o.frame = GetParam();
    o.tolerance = 1e-10;
    const sim::CorotatedSolution sol =
        sim::solve_corotated_static(model, Vector::Zero(m.mesh.num_dofs()), bc, o, {});
    // Newton stops at the force's round-off floor (4 ε |K||x - b|, the stiff layers' K), which
    // the soft layers' compliance (1000 times theirs) turns into a displacement error: measured
    // 2.0e-6 of the rotation's displacement.
    EXPECT_LE((sol.u - rigid).norm(), 1e-5 * rigid.norm());
    EXPECT_LE(sol.energy, 1e-12 * 0.5 * rigid.dot(m.K * rigid));
    // Linear elasticity answers the same clamp with a stretched, non-rigid body.
    const Vector linear = fem::solve_static(m.K, Vector::Zero(m.mesh.num_dofs()), bc, {});
    EXPECT_GT((linear - rigid).norm(), 0.1 * rigid.norm());
}

TEST_P(CorotatedStaticTest, TendsToTheLinearSolutionAsTheLoadVanishes) {
    // The first nonlinear term is quadratic in u: |u_cr - u_lin| / |u_lin| = O(load). (Gravity
    // 1e-2 sags the tip by 6% of the length, 1e-3 by 0.6%.)
    std::vector<double> loads = {1e-2, 1e-3}, difference;
    for (const double g : loads) {
        const scene::FineModel m = layered_bar_model(g);
        sim::CorotationOptions o;
        o.frame = GetParam();
        o.tolerance = 1e-11;
        const Vector u = sim::solve_corotated_static(corotated(m, GetParam()), m.f, m.bc, o, {}).u;
        const Vector linear = fem::solve_static(m.K, m.f, m.bc, {});
        difference.push_back((u - linear).norm() / linear.norm());
    }
    EXPECT_LT(difference[0], 0.05);
    // One decade of load, one decade of difference: first order (±20% in the exponent).
    EXPECT_NEAR(std::log10(difference[0] / difference[1]), 1.0, 0.2);
}

INSTANTIATE_TEST_SUITE_P(Frames, CorotatedStaticTest,
                         ::testing::Values(fem::CorotationFrame::DeVeubeke,
                                           fem::CorotationFrame::Polar),
                         [](const ::testing::TestParamInfo<fem::CorotationFrame>& p) {
                             return fem::corotation_frame_name(p.param);
                         });

TEST(CorotatedStatic, ReportsAnUnreachableToleranceWithTheLoadFactorReached) {
    const scene::FineModel m = layered_bar_model(0.05);
    sim::CorotationOptions o;
    o.max_iterations = 1;
    o.max_bisections = 1;
    o.tolerance = 1e-14;
    test::expect_error(
        [&] { sim::solve_corotated_static(corotated(m, o.frame), m.f, m.bc, o, {}); },
        "did not converge beyond load factor");
    o.tolerance = 0;
    test::expect_error(
        [&] { sim::solve_corotated_static(corotated(m, o.frame), m.f, m.bc, o, {}); },
        "corotation.tolerance");
}

}  // namespace
