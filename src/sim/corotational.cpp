#include "coarsegrain/sim/corotational.hpp"

#include <algorithm>
#include <cmath>

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

/// Newton's method for one load increment (λ f, λ u_D), from u (updated in place; u holds the
/// prescribed values λ u_D). Returns whether it converged.
class Increment {
  public:
    Increment(const fem::CorotatedModel& model, const Vector& load, const fem::Dirichlet& bc,
              const IndexVector& free, double reference, const CorotationOptions& options,
              solve::SpdSolver& solver, NewtonReport& report, Timings* timings)
        : m_model(model),
          m_load(load),
          m_bc(bc),
          m_free(free),
          m_reference(reference),
          m_options(options),
          m_solver(solver),
          m_report(report),
          m_timings(timings) {}

    /// Newton's method for the increment, from u (updated in place): first with full steps,
    /// watched (full_steps), then, if those stop making progress, again from u with the line
    /// search. Returns whether it converged within max_iterations in all.
    bool run(Vector& u, double load_factor) {
        const Vector start = u;
        int budget = m_options.max_iterations;
        if (iterate(u, load_factor, false, budget)) return true;
        u = start;
        return budget > 0 && iterate(u, load_factor, true, budget);
    }

    /// Newton iterations from u, at most `budget` (decremented), with the line search or with
    /// full steps under a watchdog: full steps may raise both merits for a while (the first
    /// step from rest, the linear solution, stretches a stiff part's linearized rotation: on
    /// the effective tensors' accordion it raised the residual 12,000 times and the potential
    /// from 0 to 30, and the next three steps converged), but if kWatchdog steps in a row
    /// lower neither the residual nor the potential below their values before them, the
    /// iteration stops. Returns whether it converged.
    bool iterate(Vector& u, double load_factor, bool line_search, int& budget) {
        fem::CorotatedModel::State state = evaluate(u);
        Vector r = residual(state, load_factor);
        double watched_residual = r.norm(), watched_potential = potential(state, u, load_factor);
        int unwatched = 0;
        for (; budget > 0; --budget) {
            if (converged(r, state)) return true;
            Vector d;
            try {
                d = newton_step(state, r);
            } catch (const NotPositiveDefinite&) {
                // The first tangent is (for zero prescribed values) the linear stiffness: the
                // model itself is singular. Later: a buckled state; try a smaller increment.
                if (m_report.iterations == 0) throw;
                return false;
            } catch (const solve::SingularMatrix& e) {
                if (m_report.iterations == 0) throw NotPositiveDefinite(e.what());
                return false;
            }
            ++m_report.iterations;
            const double step = line_search ? search(u, state, r, d, load_factor) : 1.0;
            if (step == 0) return false;
            if (!line_search) {
                u(m_free) += d;
                state = evaluate(u);
                r = residual(state, load_factor);
                if (!r.allFinite()) return false;
                const double p = potential(state, u, load_factor);
                if (r.norm() < watched_residual || p < watched_potential) {
                    watched_residual = std::min(watched_residual, r.norm());
                    watched_potential = std::min(watched_potential, p);
                    unwatched = 0;
                } else if (++unwatched == kWatchdog) {
                    --budget;
                    return false;
                }
            }
            m_report.history.push_back({load_factor, r.norm() / m_reference, step});
        }
        return converged(r, state);
    }

    /// Π = W - λ fᵀu.
    double potential(const fem::CorotatedModel::State& state, const Vector& u,
                     double load_factor) const {
        return state.energy - load_factor * m_load.dot(u);
    }

    /// The backtracking line search along d from u (state, residual r): updates them to the
    /// accepted step and returns its length, or 0 if it fell below kMinStep. Merit: the
    /// potential Π, whose gradient the force is up to O(|û|²), or the residual norm. Far from
    /// equilibrium the residual of a stiff part's linearized rotation (a spurious stretch)
    /// dwarfs the load while its energy stays small, so Π accepts the steps the residual would
    /// cut; near equilibrium, where Π's gradient and the force part by their O(|û|²), the
    /// residual takes over.
    double search(Vector& u, fem::CorotatedModel::State& state, Vector& r, const Vector& d,
                  double load_factor) const {
        const double p = potential(state, u, load_factor);
        const double slope = r.dot(d);  // -dΠ/ds at s = 0 (to O(|û|²))
        for (double step = 1; step >= kMinStep; step /= 2) {
            Vector trial = u;
            trial(m_free) += step * d;
            fem::CorotatedModel::State trial_state = evaluate(trial);
            Vector trial_r = residual(trial_state, load_factor);
            const bool descent =
                slope > 0 && potential(trial_state, trial, load_factor) <= p - 1e-4 * step * slope;
            if (descent || trial_r.norm() <= (1 - step / 4) * r.norm()) {
                u = std::move(trial);
                state = std::move(trial_state);
                r = std::move(trial_r);
                return step;
            }
        }
        return 0;
    }

    /// Whether the residual (free DOFs) at `state` meets the tolerance or the round-off floor.
    bool converged(const Vector& r, const fem::CorotatedModel::State& state) const {
        return r.norm() <=
               std::max(m_options.tolerance * m_reference, kRoundOffFactor * state.round_off);
    }

    /// The Newton step T^{-1} r with the tangent at `state` on the free DOFs.
    Vector newton_step(const fem::CorotatedModel::State& state, const Vector& r) {
        const bool consistent = m_options.tangent == Tangent::Consistent;
        const SparseMatrix T = consistent ? m_model.jacobian(state) : m_model.tangent(state);
        const fem::ReducedSystem sys = fem::reduce(T, Vector::Zero(T.rows()), m_bc);
        {
            const Phase phase("factorize", m_timings);
            if (consistent)
                m_lu.factorize(sys.K);
            else
                m_solver.factorize(sys.K);
        }
        const Phase phase("solve", m_timings);
        return consistent ? m_lu.solve(r) : m_solver.solve(r);
    }

    /// The state at u.
    fem::CorotatedModel::State evaluate(const Vector& u) const {
        const Phase phase("newton", m_timings);
        return m_model.evaluate(u);
    }

    /// λ f - f_int(u) on the free DOFs.
    Vector residual(const fem::CorotatedModel::State& state, double load_factor) const {
        return restrict(load_factor * m_load - state.force, m_free);
    }

  private:
    const fem::CorotatedModel& m_model;
    const Vector& m_load;
    const fem::Dirichlet& m_bc;
    const IndexVector& m_free;
    double m_reference;
    const CorotationOptions& m_options;
    solve::SpdSolver& m_solver;
    solve::SparseLu m_lu;
    NewtonReport& m_report;
    Timings* m_timings;
};

}  // namespace

std::string tangent_name(Tangent tangent) {
    return tangent == Tangent::Consistent ? "consistent" : "fixed_frame";
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
    CG_VERIFY(options.tolerance > 0 && options.tolerance < 1,
              "corotation.tolerance: expected a number in (0, 1), got {}", options.tolerance);
    CG_VERIFY(options.max_iterations >= 1 && options.max_bisections >= 0,
              "corotation: max_iterations must be >= 1 and max_bisections >= 0, got {} and {}",
              options.max_iterations, options.max_bisections);
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
    Increment increment(model, f, bc, free, reference, options, solver, sol.report, timings);
    Vector u = prescribed(0);

    double done = 0, size = 1;
    const double smallest = std::ldexp(1.0, -options.max_bisections);
    while (done < 1) {
        const double load_factor = std::min(1.0, done + size);
        Vector trial = u;
        for (std::size_t i = 0; i < bc.dofs.size(); ++i)
            trial[bc.dofs[i]] = load_factor * bc.values[static_cast<Index>(i)];
        if (increment.run(trial, load_factor)) {
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
    const fem::CorotatedModel::State state = increment.evaluate(u);
    sol.report.residual = increment.residual(state, 1).norm() / reference;
    sol.report.round_off = kRoundOffFactor * state.round_off / reference;
    sol.energy = state.energy;
    sol.u = std::move(u);
    return sol;
}

}  // namespace coarsegrain::sim
