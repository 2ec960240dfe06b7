#pragma once
/// @file Static equilibrium of corotated linear elasticity (Kharevych et al. 2009, Sec. 4) by
/// Newton's method with a line search and load increments, for the fine model and every coarse
/// element model alike (scene "kinematics": "corotational").
#include <string>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/corotation.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::sim {

/// Newton's method did not reach its tolerance at the smallest load increment (not a singular
/// model: that is NotPositiveDefinite).
class NewtonFailed : public Error {
  public:
    using Error::Error;
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
    /// Halvings of a load increment (from the whole load) before the solve gives up.
    int max_bisections = 10;
};

/// One Newton iteration.
struct NewtonIteration {
    double load_factor = 0;  ///< λ of the increment: load λ f, prescribed values λ u_D
    double residual = 0;     ///< relative residual after the iteration
    double step = 0;         ///< line-search step length taken (1: the full Newton step)
};

/// How a corotated solve went.
struct NewtonReport {
    int iterations = 0;  ///< Newton iterations (tangent factorizations), failed increments included
    int increments = 0;  ///< load increments that converged (1 if the whole load converged)
    int bisections = 0;  ///< increments halved after failing
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

}  // namespace coarsegrain::sim
