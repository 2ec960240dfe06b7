#include "coarsegrain/sim/dynamics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::sim {

namespace {

/// Weights (c_C, c_K) of the step operator S = M + c_C C + c_K K.
std::pair<double, double> step_weights(const DynamicsOptions& o) {
    const double dt = o.dt;
    return o.integrator == Integrator::Midpoint ? std::pair{dt / 2, dt * dt / 4}
                                                : std::pair{dt, dt * dt};
}

void check_sizes(const SparseMatrix& K, const SparseMatrix& M) {
    CG_VERIFY(K.rows() == K.cols() && M.rows() == M.cols() && K.rows() == M.rows(),
              "time stepping: stiffness {}x{} and mass {}x{} must be square of one size", K.rows(),
              K.cols(), M.rows(), M.cols());
}

Vector restrict_to(const Vector& x, const IndexVector& dofs) {
    Vector r(dofs.size());
    for (Index i = 0; i < dofs.size(); ++i) r[i] = x[dofs[i]];
    return r;
}

/// Prints "coarsegrain: <name> time stepping: k / n steps, r steps/s" every few seconds.
class StepProgress {
  public:
    StepProgress(std::string name, int steps) : m_name(std::move(name)), m_steps(steps) {}
    void tick(int done) {
        if (!progress_enabled()) return;
        const auto now = std::chrono::steady_clock::now();
        if (now - m_last < std::chrono::seconds(2)) return;
        m_last = now;
        const double seconds = std::chrono::duration<double>(now - m_start).count();
        std::fprintf(stderr, "coarsegrain: %s time stepping: %d / %d steps, %.1f steps/s\n",
                     m_name.c_str(), done, m_steps, done / seconds);
    }

  private:
    std::string m_name;
    int m_steps;
    std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
    std::chrono::steady_clock::time_point m_last = m_start;
};

}  // namespace

std::string integrator_name(Integrator integrator) {
    return integrator == Integrator::Midpoint ? "midpoint" : "implicit_euler";
}

void validate(const DynamicsOptions& o) {
    CG_VERIFY(std::isfinite(o.dt) && o.dt > 0, "dynamics.dt: expected a number > 0, got {}", o.dt);
    CG_VERIFY(o.steps >= 1, "dynamics.steps: expected an integer >= 1, got {}", o.steps);
    CG_VERIFY(o.output_every >= 1 && o.output_every <= o.steps,
              "dynamics.output_every: expected an integer in [1, steps = {}], got {}", o.steps,
              o.output_every);
    CG_VERIFY(std::isfinite(o.rayleigh_mass) && o.rayleigh_mass >= 0 &&
                  std::isfinite(o.rayleigh_stiffness) && o.rayleigh_stiffness >= 0,
              "dynamics.damping.rayleigh: expected two numbers >= 0, got [{}, {}]", o.rayleigh_mass,
              o.rayleigh_stiffness);
    CG_VERIFY(o.initial_velocity.allFinite(), "dynamics.initial_velocity: expected finite numbers");
}

SparseMatrix step_operator(const SparseMatrix& K, const SparseMatrix& M,
                           const DynamicsOptions& options) {
    validate(options);
    check_sizes(K, M);
    const auto [cC, cK] = step_weights(options);
    // S = M + c_C (α M + β K) + c_K K
    SparseMatrix S =
        (1 + cC * options.rayleigh_mass) * M + (cK + cC * options.rayleigh_stiffness) * K;
    S.makeCompressed();
    return S;
}

TimeStepper::TimeStepper(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                         const DynamicsOptions& options, const solve::SolverOptions& solver)
    : m_K(K), m_M(M), m_options(options) {
    const SparseMatrix S = step_operator(K, M, options);
    fem::ReducedSystem sys = fem::reduce(S, Vector::Zero(S.rows()), bc);
    m_free = std::move(sys.free_dofs);
    auto factorization = std::make_shared<solve::SpdSolver>(solver);
    factorization->compute(sys.K);
    m_solve = [factorization, free = m_free](const Vector& r) {
        return factorization->solve(restrict_to(r, free));
    };
}

TimeStepper::TimeStepper(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                         const DynamicsOptions& options, StepSolve solve)
    : m_K(K), m_M(M), m_options(options) {
    validate(options);
    check_sizes(K, M);
    m_free = fem::free_dofs(K.rows(), bc);
    m_solve = [solve = std::move(solve), free = m_free, n = K.rows()](const Vector& r) {
        const Vector x = solve(r);
        CG_VERIFY(x.size() == n, "time stepping: the step solve returned {} entries, not {}",
                  x.size(), n);
        return restrict_to(x, free);
    };
}

void TimeStepper::step(State& s, const Vector& f) const {
    CG_VERIFY(s.u.size() == dofs() && s.v.size() == dofs() && f.size() == dofs(),
              "time stepping: state ({}, {}) and load ({}) must have {} entries", s.u.size(),
              s.v.size(), f.size(), dofs());
    const double dt = m_options.dt;
    const bool midpoint = m_options.integrator == Integrator::Midpoint;
    // The damping terms cancel from both right-hand sides (midpoint: S v + (M - c_C C - c_K K) v
    // = 2 M v; implicit Euler has none), so only S carries C.
    const Vector rhs = (midpoint ? 2.0 : 1.0) * (m_M * s.v) + dt * (f - m_K * s.u);
    const Vector x = m_solve(rhs);
    if (midpoint) {  // x = w = v + v' on the free DOFs
        for (Index i = 0; i < m_free.size(); ++i) {
            const Index d = m_free[i];
            s.u[d] += dt / 2 * x[i];
            s.v[d] = x[i] - s.v[d];
        }
    } else {  // x = v'
        for (Index i = 0; i < m_free.size(); ++i) {
            const Index d = m_free[i];
            s.v[d] = x[i];
            s.u[d] += dt * x[i];
        }
    }
}

double TimeStepper::energy(const State& s, const Vector& f) const {
    return 0.5 * s.v.dot(m_M * s.v) + 0.5 * s.u.dot(m_K * s.u) - f.dot(s.u);
}

Vector uniform_field(Index dofs, const Eigen::VectorXd& velocity) {
    const Index dim = velocity.size();
    CG_VERIFY(dim > 0 && dofs % dim == 0, "uniform_field: {} DOFs are not nodes of {} components",
              dofs, dim);
    return velocity.replicate(dofs / dim, 1);
}

std::pair<State, Vector> initial_state(Index n, const Vector& f, const fem::Dirichlet& bc,
                                       const Vector& v0, const DynamicsOptions& options,
                                       const std::function<Vector()>& static_solution) {
    CG_VERIFY(f.size() == n && (v0.size() == 0 || v0.size() == n),
              "initial state: load ({}) and velocity ({}) must have {} entries", f.size(),
              v0.size(), n);
    State s;
    s.v = v0.size() ? v0 : Vector::Zero(n);
    for (Index d : bc.dofs) s.v[d] = 0;
    if (options.start == Start::Static) {
        s.u = static_solution();
        return {std::move(s), Vector::Zero(n)};
    }
    s.u = Vector::Zero(n);
    for (std::size_t k = 0; k < bc.dofs.size(); ++k)
        s.u[bc.dofs[k]] = bc.values[static_cast<Index>(k)];
    return {std::move(s), f};
}

std::pair<State, Vector> initial_state(const SparseMatrix& K, const Vector& f,
                                       const fem::Dirichlet& bc, const Vector& v0,
                                       const DynamicsOptions& options,
                                       const solve::SolverOptions& solver) {
    return initial_state(K.rows(), f, bc, v0, options,
                         [&] { return fem::solve_static(K, f, bc, solver); });
}

double Trajectory::energy_drift() const {
    double drift = 0, kinetic_max = 0;
    for (std::size_t i = 0; i < energy.size(); ++i) {
        drift = std::max(drift, std::abs(energy[i] - energy[0]));
        kinetic_max = std::max(kinetic_max, kinetic[i]);
    }
    return kinetic_max > 0 ? drift / kinetic_max : 0.0;
}

Trajectory run_steps(const State& start, const DynamicsOptions& options, const SparseMatrix& M,
                     const Step& step, const std::function<double(const State&)>& energy,
                     const std::string& name) {
    Trajectory t;
    State s = start;
    const auto save = [&](double time, const StepSolves& solves, double seconds) {
        t.times.push_back(time);
        t.u.push_back(s.u);
        t.energy.push_back(energy(s));
        t.kinetic.push_back(0.5 * s.v.dot(M * s.v));
        t.iterations.push_back(solves.solves);
        t.krylov_iterations.push_back(solves.krylov_iterations);
        t.factorizations.push_back(solves.factorizations);
        t.step_seconds.push_back(seconds);
    };
    save(0, {}, 0);
    StepProgress progress(name.empty() ? "model" : name, options.steps);
    double stepping = 0, since_frame = 0;
    StepSolves frame;  // the solves since the last saved frame
    for (int k = 1; k <= options.steps; ++k) {
        if (interrupt_requested())
            throw Interrupted(fmt::format("interrupted at step {} of {}", k, options.steps));
        const auto begin = std::chrono::steady_clock::now();
        const StepSolves solves = step(s);
        frame.solves += solves.solves;
        frame.krylov_iterations += solves.krylov_iterations;
        frame.factorizations += solves.factorizations;
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
        stepping += seconds;
        since_frame += seconds;
        if (k % options.output_every == 0) {
            save(k * options.dt, frame, since_frame);
            frame = {};
            since_frame = 0;
        }
        progress.tick(k);
    }
    t.per_step_seconds = stepping / options.steps;
    return t;
}

Trajectory simulate(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                    const State& start, const Vector& f, const DynamicsOptions& options,
                    const solve::SolverOptions& solver, const std::string& name) {
    Timings timings;
    std::optional<TimeStepper> stepper;
    {
        const Phase phase(name.empty() ? "factorize" : name + " factorize", &timings);
        stepper.emplace(K, M, bc, options, solver);
    }
    Trajectory t = run_steps(
        start, options, M,
        [&](State& s) {
            stepper->step(s, f);
            return StepSolves{1, 0, 0};
        },
        [&](const State& s) { return stepper->energy(s, f); }, name);
    t.factorize_seconds = timings.entries().back().second;
    return t;
}

}  // namespace coarsegrain::sim
