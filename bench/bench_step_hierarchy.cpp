// The material-adapted hierarchy adapted to one time step (coarse.operator "step", Chen et al.
// 2019, Sec. 4.2) against the one adapted to the stiffness, across time steps: prints the table
// of docs/guide.md ("Dynamics", "A hierarchy adapted to the time step").
//
//   build/release/bench/bench_step_hierarchy
//
// The demo's layered beam at 32x8x8 hexes (8,019 DOFs), mra-linear with 3 levels and global
// solves (243 coarse DOFs), consistent fine mass, Galerkin coarse mass, from rest under gravity
// for two periods of the lowest fine mode. Per integrator and dt: the build of each hierarchy,
// the coarse lowest frequency against the fine one, and trajectory_l2_rel (as `simulate`) of
// each coarse model against the fine run with the same dt.
#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"

using namespace coarsegrain;

namespace {

/// A coarse model with its mass, build time and lowest frequency.
struct Coarse {
    coarsen::CoarseModel model;
    SparseMatrix M;
    double build_seconds = 0, lowest_hz = 0;
};

Coarse build(const scene::Scene& sc, const scene::FineModel& fine, const SparseMatrix& M) {
    Coarse c;
    const auto t0 = std::chrono::steady_clock::now();
    c.model = coarsen::build_coarse_model(sc, fine, "mra-linear");
    c.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    c.M = c.model.mass(M);
    c.lowest_hz = sim::modes(c.model.K, c.M, c.model.bc, 1).frequencies_hz[0];
    return c;
}

/// sqrt(Σ_t |u_c(t) - u(t)|²) / sqrt(Σ_t |u(t)|²) over the saved frames.
double trajectory_error(const Coarse& c, const sim::Trajectory& fine,
                        const sim::DynamicsOptions& o) {
    const coarsen::CoarseModel& m = c.model;
    const auto [s0, f] = sim::initial_state(m.K, m.f, m.bc, Vector(), o);
    const sim::Trajectory t = sim::simulate(m.K, c.M, m.bc, s0, f, o);
    double diff2 = 0, norm2 = 0;
    for (std::size_t i = 0; i < t.u.size(); ++i) {
        diff2 += (m.to_fine * t.u[i] - fine.u[i]).squaredNorm();
        norm2 += fine.u[i].squaredNorm();
    }
    return std::sqrt(diff2 / norm2);
}

}  // namespace

int main() {
    nlohmann::json j = scene::demo_scene(0.67);
    j["coarse"] = {{"levels", 3}, {"cell_tensors", false}, {"spectrum_max_dofs", 0}};
    j["dynamics"] = {{"dt", 0.01}, {"steps", 1}};
    const scene::Scene base = scene::parse_scene(j, "demo beam 32x8x8", "");
    const scene::FineModel fine = scene::build_fine_model(base);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const double f_fine = sim::modes(fine.K, M, fine.bc, 1).frequencies_hz[0];
    const Coarse stiffness = build(base, fine, M);
    fmt::print(
        "fine: {} DOFs, lowest frequency {:.4f} Hz; stiffness-adapted: {} DOFs, built in "
        "{:.1f} s, lowest frequency {:+.4f}%\n\n",
        fine.K.rows(), f_fine, stiffness.model.K.rows(), stiffness.build_seconds,
        100 * (stiffness.lowest_hz / f_fine - 1));
    fmt::print(
        "| integrator | dt | steps per lowest period | step-adapted build s | lowest "
        "frequency, step-adapted | trajectory_l2_rel, step-adapted | trajectory_l2_rel, "
        "stiffness-adapted |\n|---|---|---|---|---|---|---|\n");
    for (const auto& [integrator, dt] : {std::pair{sim::Integrator::ImplicitEuler, 0.001},
                                         {sim::Integrator::ImplicitEuler, 0.005},
                                         {sim::Integrator::ImplicitEuler, 0.02},
                                         {sim::Integrator::ImplicitEuler, 0.05},
                                         {sim::Integrator::ImplicitEuler, 0.2},
                                         {sim::Integrator::Midpoint, 0.005},
                                         {sim::Integrator::Midpoint, 0.05}}) {
        scene::Scene sc = base;
        sim::DynamicsOptions& o = *sc.dynamics;
        o.integrator = integrator;
        o.dt = dt;
        o.steps = static_cast<int>(std::ceil(2 / (f_fine * dt)));
        sc.coarse.mra.fine_operator = mra::Operator::Step;
        const Coarse step = build(sc, fine, M);
        const auto [s0, f] = sim::initial_state(fine.K, fine.f, fine.bc, Vector(), o);
        const sim::Trajectory t = sim::simulate(fine.K, M, fine.bc, s0, f, o);
        fmt::print("| {} | {} | {:.0f} | {:.1f} | {:+.3g}% | {:.3g} | {:.3g} |\n",
                   sim::integrator_name(integrator), dt, 1 / (f_fine * dt), step.build_seconds,
                   100 * (step.lowest_hz / f_fine - 1), trajectory_error(step, t, o),
                   trajectory_error(stiffness, t, o));
    }
    return 0;
}
