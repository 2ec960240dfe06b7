#pragma once
/// @file Dynamic runs as a scene defines them, computed in memory: the time stepping of
/// `coarsegrain simulate` (the fine model and each method's coarse model stepped from the scene's
/// start, every saved coarse frame carried to the fine mesh and compared with the fine frame of
/// the same time) and the natural modes of `coarsegrain modes` (fine and coarse, paired by the
/// modal assurance criterion). The command-line tool writes their files and summary.json from
/// these results; the Python module returns them as arrays.
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"

namespace coarsegrain::coarsen {

/// The fine model of a dynamic run, with its mass.
struct FineDynamics {
    const scene::FineModel& model;  ///< held by reference: it must outlive the run
    SparseMatrix M;                 ///< num_dofs square mass (consistent or lumped)
    /// The model's phases so far (e.g. "read", "assemble"), "mass", then the run's: "initial
    /// state", "factorize", "per_step" (seconds per step), ["warp", "warp_per_frame"], "write
    /// frames" (probes and the observer's frames), [modes: "eigenpairs"]
    Timings timings;
    /// The RS post-warp of fine displacements, factorized on first use (phase "warp").
    std::unique_ptr<fem::RsWarp> warp;
};

/// The fine model with its mass of type `mass` (phase "mass", appended to `timings`).
FineDynamics fine_dynamics(const scene::FineModel& model, fem::MassType mass, Timings timings = {});

/// The run's RS post-warp (scene "warp": "rs") of fine displacements (Chen et al. 2019, Eq. 13),
/// factorized on first use (phase "warp" of fine.timings).
const fem::RsWarp& fine_warp(const scene::Scene& scene, FineDynamics& fine);

/// A coarse model and its mass for the fine mass.
struct CoarseDynamics {
    CoarseModel model;
    SparseMatrix M;  ///< coarse DOFs square: model.mass(fine.M)
    /// "build" (the sum of the model's build phases), "mass", then the run's: "initial state",
    /// "factorize", "per_step", ["warp_per_frame"], "write frames"; modes: "eigenpairs"
    Timings timings;
};

/// The coarse model built for `method` with its mass for the fine model's (phases "build" and
/// "mass").
/// @throws Error naming the scene's source and the method if it defines no coarse mass
CoarseDynamics coarse_dynamics(CoarseModel model, const FineDynamics& fine,
                               const scene::Scene& scene, const std::string& method);

/// Builds the method's coarse model (build_coarse_model) with its mass (coarse_dynamics).
/// @throws as build_coarse_model, coarse_dynamics
CoarseDynamics build_coarse_dynamics(const scene::Scene& scene, const FineDynamics& fine,
                                     const std::string& method);

/// Checks that the scene has a "dynamics" block, as a simulate run needs.
/// @throws InvalidScene naming the scene otherwise
void check_dynamics(const scene::Scene& scene);

/// Checks before a run that its saved frames of the fine model (1 + steps / output_every
/// vectors of num_dofs doubles) fit in half this machine's memory.
/// @throws Error naming dynamics.output_every otherwise
void check_frames_fit(const scene::Scene& scene, const scene::FineModel& fine);

/// Displacements at the scene's probes over a run: [saved time][probe], each of size dim.
using ProbeSeries = std::vector<std::vector<Eigen::VectorXd>>;

/// What a dynamic run hands out while it runs (the command-line tool writes its files from
/// these calls). Every function does nothing by default. Calls come from the thread that runs
/// simulate_models / modes_models.
class RunObserver {
  public:
    virtual ~RunObserver() = default;
    /// The fine model has been stepped: `fine` holds its saved frames (all fine DOFs, post-warped
    /// with "warp": "rs" and linear kinematics), before any of them is handed to frame().
    virtual void fine_stepped(const sim::Trajectory& /*fine*/) {}
    /// Saved frame i (of time `time`) of the run `name` on the fine mesh (all fine DOFs): "fine",
    /// "fine-linear" (corotational kinematics) or a method's carried coarse frame. `reference`
    /// is the fine frame it is compared with (nullptr for the fine run itself).
    virtual void frame(const std::string& /*name*/, std::size_t /*i*/, double /*time*/,
                       const Vector& /*u*/, const Vector* /*reference*/) {}
    /// Every frame of the run `name` has been handed to frame().
    virtual void run_done(const std::string& /*name*/) {}
    /// A method's coarse model has been built, with its mass, and is about to run.
    virtual void coarse_built(const std::string& /*method*/, const CoarseDynamics& /*coarse*/) {}
    /// A method of several failed with this message (its result holds it as `error`; the
    /// others still run). With one method the failure is thrown instead.
    virtual void method_failed(const std::string& /*method*/, const std::string& /*message*/) {}
};

/// Where a run's coarse models come from: built for the method, or built beforehand.
using CoarseSource = std::function<CoarseDynamics(const std::string& method)>;

/// One model's run against the fine one, on the fine mesh.
struct ModelDynamics {
    std::string name;   ///< the method, or "fine-linear"
    std::string error;  ///< why the method failed (with several methods), empty if it ran
    ProbeSeries probes;
    /// sqrt(sum_i |u_i - u_fine,i|² / sum_i |u_fine,i|²) over the saved frames i (all fine DOFs)
    double trajectory_l2_rel = 0;
    /// max_i,p |probe_p(u_i) - probe_p(u_fine,i)| / max_i,p |probe_p(u_fine,i)|
    double probe_max_rel = 0;
    /// The run's saved frames on its own DOFs (a method: the coarse DOFs; empty for
    /// "fine-linear", whose frames only pass through RunObserver::frame).
    std::vector<Vector> u;
    /// Its summary.json entry (`coarsegrain simulate`): "method", "coarse" {"nodes", "elements",
    /// "dofs", "timings", "frames"}, "probes" [{"point", "u_fine", "u"}], "timings" {"coarse"},
    /// "speedup" {"per_step", "per_frame"}, "errors" {"trajectory_l2_rel", "probe_max_rel",
    /// "phase"}; or {"method", "error"} if it failed. "fine-linear": "timings", "frames",
    /// "errors" {"trajectory_l2_rel", "probe_max_rel"}. The fine timings ("timings" "fine") are
    /// added by simulate_summary.
    nlohmann::json entry;
    /// The coarse model, if the run keeps it (simulate_models' keep_models).
    std::optional<CoarseDynamics> coarse;
};

/// A simulate run: the fine run, with corotational kinematics the linear fine run beside it,
/// and each method's run.
struct SimulateResult {
    sim::Trajectory fine;  ///< saved times and frames of the fine model, post-warped if asked
    ProbeSeries fine_probes;
    nlohmann::json fine_frames;  ///< summary "fine" "frames": energy and solves per frame
    std::optional<ModelDynamics> fine_linear;  ///< corotational kinematics only
    std::vector<ModelDynamics> methods;        ///< in the order of the methods given
    int failed = 0;                            ///< methods that failed
};

/// Steps the fine model from the scene's start (corotated with "kinematics": "corotational",
/// else linear and post-warped with "warp": "rs"; with corotation also the linear fine model,
/// run "fine-linear") and the coarse model that `source` gives for each method (corotated if
/// the scene's kinematics are and it has elements to rotate, else linear, its frames post-warped
/// on the fine mesh with "warp": "rs"), carries every saved frame to the fine mesh (`observer`
/// sees each one), and compares it with the fine frame of the same time: trajectory and probe
/// errors, and per probe the phase of its dominant component (sim::compare_phase). With several
/// methods a method that fails is reported (observer.method_failed, its entry's "error") and
/// the others still run. Phases go to fine.timings and each method's timings.
/// @param keep_models  keep each coarse model in its result (otherwise it is freed once it ran)
/// @throws InvalidScene if the scene has no "dynamics" block (check_dynamics) or a probe lies
///         outside the mesh;
///         as the solvers; the failure of the only method; Interrupted between steps
SimulateResult simulate_models(const scene::Scene& scene, FineDynamics& fine,
                               const std::vector<std::string>& methods, const CoarseSource& source,
                               RunObserver& observer, bool keep_models = false);

/// The summary.json of a simulate run (`coarsegrain simulate` without its files): "command",
/// "scene", "fine" {sizes, "timings", "frames", ["linear"]}, "dynamics", "kinematics", "warp",
/// "times", "solver", "threads", "warnings", ["corotation"], "probes", "timings" {"fine"}, the
/// method entries (one method's keys at the top level, several in "methods" with
/// "failed_methods"; each gets "timings" "fine") and "peak_memory_mb".
/// @param top  keys set at the top level before the method entries (a single method's entry
///             overrides those it shares, e.g. "pvd")
nlohmann::json simulate_summary(const scene::Scene& scene, const FineDynamics& fine,
                                const SimulateResult& result,
                                const nlohmann::json& top = nlohmann::json::object());

/// A method's modes against the fine ones.
struct ModesMethod {
    std::string method;
    std::string error;  ///< why the method failed (with several methods), empty if it ran
    sim::Modes modes;   ///< the coarse model's eigenpairs, vectors over the coarse DOFs
    Matrix carried;     ///< fine DOFs x modes: the coarse mode shapes on the fine mesh
    /// Per fine mode, its coarse mode (sim::pair_modes on the carried shapes) and their MAC.
    std::vector<sim::ModePair> pairs;
    /// Its summary.json entry (`coarsegrain modes`): "method", "coarse" {"nodes", "elements",
    /// "dofs", "timings", "frequencies_hz"}, "errors" {"frequency_rel"} (per fine mode, against
    /// its paired coarse mode), "mac", "mac_pairs"; or {"method", "error"}.
    nlohmann::json entry;
    std::optional<CoarseDynamics> coarse;  ///< the coarse model, if kept
};

/// A modes run: the fine model's lowest modes and each method's.
struct ModesResult {
    sim::Modes fine;  ///< vectors over all fine DOFs
    std::vector<ModesMethod> methods;
    int failed = 0;
};

/// The `count` lowest natural frequencies and modes (K φ = ω² M φ with the Dirichlet DOFs held)
/// of the fine model (phase "eigenpairs" of fine.timings) and of each method's coarse model
/// (built by build_coarse_dynamics), the coarse modes carried to the fine mesh and paired with
/// the fine ones by the modal assurance criterion. Failures of several methods are reported as
/// simulate_models does (observer.method_failed).
/// @throws as sim::modes; the failure of the only method
ModesResult modes_models(const scene::Scene& scene, FineDynamics& fine,
                         const std::vector<std::string>& methods, int count, RunObserver& observer,
                         bool keep_models = false);

/// The summary.json of a modes run (`coarsegrain modes` without its files): "command", "scene",
/// "fine" {sizes, "timings", "frequencies_hz"}, "count", "mass", "solver", "threads",
/// "warnings", the method entries (as simulate_summary) and "peak_memory_mb".
/// @param top  keys set at the top level before the method entries (e.g. "plots")
nlohmann::json modes_summary(const scene::Scene& scene, const FineDynamics& fine,
                             const ModesResult& result,
                             const nlohmann::json& top = nlohmann::json::object());

}  // namespace coarsegrain::coarsen
