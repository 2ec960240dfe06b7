#pragma once
/// @file Linear elastodynamics M ü + C u̇ + K u = f with Rayleigh damping C = α M + β K, for the
/// fine model and every coarse model alike: implicit midpoint (Kharevych et al. 2009, Sec. 4.4,
/// "Time Integration") and implicit Euler (Chen et al. 2019, Sec. 4.2), one factorization per run.
#include <functional>
#include <string>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::sim {

/// The most steps a run may take (dynamics.steps).
constexpr int kMaxSteps = 100'000'000;

enum class Integrator {
    /// Implicit midpoint: u' = u + dt/2 (v + v'), M (v' - v) = dt (f - K (u + u')/2 -
    /// C (v + v')/2). Symplectic, second order; undamped it conserves the discrete energy
    /// (energy()) exactly. For a linear system under a constant load it is Newmark's
    /// average-acceleration rule (β = 1/4, γ = 1/2; HHT with α = 0).
    Midpoint,
    /// Implicit (backward) Euler in velocity form: M (v' - v) = dt (f - K u' - C v'),
    /// u' = u + dt v'. First order; its energy never increases.
    ImplicitEuler,
};

/// How a run starts.
enum class Start {
    /// u = the prescribed values (0 elsewhere), v = the initial velocity; the load is switched
    /// on at t = 0 and held.
    Rest,
    /// u = the static solution of the load, v = the initial velocity; the load is removed at
    /// t = 0 (free vibration about the unloaded state).
    Static,
};

/// The scene's "dynamics" block.
struct DynamicsOptions {
    Integrator integrator = Integrator::Midpoint;
    double dt = 0;         ///< time step, > 0
    int steps = 0;         ///< number of steps, >= 1
    int output_every = 1;  ///< a frame is saved every output_every steps (and at t = 0)
    Start start = Start::Rest;
    Eigen::VectorXd initial_velocity;  ///< one velocity for every free node (size dim; 0 if empty)
    double rayleigh_mass = 0;          ///< α of C = α M + β K (1/time), >= 0
    double rayleigh_stiffness = 0;     ///< β of C = α M + β K (time), >= 0
    /// The fine model's mass ("mass": "consistent" or "lumped"); a coarse model's mass is an
    /// option of its method.
    fem::MassType mass = fem::MassType::Consistent;
};

/// "midpoint", "implicit_euler".
std::string integrator_name(Integrator integrator);

/// The state of a model: displacement and velocity over all its DOFs.
struct State {
    Vector u, v;
};

/// The operator of one step, S = M + c_C C + c_K K with C = α M + β K (midpoint: c_C = dt/2,
/// c_K = dt²/4; implicit Euler: dt, dt²), over all DOFs (n x n, both triangles, as K and M):
/// the matrix of Chen et al. 2019, Sec. 4.2, "L u̇_{t+dt} = u̇_t", for these integrators.
/// @throws Error if the options are out of range or K and M are not square of one size
SparseMatrix step_operator(const SparseMatrix& K, const SparseMatrix& M,
                           const DynamicsOptions& options);

/// A solver of the step operator over all n DOFs: x = solve(r) with S x = r on the free DOFs
/// (the entries of r at Dirichlet DOFs are ignored, and those of x there are not used).
using StepSolve = std::function<Vector(const Vector& r)>;

/// Time stepping of one model. The step operator S (step_operator) restricted to the free DOFs
/// is factorized once by the constructor, or solved by a given StepSolve; each step is then two
/// sparse products and one solve with S:
///   midpoint:        S w = 2 M v + dt (f - K u),   v' = w - v,   u' = u + dt/2 w
///   implicit Euler:  S v' = M v + dt (f - K u),    u' = u + dt v'
/// The damping enters S only: it cancels from both right-hand sides.
/// Dirichlet DOFs keep their prescribed values and zero velocity.
class TimeStepper {
  public:
    /// @param K  n x n stiffness, both triangles stored (kept by reference: it must outlive the
    ///           stepper, as M)
    /// @param M  n x n mass (consistent, lumped or Galerkin), symmetric positive definite on the
    ///           free DOFs
    /// @throws Error if sizes disagree or options are out of range; NotPositiveDefinite if the
    ///         step operator is not positive definite on the free DOFs
    TimeStepper(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                const DynamicsOptions& options, const solve::SolverOptions& solver = {});
    /// As above, with the solves of S by `solve` (e.g. mra::MultilevelSolver on a hierarchy of
    /// S, Chen et al. 2019, Secs. 3.6 and 4.2) instead of a factorization.
    /// @throws Error if sizes disagree or options are out of range
    TimeStepper(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                const DynamicsOptions& options, StepSolve solve);
    /// Advances `s` by one step under the load f (n entries).
    void step(State& s, const Vector& f) const;
    /// Discrete energy ½ vᵀM v + ½ uᵀK u - fᵀu (kinetic + strain - work of the constant load f).
    double energy(const State& s, const Vector& f) const;
    Index dofs() const { return m_K.rows(); }

  private:
    const SparseMatrix& m_K;
    const SparseMatrix& m_M;
    DynamicsOptions m_options;
    IndexVector m_free;
    /// x over the free DOFs for r over all DOFs
    std::function<Vector(const Vector& r)> m_solve;
};

/// Saved frames of a run.
struct Trajectory {
    std::vector<double> times;    ///< t = 0 and every output_every-th step
    std::vector<Vector> u;        ///< displacement over all DOFs at each saved time
    std::vector<double> energy;   ///< the stepper's discrete energy at each saved time
    std::vector<double> kinetic;  ///< ½ vᵀM v at each saved time
    /// Solves with the step matrix of the steps since the previous saved time (0 at t = 0): one
    /// per step for linear models, the Newton iterations for corotated ones.
    std::vector<int> iterations;
    /// Of a corotated run, the Krylov iterations of those steps and the factorizations among
    /// their solves (corotation.linear_solve); zero for a linear run, which factorizes once
    /// before its first step.
    std::vector<int> krylov_iterations, factorizations;
    std::vector<double> step_seconds;  ///< wall time of those steps
    double factorize_seconds = 0;
    double per_step_seconds = 0;  ///< wall time of the step loop / steps (frames not included)

    /// max_i |energy_i - energy_0| / max_i kinetic_i (0 if the body never moves): the drift of
    /// the discrete energy against the largest kinetic energy of the run.
    double energy_drift() const;
};

/// The linear solves of one step: with its step matrix, and of a corotated step the Krylov
/// iterations and the factorizations among them.
struct StepSolves {
    int solves = 0;
    int krylov_iterations = 0;
    int factorizations = 0;
};

/// One step of a model: advances the state and returns its solves.
using Step = std::function<StepSolves(State& s)>;

/// The step loop of simulate and simulate_corotated: options.steps steps of `step` from
/// `start`, a frame (with energy(state) and ½ vᵀM v) saved every options.output_every steps and
/// at t = 0. Progress ("<name> time stepping", steps per second) goes to stderr for runs longer
/// than a second.
/// @throws whatever step throws; Interrupted before a step once an interrupt is requested
///         (request_interrupt)
Trajectory run_steps(const State& start, const DynamicsOptions& options, const SparseMatrix& M,
                     const Step& step, const std::function<double(const State&)>& energy,
                     const std::string& name);

/// The initial state and the load held during the run, by options.start: Rest gives u = bc
/// values, load f; Static gives u = the static solution of f (one extra factorization of K),
/// load 0. The velocity is v0 on the free DOFs (v0 empty: zero).
/// @throws as fem::solve_static
std::pair<State, Vector> initial_state(const SparseMatrix& K, const Vector& f,
                                       const fem::Dirichlet& bc, const Vector& v0,
                                       const DynamicsOptions& options,
                                       const solve::SolverOptions& solver = {});

/// initial_state of an n-DOF model whose static solution of f, for options.start Static, is
/// `static_solution()` (not called otherwise).
/// @throws Error if f or v0 has the wrong size; whatever static_solution throws
std::pair<State, Vector> initial_state(Index n, const Vector& f, const fem::Dirichlet& bc,
                                       const Vector& v0, const DynamicsOptions& options,
                                       const std::function<Vector()>& static_solution);

/// A velocity field that is `velocity` (size dim) at every node of an n-DOF interleaved model.
Vector uniform_field(Index dofs, const Eigen::VectorXd& velocity);

/// Runs options.steps steps from `start` under the load `f`, saving a frame every
/// options.output_every steps (and t = 0). Progress ("<name> time stepping", steps per second)
/// goes to stderr for runs longer than a second.
/// @throws as TimeStepper
Trajectory simulate(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc,
                    const State& start, const Vector& f, const DynamicsOptions& options,
                    const solve::SolverOptions& solver = {}, const std::string& name = "");

/// Checks every option's range (dt > 0 and finite, steps >= 1, 1 <= output_every <= steps,
/// damping >= 0 and finite, initial velocity finite).
/// @throws Error naming the key (dynamics.dt, ...)
void validate(const DynamicsOptions& options);

}  // namespace coarsegrain::sim
