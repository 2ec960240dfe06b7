#pragma once
/// @file Corotated linear elasticity (Kharevych et al. 2009, Sec. 4) solved by Newton's method
/// with a line search: static equilibrium with load increments, and time steps of implicit
/// midpoint and implicit Euler, for the fine model and every coarse element model alike (scene
/// "kinematics": "corotational").
#include <string>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/corotation.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::sim {

/// Newton's method did not reach its tolerance at the smallest load increment (not a singular
/// model: that is NotPositiveDefinite).
class NewtonFailed : public ErrorOf<NewtonFailed> {
  public:
    using ErrorOf::ErrorOf;
};

/// "linear" or "corotational" (scene "kinematics").
enum class Kinematics { Linear, Corotational };

/// "linear", "corotational".
std::string kinematics_name(Kinematics kinematics);

/// The matrix of Newton's iterations.
enum class Tangent {
    /// The Jacobian of the force, the frames' derivative included
    /// (fem::CorotatedModel::jacobian): quadratic convergence; not symmetric, so every
    /// iteration factorizes it by sparse LU (UMFPACK) whatever solver.backend says.
    Consistent,
    /// R K Rᵀ, the frames held fixed (fem::CorotatedModel::tangent): symmetric positive definite
    /// (the solver.backend factorizes it, cheaper than the LU), but Newton's method with it
    /// converges linearly (rate about 0.15 on a cantilever bent by a third of its length: 14
    /// iterations against 6; docs/guide.md, "Large rotations").
    FixedFrame,
};

/// "consistent", "fixed_frame".
std::string tangent_name(Tangent tangent);

/// The Newton iterations of a corotated time step.
enum class StepIterations {
    /// Newton's method to CorotationOptions::tolerance (default).
    Newton,
    /// One Newton iteration from the state at the step's start, without a line search: the
    /// linearly implicit step of real-time corotated simulation (one factorization per step).
    /// It leaves the force's remainder O(|Δu|²) = O(dt²) in each step's equation, which the
    /// inertia (1/dt²) turns into O(dt⁴) in u and O(dt³) in v: the trajectories part by O(dt²)
    /// over a unit time (measured: 1.8e-4 and 4.6e-5 of the swing at dt 1/20 and 1/40).
    Linearized,
};

/// "newton", "linearized".
std::string step_iterations_name(StepIterations iterations);

/// How a corotated time step solves the linear system of each Newton iteration,
/// T d = r with T = J(w) + A (the tangent at w plus the step's c_M M + c_C C).
enum class LinearSolve {
    /// Factorize T at every iteration: UMFPACK's LU for the consistent tangent, the
    /// solver.backend for the fixed frame.
    Factorize,
    /// Krylov iterations preconditioned by one factorization of the step matrix at rest,
    /// T_0 = K + A (K the linear stiffness, the tangent at u = 0; with stiffness damping A
    /// holds β K, the damping's value at rest, instead of the step's β K_R, which changes
    /// every step), factorized by solver.backend on the free DOFs once per step length (the
    /// stepper's dynamics.dt at construction). Conjugate gradients for the fixed frame (T
    /// symmetric positive definite: one product with T and one back-substitution per
    /// iteration), Eigen's BiCGSTAB for the consistent tangent (not symmetric: two of each per
    /// iteration). Each solve stops at the
    /// relative residual |r - T d| <= η |r| of Eisenstat and Walker (1996, choice 2: η_k =
    /// 0.9 (|r_k| / |r_{k-1}|)², at most kMaxForcing, which is also η_0), but no tighter than
    /// half the Newton target over |r_k|: the inexact steps keep Newton's rate (|r_{k+1}| <=
    /// η_k |r_k| + O(|d|²)) and Newton still stops at CorotationOptions::tolerance, without
    /// solving beyond what that needs. A linearized step solves to η = tolerance. A solve that
    /// does not converge in kMaxKrylovIterations is discarded and T factorized instead.
    /// T_0⁻¹ T is the identity at rest and drifts from it as the elements turn (R K Rᵀ
    /// against K): the iterations grow with the rotation (docs/guide.md, "Large rotations").
    /// Statics ignore it and factorize (their load increments leave the rest state behind).
    RestKrylov,
    /// Krylov iterations (as RestKrylov: conjugate gradients for the fixed frame, BiCGSTAB for
    /// the consistent tangent, to the Eisenstat–Walker residual) preconditioned by the latest
    /// factorization of T, which the stepper keeps across iterations and steps: a lagged
    /// Jacobian (the chord method) whose error the Krylov iterations correct, so that Newton
    /// keeps its rate. The first iteration of a run factorizes T; a solve that does not
    /// converge within kLaggedKrylovIterations is discarded and T factorized instead, the new
    /// factorization preconditioning the solves that follow. Where RestKrylov's preconditioner
    /// drifts from T as the elements turn, this one is refreshed by the turning itself.
    /// The default: the fastest on the fine and the coarse accordion, with either tangent
    /// (docs/corotated_dynamics_bench.md: 6 to 9 times faster than factorizing on the fine
    /// model, where RestKrylov is 3 to 11 times; on the coarse one 1.2 to 1.7 times, where
    /// RestKrylov's iterations reach their cap and fall back to factorizing).
    LaggedKrylov,
};

/// "factorize", "rest_krylov", "lagged_krylov".
std::string linear_solve_name(LinearSolve solve);

/// Krylov iterations per Newton iteration (LinearSolve::RestKrylov) before the iteration
/// factorizes its matrix instead.
constexpr int kMaxKrylovIterations = 100;
/// Krylov iterations per Newton iteration (LinearSolve::LaggedKrylov) before the iteration
/// factorizes its matrix instead, which then preconditions the solves that follow.
constexpr int kLaggedKrylovIterations = 10;
/// The largest relative residual of a Krylov solve in a Newton iteration (LinearSolve::RestKrylov).
/// On the accordion (bench/bench_corotated_dynamics.cpp, frames 16-18) caps of 0.5, 0.1 and 0.01
/// took 5, 4 and 4 consistent Newton iterations per step and 6, 6 and 5 fixed-frame ones; the
/// frame times differed by at most 10%.
constexpr double kMaxForcing = 0.01;

/// The scene's "corotation" block: the frame and the Newton solve.
struct CorotationOptions {
    fem::CorotationFrame frame = fem::CorotationFrame::DeVeubeke;
    Tangent tangent = Tangent::Consistent;
    /// Converged when the residual on the free DOFs, |f - f_int(u)|, is at most tolerance times
    /// its value at the start of the solve (u = 0 with the prescribed values, the full load), or
    /// at most 4 times the force's round-off (fem::CorotatedModel::State::round_off), below
    /// which no iteration can reduce it (NewtonReport::round_off says where that is).
    double tolerance = 1e-8;
    /// Newton iterations per load increment before the increment is halved.
    int max_iterations = 60;
    /// Halvings of a load increment (from the whole load), or of a time step (CorotatedStepper),
    /// before the solve gives up.
    int max_bisections = 10;
    /// The Newton iterations of a time step (CorotatedStepper; statics ignore it).
    StepIterations step = StepIterations::Newton;
    /// The linear solves of a time step's Newton iterations (CorotatedStepper; statics
    /// ignore it and factorize every iteration).
    LinearSolve linear_solve = LinearSolve::LaggedKrylov;
};

/// One Newton iteration.
struct NewtonIteration {
    double load_factor = 0;  ///< λ of the increment: load λ f, prescribed values λ u_D
    double residual = 0;     ///< relative residual after the iteration
    double step = 0;         ///< line-search step length taken (1: the full Newton step)
};

/// How a corotated solve went.
struct NewtonReport {
    int iterations = 0;  ///< Newton iterations (linear solves), failed increments included
    /// Krylov iterations in all (LinearSolve::RestKrylov; 0 when every iteration factorizes).
    int krylov_iterations = 0;
    /// Newton iterations that factorized their matrix: all with LinearSolve::Factorize, those
    /// whose Krylov solve did not converge with RestKrylov.
    int factorizations = 0;
    int increments = 0;   ///< load increments that converged (1 if the whole load converged)
    int bisections = 0;   ///< increments halved after failing
    double residual = 0;  ///< final relative residual
    /// The residual the force's round-off allows, relative as `residual`: 4 ε-scaled force
    /// magnitudes (CorotationOptions::tolerance).
    double round_off = 0;
    std::vector<NewtonIteration> history;
};

/// A corotated static solution.
struct CorotatedSolution {
    Vector u;           ///< all model DOFs, prescribed values included
    double energy = 0;  ///< corotated strain energy W(u)
    NewtonReport report;
};

/// Solves the corotated equilibrium f_int(u) = f on the DOFs that bc leaves free, with u = bc's
/// values on its DOFs. The load and the prescribed values are applied in increments λ f, λ u_D:
/// first the whole (λ = 1); an increment whose Newton iteration does not converge within
/// max_iterations (or whose line search stalls, or whose tangent is singular or, for the fixed
/// frame, not positive definite) is halved, and the next one is doubled again after a success,
/// up to the rest of the load. Each iteration factorizes the tangent (options.tangent) on the
/// free DOFs (one symbolic analysis for the solve) and takes the Newton step d = T^{-1} r,
/// scaled by a backtracking line search (halving s down to 1/64) that accepts a step lowering
/// the potential Π = W - λ fᵀu by 1e-4 s rᵀd (the force is Π's gradient up to O(|û|²)) or the
/// residual norm to (1 - s/4) |r|: far from equilibrium the residual of a stiff part's
/// linearized rotation dwarfs the load while its energy stays small, near equilibrium the
/// residual decides. Phases "newton" (evaluations) and "factorize", "solve" go to `timings`.
/// @throws Error if sizes disagree or the options are out of range; NotPositiveDefinite if the
///         first tangent (for zero prescribed values: the stiffness) is singular or not
///         definite (the conditions do not hold the model); NewtonFailed naming the load
///         factor reached, the iterations and the residual if the smallest increment fails
CorotatedSolution solve_corotated_static(const fem::CorotatedModel& model, const Vector& f,
                                         const fem::Dirichlet& bc, const CorotationOptions& options,
                                         const solve::SolverOptions& solver,
                                         Timings* timings = nullptr);

/// Corotated elastodynamics M ü + C u̇ + f_int(u) = f (Kharevych et al. 2009, Sec. 4.4, "Time
/// Integration", with the corotated force of Sec. 4), by the integrators of TimeStepper:
///   midpoint:        w = (u + u')/2 solves f_int(w) + (4/dt²) M (w - u - dt v/2)
///                    + (2/dt) C (w - u) = f,  then u' = 2w - u, v' = 4 (w - u)/dt - v;
///   implicit Euler:  f_int(u') + M (u' - u - dt v)/dt² + C (u' - u)/dt = f,  v' = (u' - u)/dt.
/// Each is f_int(w) + A w = b with A = c_M M + c_C C (midpoint 4/dt², 2/dt; Euler 1/dt², 1/dt),
/// solved by Newton's method with the Jacobian J(w) + A (corotation.tangent) from w = u, the
/// full steps watched and then line-searched on Π(w) = W(w) + ½ wᵀA w - bᵀw as in
/// solve_corotated_static, to the residual corotation.tolerance times the step's force scale
/// max(|r(u)|, |f_int(u)|) on the free DOFs (or 4 times the force's round-off); or by one
/// linearized iteration (corotation.step). Rayleigh damping C = α M + β K_R rotates with the
/// body: K_R = Σ R^e K^e R^eᵀ with the frames of the step's start, held through the step (so
/// that A is constant within it; it is the stiffness K when the body has not turned).
/// Midpoint does not conserve the energy ½ vᵀM v + W(u) - fᵀu exactly, as the corotated force is
/// the gradient of W only up to O(|û|²) (the paper notes it); implicit Euler dissipates it.
/// Dirichlet DOFs keep their prescribed values and zero velocity.
class CorotatedStepper {
  public:
    /// @param model  kept by reference, as M: both must outlive the stepper
    /// @param M      model.num_dofs() square mass, symmetric positive definite on the free DOFs
    /// @throws Error if sizes disagree or options are out of range; with linear_solve
    ///         rest_krylov, NotPositiveDefinite if the step matrix at rest is not
    CorotatedStepper(const fem::CorotatedModel& model, const SparseMatrix& M,
                     const fem::Dirichlet& bc, const DynamicsOptions& dynamics,
                     const CorotationOptions& corotation, const solve::SolverOptions& solver);
    ~CorotatedStepper();
    CorotatedStepper(CorotatedStepper&&) noexcept;
    CorotatedStepper& operator=(CorotatedStepper&&) noexcept;

    /// Advances `s` by one step of dt under the load f; returns how its Newton solves went:
    /// `increments` the sub-steps taken, `bisections` the halvings, `residual` the largest
    /// final relative residual. A step whose Newton solve does not converge within
    /// corotation.max_iterations is replaced by two steps of dt/2 (each halved again on
    /// failure, at most corotation.max_bisections deep): a smaller step converges more easily,
    /// as A grows as 1/dt² (the coarse accordion under strong gravity needs it where the
    /// force's non-potential part, O(|K||û|²), misleads the line search's merits).
    /// @throws Error on size mismatch; NotPositiveDefinite / solve::SingularMatrix if the step's
    ///         matrix is; NewtonFailed naming the smallest step if a step of dt /
    ///         2^max_bisections does not converge
    NewtonReport step(State& s, const Vector& f);
    /// Discrete energy ½ vᵀM v + W(u) - fᵀu (kinetic + corotated strain - work of f).
    double energy(const State& s, const Vector& f) const;
    Index dofs() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// The start of a corotated run, as initial_state: options.start Static starts from the
/// corotated static solution of f (solve_corotated_static) and removes the load.
/// @throws as initial_state and solve_corotated_static
std::pair<State, Vector> corotated_initial_state(const fem::CorotatedModel& model, const Vector& f,
                                                 const fem::Dirichlet& bc, const Vector& v0,
                                                 const DynamicsOptions& dynamics,
                                                 const CorotationOptions& corotation,
                                                 const solve::SolverOptions& solver = {});

/// simulate() with corotated forces (CorotatedStepper); the trajectory's `iterations` count the
/// Newton iterations. A step whose Newton solve fails throws NewtonFailed naming its time.
/// @throws as CorotatedStepper
Trajectory simulate_corotated(const fem::CorotatedModel& model, const SparseMatrix& M,
                              const fem::Dirichlet& bc, const State& start, const Vector& f,
                              const DynamicsOptions& dynamics, const CorotationOptions& corotation,
                              const solve::SolverOptions& solver = {},
                              const std::string& name = "");

}  // namespace coarsegrain::sim
