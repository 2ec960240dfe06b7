// The material-adapted hierarchy of one time step (Chen et al. 2019, Sec. 4.2): built on the
// step operator S = M + c_C C + c_K K instead of the stiffness.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/mra/coarse_model.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"
#include "sim/layered_bar.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using nlohmann::json;

namespace {

/// The layered bar of layered_bar.hpp, its fine model and consistent mass, with a 3-level
/// stiffness hierarchy and an implicit Euler step of dt = 1 configured.
struct StepBar {
    scene::Scene base;
    scene::FineModel fine;
    SparseMatrix M;
};

StepBar step_bar() {
    json j = test::layered_bar_json();
    j["coarse"] = {{"levels", 3}};
    j["dynamics"] = {{"integrator", "implicit_euler"}, {"dt", 1.0}, {"steps", 1}};
    StepBar b{scene::parse_scene(j, "layers.json", ""), {}, {}};
    b.fine = scene::build_fine_model(b.base);
    b.M = fem::mass_matrix(b.fine.mesh, b.fine.materials, fem::MassType::Consistent);
    return b;
}

sim::DynamicsOptions step_options(sim::Integrator integrator, double dt, double damping) {
    sim::DynamicsOptions o;
    o.integrator = integrator;
    o.dt = dt;
    o.steps = 200;
    o.rayleigh_mass = damping;
    o.rayleigh_stiffness = damping / 100;
    return o;
}

/// Hierarchy options whose multilevel solve is exact (Eq. 12 holds to round-off): global
/// solves, no truncation, no invariance correction.
mra::Options exact_hierarchy_options() {
    mra::Options o;
    o.levels = 3;
    o.truncation = 0;
    o.invariance = false;
    o.fine_operator = mra::Operator::Step;
    return o;
}

/// max_t |a(t) - b(t)|_inf / max_t |b(t)|_inf over two runs from the same state.
double run_difference(const sim::TimeStepper& a, const sim::TimeStepper& b, sim::State s,
                      const Vector& f, int steps) {
    sim::State t = s;
    double worst = 0, scale = 0;
    for (int k = 0; k < steps; ++k) {
        a.step(s, f);
        b.step(t, f);
        worst = std::max(worst, (s.u - t.u).lpNorm<Eigen::Infinity>());
        scale = std::max(scale, t.u.lpNorm<Eigen::Infinity>());
    }
    EXPECT_GT(scale, 0);
    return worst / scale;
}

}  // namespace

// With global solves and every level, the hierarchy of S is a complete S-orthogonal basis
// (Φ^1 and the wavelets Ψ^k of Eq. 12), so the multilevel solve (Sec. 3.6) is S^{-1}: stepping
// with it reproduces the fine time stepping. The solve is exact up to round-off in the
// C̃/W products and the level factorizations (cond(S) ~ 1e3 here): 200 steps agree to 1e-9 (measured
// 6e-13).
TEST(StepHierarchy, AllLevelsReproduceTheFineTimeStepping) {
    const scene::Scene sc = scene::parse_scene(test::layered_bar_json(), "layers.json", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    for (const auto& [integrator, damping] : {std::pair{sim::Integrator::Midpoint, 0.0},
                                              std::pair{sim::Integrator::ImplicitEuler, 0.5}}) {
        const sim::DynamicsOptions o = step_options(integrator, 0.05, damping);
        const SparseMatrix S = sim::step_operator(fine.K, M, o);
        const mra::Hierarchy h =
            mra::build_hierarchy(fine.mesh, S, fine.bc.dofs, exact_hierarchy_options());
        mra::MultilevelSolver multilevel(h);
        const sim::TimeStepper reference(fine.K, M, fine.bc, o);
        const sim::TimeStepper by_levels(fine.K, M, fine.bc, o,
                                         [&](const Vector& r) { return multilevel.solve(r); });
        const auto [start, f] = sim::initial_state(fine.K, fine.f, fine.bc, Vector(), o);
        EXPECT_LT(run_difference(by_levels, reference, start, f, o.steps), 1e-9)
            << sim::integrator_name(integrator);
    }
}

// The coarse model of a step-adapted hierarchy is K and M through it (Φ K Φᵀ, Φ M Φᵀ); its own
// step operator M_c + c_C C_c + c_K K_c is then the hierarchy's coarsest operator A^1 (the
// Galerkin product is linear in the operator), to round-off.
TEST(StepHierarchy, CoarseStepOperatorIsTheCoarsestLevel) {
    json j = test::layered_bar_json();
    j["coarse"] = {{"levels", 3}, {"operator", "step"}};
    j["dynamics"] = {{"integrator", "implicit_euler"},
                     {"dt", 0.05},
                     {"steps", 10},
                     {"damping", {{"rayleigh", {0.5, 0.005}}}}};
    const scene::Scene sc = scene::parse_scene(j, "layers.json", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const sim::DynamicsOptions& o = *sc.dynamics;
    const auto h = std::make_shared<const mra::Hierarchy>(mra::build_hierarchy(
        fine.mesh, sim::step_operator(fine.K, M, o), fine.bc.dofs, sc.coarse.mra));
    const coarsen::CoarseModel on_step = mra::coarse_model(h, fine.f);  // K = S A^1 S
    const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, "mra-linear");
    const Matrix expected(on_step.K);
    const Matrix actual(sim::step_operator(model.K, model.mass(M), o));
    EXPECT_LT((actual - expected).norm(), 1e-12 * expected.norm());
    EXPECT_FALSE(model.compare_with_fine);  // the levels' operators are not the stiffness
}

// As dt grows, S / c_K = K + (M + c_C C) / c_K tends to K, and the step-adapted basis to the
// stiffness-adapted one, by O(1/c_K) = O(dt^-2): the Galerkin coarse mass Φ M Φᵀ differs by
// dt^-2 (fitted slope -2). The stiffness-adapted basis minimizes the K-energy of every basis
// function under the same measurements (Eq. 10), so K_c = Φ K Φᵀ is stationary there and differs
// only by the square, dt^-4 (fitted slope -4). Both asserted within 0.1, over dt = 1, 2, 4, 8
// (the bar's lowest period is 18.3; the basis functions are local, and these steps are already
// long against the periods of motions on their support).
TEST(StepHierarchy, LargeStepsTendToTheStiffnessHierarchy) {
    const StepBar bar = step_bar();
    const scene::Scene& base = bar.base;
    const scene::FineModel& fine = bar.fine;
    const SparseMatrix& M = bar.M;
    const coarsen::CoarseModel stiffness = coarsen::build_coarse_model(base, fine, "mra-linear");
    const Matrix K_stiffness(stiffness.K), M_stiffness(stiffness.mass(M));
    std::vector<double> dts, K_differences, M_differences;
    for (const double dt : {1.0, 2.0, 4.0, 8.0}) {
        scene::Scene sc = base;
        sc.coarse.mra.fine_operator = mra::Operator::Step;
        sc.dynamics->dt = dt;
        const coarsen::CoarseModel step = coarsen::build_coarse_model(sc, fine, "mra-linear");
        dts.push_back(dt);
        K_differences.push_back((Matrix(step.K) - K_stiffness).norm() / K_stiffness.norm());
        M_differences.push_back((Matrix(step.mass(M)) - M_stiffness).norm() / M_stiffness.norm());
    }
    EXPECT_NEAR(test::fitted_slope(dts, M_differences), -2.0, 0.1);
    EXPECT_NEAR(test::fitted_slope(dts, K_differences), -4.0, 0.1);
}

// The step-adapted basis minimizes the S-energy M + dt² K (implicit Euler) of its functions:
// where dt is short against the periods of motions on a coarse cell's support, the mass term
// shapes them, and they carry the slow global modes worse than the stiffness-adapted basis.
// Both coarse models are Galerkin (Rayleigh-Ritz), so their frequencies bound the fine ones from
// above; the bar's lowest one (fine 0.0546, period 18.3) comes out measured +902% at dt = 0.1,
// +133% at 0.3, +2.5% at 1, +0.11% at 3 and +0.03% at 10, the stiffness basis's +0.03%. Asserted:
// an upper bound at every dt, error falling as dt grows, above 100% at dt = 0.1 (T/180, a usual
// fine step), and within 1e-3 of the stiffness basis's frequency at dt = 10 (measured 5e-5).
TEST(StepHierarchy, ShortStepsStiffenTheLowestMode) {
    const StepBar bar = step_bar();
    const scene::Scene& base = bar.base;
    const scene::FineModel& fine = bar.fine;
    const SparseMatrix& M = bar.M;
    const auto lowest = [&](const scene::Scene& sc) {
        const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, "mra-linear");
        return sim::modes(c.K, c.mass(M), c.bc, 1).frequencies_hz[0];
    };
    const double f_fine = sim::modes(fine.K, M, fine.bc, 1).frequencies_hz[0];
    const double f_stiffness = lowest(base);
    double previous = std::numeric_limits<double>::infinity();
    for (const double dt : {0.1, 0.3, 1.0, 3.0, 10.0}) {
        scene::Scene sc = base;
        sc.coarse.mra.fine_operator = mra::Operator::Step;
        sc.dynamics->dt = dt;
        const double f = lowest(sc);
        EXPECT_GE(f, f_fine * (1 - 1e-12)) << "dt " << dt;
        EXPECT_LT(f, previous) << "dt " << dt;
        previous = f;
        if (dt == 0.1) {
            EXPECT_GT(f / f_fine - 1, 1.0);
        }
        if (dt == 10.0) {
            EXPECT_LT(std::abs(f / f_stiffness - 1), 1e-3);
        }
    }
}

// The operator needs the dynamics that define the step, and cell localization needs the
// stiffness (its parts are element stiffness matrices): scene errors naming the key.
TEST(StepHierarchy, SceneErrorsNameTheOperator) {
    json j = test::layered_bar_json();
    j["coarse"] = {{"levels", 3}, {"operator", "step"}};
    const auto parse = [&] { return scene::parse_scene(j, "s.json", ""); };
    test::expect_error(parse, "coarse.operator");
    j["dynamics"] = {{"dt", 0.05}, {"steps", 10}};
    j["coarse"]["localization"] = "cell";
    j["coarse"]["radius"] = 2;
    test::expect_error(parse, "operator \"stiffness\"");
    j["coarse"] = {{"levels", 3}, {"operator", "mass"}};
    test::expect_error(parse, "\"stiffness\", \"step\"");
}
