#include "coarsegrain/sim/corotational.hpp"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/solve/lu_solver.hpp"

namespace coarsegrain::sim {

namespace {

/// The smallest line-search step before an iteration counts as stalled.
constexpr double kMinStep = 1.0 / 64;

/// Full Newton steps in a row that lower neither merit before the watchdog stops them.
constexpr int kWatchdog = 4;

/// Residuals below this many times the force's round-off count as converged: exact Newton
/// iterations stall at 0.4 to 2.1 times it (fem::CorotatedModel::State::round_off).
constexpr double kRoundOffFactor = 4;

/// v restricted to the free DOFs.
Vector restrict(const Vector& v, const IndexVector& free) { return v(free); }

/// The equations f_int(w) + A w = b on the free DOFs, w holding the prescribed values on the
/// others: a static load increment (no A, b = λ f) or one implicit time step.
struct Balance {
    Vector b;                         ///< num_dofs
    const SparseMatrix* A = nullptr;  ///< num_dofs square, symmetric (none: 0)
    double load_factor = 1;           ///< λ, for the history
};

/// Eigen's preconditioner interface around a solve kept elsewhere (set() before the Krylov
/// solver's compute): z = P⁻¹ r by one back-substitution with a factorization.
class FactorizationPreconditioner {
  public:
    void set(std::function<Vector(const Vector&)> solve) { m_solve = std::move(solve); }
    template <typename MatrixType>
    FactorizationPreconditioner& analyzePattern(const MatrixType&) {
        return *this;
    }
    template <typename MatrixType>
    FactorizationPreconditioner& factorize(const MatrixType&) {
        return *this;
    }
    template <typename MatrixType>
    FactorizationPreconditioner& compute(const MatrixType&) {
        return *this;
    }
    template <typename Rhs>
    Vector solve(const Rhs& r) const {
        return m_solve(Vector(r));
    }
    Eigen::ComputationInfo info() const { return Eigen::Success; }

  private:
    std::function<Vector(const Vector&)> m_solve;
};

/// Newton's method for one Balance.
class Newton {
  public:
    Newton(const fem::CorotatedModel& model, const fem::Dirichlet& bc, const IndexVector& free,
           const CorotationOptions& options, solve::SpdSolver& solver, Timings* timings)
        : m_model(model),
          m_bc(bc),
          m_free(free),
          m_options(options),
          m_solver(solver),
          m_timings(timings) {}

    /// The factorization preconditioning every linear solve by Krylov iterations from now on
    /// (LinearSolve::RestKrylov; kept by reference).
    void set_rest(const solve::SpdSolver& rest) { m_rest = &rest; }

    /// From now on, precondition every linear solve's Krylov iterations by the latest
    /// factorization this Newton made (LinearSolve::LaggedKrylov).
    void set_lagged() { m_lagged = true; }

    /// Newton's method for `balance` from u (updated in place; `at_u` its state), converged
    /// when the residual is at most tolerance times `reference`: first with full steps, watched
    /// (iterate), then, if those stop making progress, again from u with the line search.
    /// Returns whether it converged within max_iterations in all; the iterations go to `report`.
    bool run(Vector& u, const fem::CorotatedModel::State& at_u, const Balance& balance,
             double reference, NewtonReport& report) {
        m_balance = &balance;
        m_reference = reference;
        m_report = &report;
        const Vector start = u;
        int budget = m_options.max_iterations;
        if (iterate(u, at_u, false, budget)) return true;
        u = start;
        return budget > 0 && iterate(u, at_u, true, budget);
    }

    /// One Newton iteration for `balance` from u (updated in place; `at_u` its state), a full
    /// step.
    void linearized(Vector& u, const fem::CorotatedModel::State& at_u, const Balance& balance,
                    NewtonReport& report) {
        m_balance = &balance;
        m_report = &report;
        m_forcing = m_options.tolerance;
        u(m_free) += newton_step(at_u, residual(at_u, u));
        ++report.iterations;
    }

    /// Newton iterations from u (state `at_u`), at most `budget` (decremented), with the line
    /// search or with full steps under a watchdog: full steps may raise both merits for a while
    /// (the first step from rest, the linear solution, stretches a stiff part's linearized
    /// rotation: on the effective tensors' accordion it raised the residual 12,000 times and the
    /// potential from 0 to 30, and the next three steps converged), but if kWatchdog steps in a row
    /// lower neither the residual nor the potential below their values before them, the
    /// iteration stops. Returns whether it converged.
    bool iterate(Vector& u, const fem::CorotatedModel::State& at_u, bool line_search, int& budget) {
        fem::CorotatedModel::State state = at_u;
        Vector r = residual(state, u);
        m_previous_residual = 0;
        double watched_residual = r.norm(), watched_potential = potential(state, u);
        int unwatched = 0;
        for (; budget > 0; --budget) {
            if (converged(r, state)) return true;
            Vector d;
            try {
                if (krylov()) m_forcing = forcing(r, state);
                d = newton_step(state, r);
            } catch (const NotPositiveDefinite&) {
                // The first tangent is (for zero prescribed values) the linear stiffness: the
                // model itself is singular. Later: a buckled state; try a smaller increment.
                if (m_report->iterations == 0) throw;
                return false;
            } catch (const solve::SingularMatrix& e) {
                if (m_report->iterations == 0) throw NotPositiveDefinite(e.what());
                return false;
            }
            ++m_report->iterations;
            const double step = line_search ? search(u, state, r, d) : 1.0;
            if (step == 0) return false;
            if (!line_search) {
                u(m_free) += d;
                state = evaluate(u);
                r = residual(state, u);
                if (!r.allFinite()) return false;
                const double p = potential(state, u);
                if (r.norm() < watched_residual || p < watched_potential) {
                    watched_residual = std::min(watched_residual, r.norm());
                    watched_potential = std::min(watched_potential, p);
                    unwatched = 0;
                } else if (++unwatched == kWatchdog) {
                    --budget;
                    return false;
                }
            }
            m_report->history.push_back({m_balance->load_factor, r.norm() / m_reference, step});
        }
        return converged(r, state);
    }

    /// Π = W + ½ uᵀA u - bᵀu.
    double potential(const fem::CorotatedModel::State& state, const Vector& u) const {
        const double quadratic = m_balance->A ? 0.5 * u.dot(*m_balance->A * u) : 0.0;
        return state.energy + quadratic - m_balance->b.dot(u);
    }

    /// The backtracking line search along d from u (state, residual r): updates them to the
    /// accepted step and returns its length, or 0 if it fell below kMinStep. Merit: the
    /// potential Π, whose gradient the force is up to O(|û|²), or the residual norm. Far from
    /// equilibrium the residual of a stiff part's linearized rotation (a spurious stretch)
    /// dwarfs the load while its energy stays small, so Π accepts the steps the residual would
    /// cut; near equilibrium, where Π's gradient and the force part by their O(|û|²), the
    /// residual takes over.
    double search(Vector& u, fem::CorotatedModel::State& state, Vector& r, const Vector& d) const {
        const double p = potential(state, u);
        const double slope = r.dot(d);  // -dΠ/ds at s = 0 (to O(|û|²))
        for (double step = 1; step >= kMinStep; step /= 2) {
            Vector trial = u;
            trial(m_free) += step * d;
            fem::CorotatedModel::State trial_state = evaluate(trial);
            Vector trial_r = residual(trial_state, trial);
            const bool descent =
                slope > 0 && potential(trial_state, trial) <= p - 1e-4 * step * slope;
            if (descent || trial_r.norm() <= (1 - step / 4) * r.norm()) {
                u = std::move(trial);
                state = std::move(trial_state);
                r = std::move(trial_r);
                return step;
            }
        }
        return 0;
    }

    /// The residual norm at which Newton's method has converged at `state`: the tolerance or
    /// the round-off floor.
    double target(const fem::CorotatedModel::State& state) const {
        return std::max(m_options.tolerance * m_reference, kRoundOffFactor * state.round_off);
    }

    /// Whether the residual (free DOFs) at `state` meets the tolerance or the round-off floor.
    bool converged(const Vector& r, const fem::CorotatedModel::State& state) const {
        return r.norm() <= target(state);
    }

    /// The relative residual of the next Krylov solve, for the Newton residual r: Eisenstat
    /// and Walker's choice 2, η = 0.9 (|r| / |r_previous|)² at most kMaxForcing (and that
    /// in the first iteration), at least half the Newton target over |r|.
    double forcing(const Vector& r, const fem::CorotatedModel::State& state) {
        const double norm = r.norm();
        double eta = kMaxForcing;
        if (m_previous_residual > 0)
            eta = std::min(kMaxForcing, 0.9 * std::pow(norm / m_previous_residual, 2));
        m_previous_residual = norm;
        return std::max(eta, 0.5 * target(state) / norm);
    }

    /// Whether the next linear solve starts with Krylov iterations: with a rest factorization,
    /// or lagged once a factorization exists.
    bool krylov() const { return m_rest || (m_lagged && m_factorized); }

    /// z = P⁻¹ r with the Krylov preconditioner: the rest factorization, or the latest one.
    Vector precondition(const Vector& r) const {
        if (m_rest) return m_rest->solve(r);
        return m_options.tangent == Tangent::Consistent ? m_lu.solve(r) : m_solver.solve(r);
    }

    /// Preconditioned conjugate gradients for T d = r (T symmetric positive definite) from
    /// d = 0, each iteration one product with T and one back-substitution (precondition), to
    /// |r - T d| <= m_forcing |r|. Returns whether they converged within `max_iterations` (a
    /// curvature pᵀT p <= 0, T not definite, stops them unconverged).
    bool conjugate_gradients(const SparseMatrix& T, const Vector& r, int max_iterations,
                             Vector& d) {
        const double target = m_forcing * r.norm();
        d = Vector::Zero(r.size());
        Vector residual = r, z = precondition(residual), p = z;
        double rz = residual.dot(z);
        for (int k = 1; k <= max_iterations; ++k) {
            ++m_report->krylov_iterations;
            const Vector q = T * p;
            const double curvature = p.dot(q);
            if (!(curvature > 0)) return false;
            const double alpha = rz / curvature;
            d += alpha * p;
            residual -= alpha * q;
            if (residual.norm() <= target) return d.allFinite();
            z = precondition(residual);
            const double rz_next = residual.dot(z);
            p = z + (rz_next / rz) * p;
            rz = rz_next;
        }
        return false;
    }

    /// Eigen's BiCGSTAB for T d = r (T not symmetric) from d = 0, preconditioned by
    /// `precondition` (two products with T and two back-substitutions per iteration), to
    /// |r - T d| <= m_forcing |r|. Returns whether it converged within `max_iterations`.
    bool bicgstab(const SparseMatrix& T, const Vector& r, int max_iterations, Vector& d) {
        Eigen::BiCGSTAB<SparseMatrix, FactorizationPreconditioner> krylov;
        krylov.preconditioner().set([this](const Vector& x) { return precondition(x); });
        krylov.setTolerance(m_forcing);
        krylov.setMaxIterations(max_iterations);
        krylov.compute(T);
        d = krylov.solve(r);
        m_report->krylov_iterations += static_cast<int>(krylov.iterations());
        return krylov.info() == Eigen::Success && d.allFinite();
    }

    /// The Newton step T^{-1} r with the tangent at `state` (plus A) on the free DOFs: by
    /// Krylov iterations when a preconditioner is set (krylov(); falling back to a
    /// factorization if they do not converge), else by a factorization.
    Vector newton_step(const fem::CorotatedModel::State& state, const Vector& r) {
        const bool consistent = m_options.tangent == Tangent::Consistent;
        SparseMatrix T = consistent ? m_model.jacobian(state) : m_model.tangent(state);
        if (m_balance->A) T += *m_balance->A;
        const fem::ReducedSystem sys = fem::reduce(T, Vector::Zero(T.rows()), m_bc);
        if (krylov()) {
            const Phase phase("krylov", m_timings);
            const int cap = m_rest ? kMaxKrylovIterations : kLaggedKrylovIterations;
            Vector d;
            if (consistent ? bicgstab(sys.K, r, cap, d) : conjugate_gradients(sys.K, r, cap, d))
                return d;
        }
        ++m_report->factorizations;
        {
            const Phase phase("factorize", m_timings);
            m_factorized = false;
            if (consistent)
                m_lu.factorize(sys.K);
            else
                m_solver.factorize(sys.K);
            m_factorized = true;
        }
        const Phase phase("solve", m_timings);
        return consistent ? m_lu.solve(r) : m_solver.solve(r);
    }

    /// The state at u.
    fem::CorotatedModel::State evaluate(const Vector& u) const {
        const Phase phase("newton", m_timings);
        return m_model.evaluate(u);
    }

    /// b - f_int(u) - A u on the free DOFs, for the state at u.
    Vector residual(const fem::CorotatedModel::State& state, const Vector& u) const {
        Vector r = m_balance->b - state.force;
        if (m_balance->A) r -= *m_balance->A * u;
        return restrict(r, m_free);
    }

  private:
    const fem::CorotatedModel& m_model;
    const fem::Dirichlet& m_bc;
    const IndexVector& m_free;
    const CorotationOptions& m_options;
    solve::SpdSolver& m_solver;
    const solve::SpdSolver* m_rest = nullptr;
    bool m_lagged = false;      ///< LinearSolve::LaggedKrylov
    bool m_factorized = false;  ///< whether m_lu or m_solver holds a factorization
    solve::SparseLu m_lu;
    Timings* m_timings;
    const Balance* m_balance = nullptr;
    double m_reference = 1;
    double m_forcing = kMaxForcing;  ///< relative residual of the next Krylov solve
    double m_previous_residual = 0;  ///< |r| of the previous iteration (0: none yet)
    NewtonReport* m_report = nullptr;
};

/// Checks the Newton options' ranges.
void validate(const CorotationOptions& options) {
    CG_VERIFY(options.tolerance > 0 && options.tolerance < 1,
              "corotation.tolerance: expected a number in (0, 1), got {}", options.tolerance);
    CG_VERIFY(options.max_iterations >= 1 && options.max_bisections >= 0,
              "corotation: max_iterations must be >= 1 and max_bisections >= 0, got {} and {}",
              options.max_iterations, options.max_bisections);
}

}  // namespace

std::string tangent_name(Tangent tangent) {
    return tangent == Tangent::Consistent ? "consistent" : "fixed_frame";
}

std::string step_iterations_name(StepIterations iterations) {
    return iterations == StepIterations::Newton ? "newton" : "linearized";
}

std::string linear_solve_name(LinearSolve solve) {
    switch (solve) {
        case LinearSolve::Factorize:
            return "factorize";
        case LinearSolve::RestKrylov:
            return "rest_krylov";
        case LinearSolve::LaggedKrylov:
            return "lagged_krylov";
    }
    return "";
}

std::string kinematics_name(Kinematics kinematics) {
    return kinematics == Kinematics::Linear ? "linear" : "corotational";
}

CorotatedSolution solve_corotated_static(const fem::CorotatedModel& model, const Vector& f,
                                         const fem::Dirichlet& bc, const CorotationOptions& options,
                                         const solve::SolverOptions& solver_options,
                                         Timings* timings) {
    const Index n = model.num_dofs();
    CG_VERIFY(f.size() == n, "corotated solve: load of size {} for {} DOFs", f.size(), n);
    validate(options);
    const IndexVector free = fem::free_dofs(n, bc);
    const auto prescribed = [&](double load_factor) {
        Vector u = Vector::Zero(n);
        for (std::size_t i = 0; i < bc.dofs.size(); ++i)
            u[bc.dofs[i]] = load_factor * bc.values[static_cast<Index>(i)];
        return u;
    };

    CorotatedSolution sol;
    // The residual of the whole load in the undeformed state (prescribed values applied).
    const Vector start = prescribed(1);
    const fem::CorotatedModel::State start_state = model.evaluate(start);
    const double reference = restrict(f - start_state.force, free).norm();
    if (reference == 0 || free.size() == 0) {
        sol.u = start;
        sol.energy = start_state.energy;
        sol.report.increments = 1;
        return sol;
    }
    solve::SpdSolver solver(solver_options);
    Newton newton(model, bc, free, options, solver, timings);
    Vector u = prescribed(0);

    double done = 0, size = 1;
    const double smallest = std::ldexp(1.0, -options.max_bisections);
    while (done < 1) {
        const double load_factor = std::min(1.0, done + size);
        Vector trial = u;
        for (std::size_t i = 0; i < bc.dofs.size(); ++i)
            trial[bc.dofs[i]] = load_factor * bc.values[static_cast<Index>(i)];
        const Balance balance{load_factor * f, nullptr, load_factor};
        if (newton.run(trial, newton.evaluate(trial), balance, reference, sol.report)) {
            u = std::move(trial);
            done = load_factor;
            ++sol.report.increments;
            size = std::min(2 * size, 1.0);
            continue;
        }
        ++sol.report.bisections;
        size /= 2;
        if (size < smallest)
            throw NewtonFailed(fmt::format(
                "corotated solve: Newton's method did not converge beyond load factor {:.6g} "
                "(an increment of {:.3g} failed after {} iterations in all, relative residual "
                "{:.3g} > corotation.tolerance {:g}); the load may buckle or invert elements, "
                "or raise corotation.max_iterations / max_bisections",
                done, 2 * size, sol.report.iterations,
                sol.report.history.empty() ? 1.0 : sol.report.history.back().residual,
                options.tolerance));
    }
    const fem::CorotatedModel::State state = newton.evaluate(u);
    sol.report.residual = restrict(f - state.force, free).norm() / reference;
    sol.report.round_off = kRoundOffFactor * state.round_off / reference;
    sol.energy = state.energy;
    sol.u = std::move(u);
    return sol;
}

/// The coefficients of a time step of dt's f_int(w) + A w = b, A = c_M M + c_C C, and the time
/// h with w = u + h v at constant velocity.
struct StepCoefficients {
    double mass, damping, h;
};

StepCoefficients step_coefficients(Integrator integrator, double dt) {
    if (integrator == Integrator::Midpoint) return {4 / (dt * dt), 2 / dt, dt / 2};
    return {1 / (dt * dt), 1 / dt, dt};
}

struct CorotatedStepper::Impl {
    Impl(const fem::CorotatedModel& model_, const SparseMatrix& M_, const fem::Dirichlet& bc_,
         const DynamicsOptions& dynamics_, const CorotationOptions& corotation_,
         const solve::SolverOptions& solver_)
        : model(model_),
          M(M_),
          bc(bc_),
          dynamics(dynamics_),
          corotation(corotation_),
          free(fem::free_dofs(model_.num_dofs(), bc_)),
          solver_options(solver_),
          solver(solver_),
          newton(model, bc, free, corotation, solver, nullptr) {
        if (corotation.linear_solve == LinearSolve::RestKrylov) {
            K = model.tangent(model.evaluate(Vector::Zero(model.num_dofs())));
            rest(dynamics.dt);
        }
        if (corotation.linear_solve == LinearSolve::LaggedKrylov) newton.set_lagged();
    }

    /// The factorization of the step matrix of a step of dt at rest on the free DOFs,
    /// K + c_M M + c_C (α M + β K) with K the tangent at u = 0; factorized on first use.
    const solve::SpdSolver& rest(double dt) {
        auto it = rests.find(dt);
        if (it != rests.end()) return it->second;
        const StepCoefficients c = step_coefficients(dynamics.integrator, dt);
        const SparseMatrix T0 = (1 + c.damping * dynamics.rayleigh_stiffness) * K +
                                (c.mass + c.damping * dynamics.rayleigh_mass) * M;
        solve::SpdSolver factorization(solver_options);
        factorization.factorize(fem::reduce(T0, Vector::Zero(T0.rows()), bc).K);
        return rests.emplace(dt, std::move(factorization)).first->second;
    }

    /// Advances s by dt: one step, or if its Newton solve fails, two of dt/2 (each halved
    /// again on failure, up to corotation.max_bisections times).
    void advance(State& s, const Vector& f, double dt, int depth, NewtonReport& report);
    /// One step of dt from s (updated if it converged); returns whether it did.
    bool attempt(State& s, const Vector& f, double dt, NewtonReport& report);

    const fem::CorotatedModel& model;
    const SparseMatrix& M;
    fem::Dirichlet bc;
    DynamicsOptions dynamics;
    CorotationOptions corotation;
    IndexVector free;
    solve::SolverOptions solver_options;
    solve::SpdSolver solver;
    /// LinearSolve::RestKrylov: the stiffness at rest, and the step matrices at rest by step.
    SparseMatrix K;
    std::map<double, solve::SpdSolver> rests;
    Newton newton;
};

CorotatedStepper::CorotatedStepper(const fem::CorotatedModel& model, const SparseMatrix& M,
                                   const fem::Dirichlet& bc, const DynamicsOptions& dynamics,
                                   const CorotationOptions& corotation,
                                   const solve::SolverOptions& solver) {
    validate(dynamics);
    validate(corotation);
    const Index n = model.num_dofs();
    CG_VERIFY(M.rows() == n && M.cols() == n,
              "corotated time stepping: mass {}x{} for a model of {} DOFs", M.rows(), M.cols(), n);
    m_impl = std::make_unique<Impl>(model, M, bc, dynamics, corotation, solver);
}

CorotatedStepper::~CorotatedStepper() = default;
CorotatedStepper::CorotatedStepper(CorotatedStepper&&) noexcept = default;
CorotatedStepper& CorotatedStepper::operator=(CorotatedStepper&&) noexcept = default;

Index CorotatedStepper::dofs() const { return m_impl->model.num_dofs(); }

NewtonReport CorotatedStepper::step(State& s, const Vector& f) {
    const Index n = dofs();
    CG_VERIFY(s.u.size() == n && s.v.size() == n && f.size() == n,
              "corotated time stepping: state ({}, {}) and load ({}) must have {} entries",
              s.u.size(), s.v.size(), f.size(), n);
    NewtonReport report;
    m_impl->advance(s, f, m_impl->dynamics.dt, 0, report);
    return report;
}

void CorotatedStepper::Impl::advance(State& s, const Vector& f, double dt, int depth,
                                     NewtonReport& report) {
    State trial = s;
    if (attempt(trial, f, dt, report)) {
        s = std::move(trial);
        ++report.increments;
        return;
    }
    if (depth == corotation.max_bisections)
        throw NewtonFailed(fmt::format(
            "corotated time step: Newton's method did not converge at a step of {:.3g} ({} "
            "halvings of dynamics.dt; {} iterations in all, relative residual {:.3g} > "
            "corotation.tolerance {:g}); reduce dynamics.dt or raise corotation.max_iterations "
            "/ max_bisections",
            dt, depth, report.iterations,
            report.history.empty() ? 1.0 : report.history.back().residual, corotation.tolerance));
    ++report.bisections;
    advance(s, f, dt / 2, depth + 1, report);
    advance(s, f, dt / 2, depth + 1, report);
}

bool CorotatedStepper::Impl::attempt(State& s, const Vector& f, double dt, NewtonReport& report) {
    const DynamicsOptions& o = dynamics;
    const bool midpoint = o.integrator == Integrator::Midpoint;
    // f_int(w) + A w = b with A = c_M M + c_C C and C = α M + β K_R (frames of the start).
    const StepCoefficients c = step_coefficients(o.integrator, dt);
    const double cM = c.mass, cC = c.damping, h = c.h;
    if (corotation.linear_solve == LinearSolve::RestKrylov) newton.set_rest(rest(dt));
    const fem::CorotatedModel::State start = model.evaluate(s.u);
    SparseMatrix A = (cM + cC * o.rayleigh_mass) * M;
    Vector b = f + cM * (M * (s.u + h * s.v));
    if (o.rayleigh_mass > 0) b += cC * o.rayleigh_mass * (M * s.u);
    if (o.rayleigh_stiffness > 0) {
        const SparseMatrix KR = model.tangent(start);
        A += cC * o.rayleigh_stiffness * KR;
        b += cC * o.rayleigh_stiffness * (KR * s.u);
    }
    const Balance balance{std::move(b), &A, 1};

    Vector w = s.u;
    if (corotation.step == StepIterations::Linearized) {
        newton.linearized(w, start, balance, report);
    } else {
        // The step's force scale: the residual at its start, dominated by the inertia 2 M v/dt
        // (Euler M v/dt) when the body moves, or the internal force when it rests.
        const Vector r0 = balance.b - start.force - A * s.u;
        const double reference =
            std::max(restrict(r0, free).norm(), restrict(start.force, free).norm());
        const std::size_t before = report.history.size();
        if (!newton.run(w, start, balance, reference, report)) return false;
        report.residual = std::max(
            report.residual, report.history.size() > before ? report.history.back().residual : 0.0);
    }
    for (const Index d : free) {
        if (midpoint) {
            const double du = w[d] - s.u[d];
            s.v[d] = 4 * du / dt - s.v[d];
            s.u[d] += 2 * du;
        } else {
            s.v[d] = (w[d] - s.u[d]) / dt;
            s.u[d] = w[d];
        }
    }
    return true;
}

double CorotatedStepper::energy(const State& s, const Vector& f) const {
    return 0.5 * s.v.dot(m_impl->M * s.v) + m_impl->model.evaluate(s.u).energy - f.dot(s.u);
}

std::pair<State, Vector> corotated_initial_state(const fem::CorotatedModel& model, const Vector& f,
                                                 const fem::Dirichlet& bc, const Vector& v0,
                                                 const DynamicsOptions& dynamics,
                                                 const CorotationOptions& corotation,
                                                 const solve::SolverOptions& solver) {
    return initial_state(model.num_dofs(), f, bc, v0, dynamics, [&] {
        return solve_corotated_static(model, f, bc, corotation, solver).u;
    });
}

Trajectory simulate_corotated(const fem::CorotatedModel& model, const SparseMatrix& M,
                              const fem::Dirichlet& bc, const State& start, const Vector& f,
                              const DynamicsOptions& dynamics, const CorotationOptions& corotation,
                              const solve::SolverOptions& solver, const std::string& name) {
    CorotatedStepper stepper(model, M, bc, dynamics, corotation, solver);
    int k = 0;
    return run_steps(
        start, dynamics, M,
        [&](State& s) {
            ++k;
            try {
                const NewtonReport r = stepper.step(s, f);
                return StepSolves{r.iterations, r.krylov_iterations, r.factorizations};
            } catch (const NewtonFailed& e) {
                throw NewtonFailed(
                    fmt::format("step {} (t = {:g}): {}", k, k * dynamics.dt, e.what()));
            }
        },
        [&](const State& s) { return stepper.energy(s, f); }, name);
}

}  // namespace coarsegrain::sim
