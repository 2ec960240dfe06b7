// Corotated elastodynamics (sim::CorotatedStepper): every step satisfies the integrator's
// discrete equations, midpoint converges at second order and implicit Euler at first, small
// loads give the linear trajectory at first order in the load, a spinning free body stays rigid
// (the linear model balloons), and the energy: implicit Euler dissipates it, midpoint's drift.
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/sim/corotational.hpp"
#include "sim/swinging_bar.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

fem::CorotatedModel corotated_bar(const test::SwingingBar& b) {
    return fem::CorotatedModel(b.mesh, b.mats, fem::Formulation::Standard,
                               fem::CorotationFrame::DeVeubeke);
}

sim::DynamicsOptions step_options(sim::Integrator integrator, double dt, int steps) {
    sim::DynamicsOptions o;
    o.integrator = integrator;
    o.dt = dt;
    o.steps = steps;
    o.output_every = steps;
    return o;
}

/// The corotated trajectory of the bar from rest under its load.
sim::Trajectory swing(const test::SwingingBar& b, const fem::CorotatedModel& model,
                      const sim::DynamicsOptions& o, const sim::CorotationOptions& c = {}) {
    const auto [start, f] = sim::corotated_initial_state(model, b.f, b.bc, Vector(), o, c);
    return sim::simulate_corotated(model, b.M, b.bc, start, f, o, c);
}

class CorotatedDynamicsTest : public ::testing::TestWithParam<sim::Integrator> {};

TEST_P(CorotatedDynamicsTest, EveryStepSatisfiesTheDiscreteEquations) {
    // Recompute each step's equation from the states alone:
    //   midpoint:  M (v' - v)/dt + f_int((u + u')/2) + C (v + v')/2 = f, u' = u + dt/2 (v + v')
    //   Euler:     M (v' - v)/dt + f_int(u') + C v' = f,                 u' = u + dt v'
    // with C = α M + β K_R(u), relative to the step's force scale max(|f - f_int(u) + c M v|,
    // |f_int(u)|) (c = 2/dt midpoint, 1/dt Euler: the residual at the step's start).
    const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, 1.0);
    const fem::CorotatedModel model = corotated_bar(b);
    sim::DynamicsOptions o = step_options(GetParam(), 0.05, 1);
    o.rayleigh_mass = 0.1;
    o.rayleigh_stiffness = 0.01;
    const sim::CorotationOptions c;
    sim::CorotatedStepper stepper(model, b.M, b.bc, o, c, {});
    const IndexVector free = fem::free_dofs(b.mesh.num_dofs(), b.bc);
    const bool midpoint = GetParam() == sim::Integrator::Midpoint;
    sim::State s{Vector::Zero(b.mesh.num_dofs()), Vector::Zero(b.mesh.num_dofs())};
    double worst = 0;
    int iterations = 0;
    for (int k = 0; k < 40; ++k) {
        const sim::State before = s;
        const sim::NewtonReport report = stepper.step(s, b.f);
        iterations = std::max(iterations, report.iterations);
        const SparseMatrix C =
            o.rayleigh_mass * b.M + o.rayleigh_stiffness * model.tangent(model.evaluate(before.u));
        const Vector w = midpoint ? Vector(0.5 * (before.u + s.u)) : s.u;
        const Vector v = midpoint ? Vector(0.5 * (before.v + s.v)) : s.v;
        const Vector inertia = b.M * (s.v - before.v) / o.dt;
        const Vector r = inertia + model.evaluate(w).force + C * v - b.f;
        const Vector f_start = model.evaluate(before.u).force;
        const Vector r_start = b.f - f_start + (midpoint ? 2 : 1) / o.dt * (b.M * before.v);
        const double scale = std::max(Vector(r_start(free)).norm(), Vector(f_start(free)).norm());
        worst = std::max(worst, Vector(r(free)).norm() / scale);
        const Vector kinematic = s.u - before.u - o.dt * (midpoint ? v : s.v);
        EXPECT_LT(kinematic.norm(), 1e-12 * s.u.norm());
    }
    // The tolerance, recomputed: 1% for the round-off of the two evaluations.
    EXPECT_LT(worst, 1.01 * c.tolerance);
    // Quadratic convergence from the step's start: a handful of iterations.
    EXPECT_LE(iterations, 6);
    std::printf("  %s: worst relative residual %.2e, at most %d Newton iterations per step\n",
                sim::integrator_name(GetParam()).c_str(), worst, iterations);
}

TEST_P(CorotatedDynamicsTest, ConvergesAtTheIntegratorsOrder) {
    // The swing at t = 1 with dt = 1/40, 1/80, 1/160: successive differences shrink by 2^p,
    // p = 2 for midpoint and 1 for implicit Euler. The bounds allow ±20% of 2^p for the next
    // order's term (the stiff layers' highest modes have ω dt ~ 0.4 at dt = 1/40; from 1/20
    // midpoint is not yet in its asymptotic range: 2.4).
    const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, 1.0);
    const fem::CorotatedModel model = corotated_bar(b);
    std::vector<Vector> u;
    for (int k : {40, 80, 160})
        u.push_back(swing(b, model, step_options(GetParam(), 1.0 / k, k)).u.back());
    const double ratio = (u[1] - u[0]).norm() / (u[2] - u[1]).norm();
    const double expected = GetParam() == sim::Integrator::Midpoint ? 4 : 2;
    EXPECT_GT(ratio, 0.8 * expected);
    EXPECT_LT(ratio, 1.2 * expected);
    std::printf("  %s: successive differences shrink by %.3f (%.3g, %.3g)\n",
                sim::integrator_name(GetParam()).c_str(), ratio, (u[1] - u[0]).norm(),
                (u[2] - u[1]).norm());
}

TEST_P(CorotatedDynamicsTest, SmallLoadsGiveTheLinearTrajectoryAtFirstOrder) {
    // The corotated force differs from K u by O(|u|²), so the trajectories' relative difference
    // is O(g): a tenth of the load, a tenth of the difference (±30% for the next order and the
    // frames' round-off at g = 1e-3). The linear trajectory is sim::simulate's, checked against
    // CalculiX's dynamics; damping included, which rotates with the frames.
    double previous = 0;
    for (double g : {1e-2, 1e-3}) {
        const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, g);
        const fem::CorotatedModel model = corotated_bar(b);
        sim::DynamicsOptions o = step_options(GetParam(), 0.05, 60);
        o.output_every = 1;
        o.rayleigh_mass = 0.1;
        o.rayleigh_stiffness = 0.01;
        const sim::Trajectory cr = swing(b, model, o);
        const auto [start, f] = sim::initial_state(b.K, b.f, b.bc, Vector(), o);
        const sim::Trajectory lin = sim::simulate(b.K, b.M, b.bc, start, f, o);
        double diff2 = 0, norm2 = 0;
        for (std::size_t i = 0; i < lin.u.size(); ++i) {
            diff2 += (cr.u[i] - lin.u[i]).squaredNorm();
            norm2 += lin.u[i].squaredNorm();
        }
        const double rel = std::sqrt(diff2 / norm2);
        std::printf("  g = %g: corotated against linear %.3e\n", g, rel);
        if (previous > 0) {
            EXPECT_GT(previous / rel, 7.0);
            EXPECT_LT(previous / rel, 13.0);
        }
        previous = rel;
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, CorotatedDynamicsTest,
                         ::testing::Values(sim::Integrator::Midpoint,
                                           sim::Integrator::ImplicitEuler),
                         [](const auto& p) { return sim::integrator_name(p.param); });

class SpinningBodyTest : public ::testing::TestWithParam<mesh::ElementType> {};

TEST_P(SpinningBodyTest, StaysRigidWhereTheLinearModelBalloons) {
    // A free unit square (cube) spinning at ω = π about its centre (z) turns by 180 degrees in
    // t = 1. Corotated, it turns rigidly but for its centrifugal stretch ρ ω² L² / E ~ 1e-2;
    // linear, every node flies off along its initial velocity and the body grows by
    // sqrt(1 + π²) = 3.3 times.
    const int dim = mesh::element_dim(GetParam());
    mesh::Mesh m = dim == 2
                       ? mesh::make_grid(GetParam(), Eigen::Vector2d(-0.5, -0.5),
                                         Eigen::Vector2d(0.5, 0.5), Eigen::Vector2i(4, 4))
                       : mesh::make_grid(GetParam(), Eigen::Vector3d(-0.5, -0.5, -0.5),
                                         Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3i(3, 3, 3));
    const material::ElementMaterials mats =
        material::assign(m, {{0, material::isotropic(dim, 1000.0, 0.3, 1.0)}});
    const SparseMatrix K = fem::stiffness_matrix(m, mats);
    const SparseMatrix M = fem::mass_matrix(m, mats, fem::MassType::Consistent);
    const fem::CorotatedModel model(m, mats, fem::Formulation::Standard,
                                    fem::CorotationFrame::DeVeubeke);
    const double omega = M_PI;
    sim::State s{Vector::Zero(m.num_dofs()), Vector::Zero(m.num_dofs())};
    for (Index v = 0; v < m.num_nodes(); ++v) {
        s.v[dim * v] = -omega * m.rest_positions(v, 1);
        s.v[dim * v + 1] = omega * m.rest_positions(v, 0);
    }
    const sim::DynamicsOptions o = step_options(sim::Integrator::Midpoint, 0.01, 100);
    const Vector f = Vector::Zero(m.num_dofs());
    const sim::Trajectory cr = sim::simulate_corotated(model, M, {}, s, f, o, {});
    const sim::Trajectory lin = sim::simulate(K, M, {}, s, f, o);
    // The body's stretch: the largest relative change of a node's distance from the centre.
    const auto stretch = [&](const Vector& u) {
        double worst = 0;
        for (Index v = 0; v < m.num_nodes(); ++v) {
            const Eigen::VectorXd X = m.rest_positions.row(v).transpose();
            if (X.norm() < 1e-9) continue;  // the centre
            worst = std::max(worst, std::abs((X + u.segment(dim * v, dim)).norm() / X.norm() - 1));
        }
        return worst;
    };
    // Its turn: the angle of the corner node at (0.5, 0.5).
    const Index corner = m.num_nodes() - 1;
    const Eigen::VectorXd x =
        m.rest_positions.row(corner).transpose() + cr.u.back().segment(dim * corner, dim);
    const double turn = std::atan2(x[1], x[0]) - std::atan2(0.5, 0.5) + 2 * M_PI;
    EXPECT_LT(stretch(cr.u.back()), 0.02);
    EXPECT_GT(stretch(lin.u.back()), 2.0);
    // Angular momentum is conserved but for the centrifugal stretch's inertia (2 * 1e-2): the
    // angle is π to 3%.
    EXPECT_NEAR(turn, M_PI, 0.03 * M_PI);
    std::printf("  %s: corotated stretch %.3e, linear %.3f; turned %.4f pi; energy drift %.2e\n",
                mesh::element_name(GetParam()).c_str(), stretch(cr.u.back()), stretch(lin.u.back()),
                turn / M_PI, cr.energy_drift());
}

INSTANTIATE_TEST_SUITE_P(Elements, SpinningBodyTest,
                         ::testing::Values(mesh::ElementType::Quad4, mesh::ElementType::Tri3,
                                           mesh::ElementType::Hex8, mesh::ElementType::Tet4),
                         [](const auto& p) { return mesh::element_name(p.param); });

TEST(CorotatedEnergy, ImplicitEulerDissipatesAndMidpointDriftsLittle) {
    // Undamped, the swing's discrete energy ½ vᵀM v + W - fᵀu: implicit Euler's decreases
    // (it would exactly for a potential force; the corotated force is W's gradient up to
    // O(|û|²), so allow that round-off in |û|), midpoint's drifts by a small fraction of the
    // largest kinetic energy.
    const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, 1.0);
    const fem::CorotatedModel model = corotated_bar(b);
    sim::DynamicsOptions o = step_options(sim::Integrator::ImplicitEuler, 0.02, 200);
    o.output_every = 1;
    const sim::Trajectory euler = swing(b, model, o);
    for (std::size_t i = 1; i < euler.energy.size(); ++i)
        EXPECT_LE(euler.energy[i], euler.energy[i - 1] + 1e-6 * euler.kinetic[i]) << i;
    o.integrator = sim::Integrator::Midpoint;
    const sim::Trajectory midpoint = swing(b, model, o);
    const double dissipated = (euler.energy.front() - euler.energy.back()) /
                              *std::max_element(euler.kinetic.begin(), euler.kinetic.end());
    EXPECT_LT(midpoint.energy_drift(), 0.01);
    EXPECT_GT(dissipated, 10 * midpoint.energy_drift());
    std::printf("  energy: Euler dissipated %.3f, midpoint drift %.2e (of the largest kinetic)\n",
                dissipated, midpoint.energy_drift());
}

TEST(CorotatedLinearized, ApproachesNewtonAsTheStepShrinks) {
    // One linearized iteration leaves the force's remainder O(|Δu|²) = O(dt²), which the
    // inertia (1/dt²) turns into O(dt⁴) in u and O(dt³) in v per step: O(dt²) after a unit
    // time. Halving dt quarters the difference (±20% for higher-order terms).
    const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, 1.0);
    const fem::CorotatedModel model = corotated_bar(b);
    sim::CorotationOptions linearized;
    linearized.step = sim::StepIterations::Linearized;
    std::vector<double> diff;
    for (int k : {20, 40}) {
        const sim::DynamicsOptions o = step_options(sim::Integrator::Midpoint, 1.0 / k, k);
        const Vector newton = swing(b, model, o).u.back();
        const sim::Trajectory lin = swing(b, model, o, linearized);
        EXPECT_EQ(lin.iterations.back(), k);  // one iteration per step
        diff.push_back((lin.u.back() - newton).norm() / newton.norm());
    }
    EXPECT_GT(diff[0] / diff[1], 3.2);
    EXPECT_LT(diff[0] / diff[1], 4.8);
    std::printf("  linearized against Newton at t = 1: %.3e (dt 1/20), %.3e (dt 1/40)\n", diff[0],
                diff[1]);
}

}  // namespace
