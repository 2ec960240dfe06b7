// Corotated time steps whose Newton systems are solved by Krylov iterations preconditioned by a
// factorization made earlier: the rest-state one (corotation.linear_solve "rest_krylov") or the
// latest one of the run ("lagged_krylov"). Every step still reaches corotation.tolerance, and
// the trajectory is the factorizing one's to the difference the tolerance allows, with either
// tangent, with and without stiffness damping.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <vector>

#include "coarsegrain/sim/corotational.hpp"
#include "sim/swinging_bar.hpp"

using namespace coarsegrain;

namespace {

/// The factorizing stepper of `factorize` and the one that solves its Newton systems by
/// Krylov iterations (`solve`) instead.
std::pair<sim::CorotatedStepper, sim::CorotatedStepper> stepper_pair(
    const fem::CorotatedModel& model, const test::SwingingBar& b, const sim::DynamicsOptions& o,
    const sim::CorotationOptions& factorize, sim::LinearSolve solve) {
    sim::CorotationOptions krylov = factorize;
    krylov.linear_solve = solve;
    return {sim::CorotatedStepper(model, b.M, b.bc, o, factorize, {}),
            sim::CorotatedStepper(model, b.M, b.bc, o, krylov, {})};
}

struct KrylovCase {
    mesh::ElementType type;
    sim::Tangent tangent;
    double rayleigh_stiffness;
    sim::LinearSolve solve;
};

class CorotatedKrylovTest : public ::testing::TestWithParam<KrylovCase> {};

TEST_P(CorotatedKrylovTest, TrajectoryIsTheFactorizingOnesToTheTolerance) {
    // Both steppers stop each step's Newton solve at a residual of at most the target t_k =
    // max(tolerance ref_k, 4 round-off) (ref_k the step's force scale), so their solutions w of
    // one step differ by δr with |δr| <= 2 t_k. A residual δr moves w by δw = T⁻¹ δr, and the
    // state by δu = 2 δw, δv = 4 δw / dt (midpoint), whose energy ½ δvᵀM δv + ½ δuᵀK_R δu is
    // 2 δwᵀT δw <= 2 |δr|² / λ_min(T), with T = K_R + (4/dt²) M (+ the damping) and λ_min(T) >=
    // (4/dt²) μ, μ = λ_min(M) on the free DOFs. Midpoint keeps that energy of a perturbation
    // (its linearization along the swing is conservative up to the damping, which only lowers
    // it), so the velocities part by at most sqrt(2/μ) times the sum of the injected energies'
    // square roots: |δv(t_N)| <= (2 dt / μ) Σ_k 2 t_k, and the displacements, the integrals of
    // the velocities, by |δu(t_N)| <= t_N max_k |δv(t_k)|.
    const KrylovCase c = GetParam();
    const test::SwingingBar b = test::make_swinging_bar(c.type);
    const fem::CorotatedModel model(b.mesh, b.mats, fem::Formulation::Standard,
                                    fem::CorotationFrame::DeVeubeke);
    sim::DynamicsOptions o;
    o.dt = 0.05;
    o.steps = 20;
    o.output_every = 1;
    o.rayleigh_stiffness = c.rayleigh_stiffness;
    sim::CorotationOptions factorize;
    factorize.linear_solve = sim::LinearSolve::Factorize;
    factorize.tangent = c.tangent;
    auto [exact, iterative] = stepper_pair(model, b, o, factorize, c.solve);
    const bool lagged = c.solve == sim::LinearSolve::LaggedKrylov;

    const Index n = b.mesh.num_dofs();
    const IndexVector free = fem::free_dofs(n, b.bc);
    const Matrix M_free = Matrix(b.M)(free, free);
    const double mu = Eigen::SelfAdjointEigenSolver<Matrix>(M_free).eigenvalues()[0];
    sim::State s{Vector::Zero(n), Vector::Zero(n)}, t = s;
    double injected = 0, dv_bound = 0, dv_max = 0, du = 0, dv = 0;
    int newton = 0, krylov_iterations = 0, newton_exact = 0, factorizations = 0;
    for (int k = 0; k < o.steps; ++k) {
        // The step's force scale at the start of the Krylov stepper's step (the two starts
        // agree to far below it).
        const fem::CorotatedModel::State start = model.evaluate(t.u);
        const Vector r0 = b.f - start.force + 2 / o.dt * (b.M * t.v);
        const double ref = std::max(Vector(r0(free)).norm(), Vector(start.force(free)).norm());
        injected += 2 * std::max(factorize.tolerance * ref, 4 * start.round_off);

        const sim::NewtonReport e = exact.step(s, b.f);
        const sim::NewtonReport r = iterative.step(t, b.f);
        EXPECT_LE(r.residual, factorize.tolerance) << "step " << k;
        // Rest: the rest factorization preconditions every solve. Lagged: the run's first
        // iteration factorizes, later ones only when the Krylov iterations fail.
        if (!lagged || k == 0) {
            EXPECT_EQ(r.factorizations, lagged ? 1 : 0) << "step " << k;
        }
        factorizations += r.factorizations;
        newton += r.iterations;
        newton_exact += e.iterations;
        krylov_iterations += r.krylov_iterations;
        dv_bound = 2 * o.dt / mu * injected;
        dv = (s.v - t.v).norm();
        du = (s.u - t.u).norm();
        dv_max = std::max(dv_max, dv_bound);
        EXPECT_LE(dv, dv_bound) << "step " << k;
        EXPECT_LE(du, (k + 1) * o.dt * dv_max) << "step " << k;
    }
    // The swing is large: the comparison is not made near rest.
    EXPECT_GT(s.u.lpNorm<Eigen::Infinity>(), 0.3);
    std::printf(
        "  |du| %.2e (bound %.2e), |dv| %.2e (bound %.2e), |u| %.3f; Newton iterations "
        "%d (factorizing: %d), Krylov iterations %d (%.1f per Newton iteration), "
        "factorizations %d\n",
        du, o.steps * o.dt * dv_max, dv, dv_bound, s.u.norm(), newton, newton_exact,
        krylov_iterations, static_cast<double>(krylov_iterations) / newton, factorizations);
}

INSTANTIATE_TEST_SUITE_P(
    Tangents, CorotatedKrylovTest, ::testing::ValuesIn([] {
        std::vector<KrylovCase> cases;
        for (const sim::LinearSolve solve :
             {sim::LinearSolve::RestKrylov, sim::LinearSolve::LaggedKrylov})
            for (const auto& [type, tangent, damping] :
                 {std::tuple{mesh::ElementType::Quad4, sim::Tangent::FixedFrame, 0.0},
                  {mesh::ElementType::Quad4, sim::Tangent::Consistent, 0.0},
                  {mesh::ElementType::Quad4, sim::Tangent::Consistent, 0.01},
                  {mesh::ElementType::Hex8, sim::Tangent::FixedFrame, 0.01},
                  {mesh::ElementType::Hex8, sim::Tangent::Consistent, 0.0}})
                cases.push_back({type, tangent, damping, solve});
        return cases;
    }()),
    [](const ::testing::TestParamInfo<KrylovCase>& p) {
        return std::string(p.param.type == mesh::ElementType::Quad4 ? "Quad4" : "Hex8") +
               (p.param.tangent == sim::Tangent::Consistent ? "Consistent" : "FixedFrame") +
               (p.param.rayleigh_stiffness > 0 ? "Damped" : "") +
               (p.param.solve == sim::LinearSolve::RestKrylov ? "Rest" : "Lagged");
    });

TEST(CorotatedKrylov, LaggedFactorizationIsRefreshedAsTheBarTurns) {
    // Under ten times the gravity the bar whips round. Every step meets the tolerance, and the
    // run factorizes far less often than it iterates (measured: consistent 119 Newton
    // iterations, 1 factorization; fixed frame 352 and 3). With the fixed frame the
    // factorization of an early step stops preconditioning the later ones within
    // kLaggedKrylovIterations, so the run factorizes again.
    for (const sim::Tangent tangent : {sim::Tangent::Consistent, sim::Tangent::FixedFrame}) {
        const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4, 10);
        const fem::CorotatedModel model(b.mesh, b.mats, fem::Formulation::Standard,
                                        fem::CorotationFrame::DeVeubeke);
        sim::DynamicsOptions o;
        o.dt = 0.05;
        o.steps = 40;
        sim::CorotationOptions options;
        options.tangent = tangent;
        options.linear_solve = sim::LinearSolve::LaggedKrylov;
        sim::CorotatedStepper stepper(model, b.M, b.bc, o, options, {});
        const Index n = b.mesh.num_dofs();
        sim::State s{Vector::Zero(n), Vector::Zero(n)};
        int newton = 0, factorizations = 0, krylov = 0;
        for (int k = 0; k < o.steps; ++k) {
            const sim::NewtonReport r = stepper.step(s, b.f);
            EXPECT_LE(r.residual, options.tolerance) << "step " << k;
            newton += r.iterations;
            factorizations += r.factorizations;
            krylov += r.krylov_iterations;
        }
        std::printf("  %s: %d Newton iterations, %d factorizations, %d Krylov iterations\n",
                    sim::tangent_name(tangent).c_str(), newton, factorizations, krylov);
        EXPECT_LT(10 * factorizations, newton);
        if (tangent == sim::Tangent::FixedFrame) {
            EXPECT_GT(factorizations, 1);
        }
    }
}

TEST(CorotatedKrylov, LinearizedStepSolvesToTheTolerance) {
    // One linearized iteration solves T d = r (r the residual at the step's start) to the
    // relative residual η = tolerance: d is the factorizing step's to |T⁻¹| η |r| <= η |r| /
    // σ_min(T), and the state moves by 2 d (midpoint).
    const test::SwingingBar b = test::make_swinging_bar(mesh::ElementType::Quad4);
    const fem::CorotatedModel model(b.mesh, b.mats, fem::Formulation::Standard,
                                    fem::CorotationFrame::DeVeubeke);
    sim::DynamicsOptions o;
    o.dt = 0.05;
    o.steps = 1;
    sim::CorotationOptions factorize;
    factorize.linear_solve = sim::LinearSolve::Factorize;
    factorize.step = sim::StepIterations::Linearized;
    auto [exact, iterative] = stepper_pair(model, b, o, factorize, sim::LinearSolve::RestKrylov);
    const Index n = b.mesh.num_dofs();
    const IndexVector free = fem::free_dofs(n, b.bc);
    sim::State s{Vector::Zero(n), Vector::Zero(n)};
    for (int k = 0; k < 20; ++k) {
        const sim::State before = s;
        const fem::CorotatedModel::State start = model.evaluate(before.u);
        const Vector r = b.f - start.force + 2 / o.dt * (b.M * before.v);
        const SparseMatrix T = model.jacobian(start) + 4 / (o.dt * o.dt) * b.M;
        const double sigma_min =
            Eigen::JacobiSVD<Matrix>(Matrix(T)(free, free)).singularValues().minCoeff();
        exact.step(s, b.f);
        sim::State t = before;
        const sim::NewtonReport report = iterative.step(t, b.f);
        EXPECT_EQ(report.iterations, 1);
        EXPECT_EQ(report.factorizations, 0);
        EXPECT_LE((t.u - s.u).norm(), 2 * factorize.tolerance * Vector(r(free)).norm() / sigma_min)
            << "step " << k;
    }
    EXPECT_GT(s.u.lpNorm<Eigen::Infinity>(), 0.3);
}

}  // namespace
