#include "coarsegrain/coarsen/dynamics_run.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/coarsen/summary_json.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "coarsegrain/sim/phase.hpp"

namespace coarsegrain::coarsen {

namespace {

double seconds_since(std::chrono::steady_clock::time_point begin) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

double sum(const Timings& t) {
    double s = 0;
    for (const auto& [phase, seconds] : t.entries()) s += seconds;
    return s;
}

/// Steps one model (K, M, load f, conditions bc over its own DOFs) from the scene's start with
/// the initial velocity v0: corotated on `corotated` if given (the scene's "corotation"
/// options), else linear. Phases "initial state", "factorize" (linear: the step operator's)
/// and "per_step" go to `timings`.
sim::Trajectory step_model(const scene::Scene& sc, const SparseMatrix& K, const SparseMatrix& M,
                           const Vector& f, const fem::Dirichlet& bc, const Vector& v0,
                           const fem::CorotatedModel* corotated, const solve::SolverOptions& solver,
                           const std::string& name, Timings& timings) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    std::pair<sim::State, Vector> start;
    {
        const Phase phase("initial state", &timings);
        start = corotated
                    ? sim::corotated_initial_state(*corotated, f, bc, v0, o, sc.corotation, solver)
                    : sim::initial_state(K, f, bc, v0, o, solver);
    }
    sim::Trajectory run =
        corotated ? sim::simulate_corotated(*corotated, M, bc, start.first, start.second, o,
                                            sc.corotation, solver, name)
                  : sim::simulate(K, M, bc, start.first, start.second, o, solver, name);
    timings.add("factorize", run.factorize_seconds);
    timings.add("per_step", run.per_step_seconds);
    return run;
}

/// A run's energy and solves per saved frame (summary "frames") over its `steps` steps; of a
/// corotated run also its Krylov iterations and factorizations per frame.
nlohmann::json frames_json(const sim::Trajectory& t, int steps, bool corotated) {
    int solves = 0;
    for (const int i : t.iterations) solves += i;
    nlohmann::json j = {{"energy", t.energy},
                        {"energy_drift", t.energy_drift()},
                        {"solves", t.iterations},
                        {"solves_per_step", static_cast<double>(solves) / steps},
                        {"step_seconds", t.step_seconds}};
    if (corotated) {
        j["krylov_iterations"] = t.krylov_iterations;
        j["factorizations"] = t.factorizations;
    }
    return j;
}

/// A coarse model's sizes and timings for summary "coarse".
nlohmann::json coarse_json(const CoarseDynamics& c) {
    return {{"nodes", c.model.nodes},
            {"elements", c.model.elements},
            {"dofs", c.model.K.rows()},
            {"timings", timings_json(c.timings)}};
}

/// Runs fill() for one method of `methods`. With several methods a failure (Error but
/// Interrupted) is reported instead of thrown: observer.method_failed, and the message is
/// returned; with one it is thrown. Returns the empty string if fill() finished.
template <class Fill>
std::string try_method(const std::string& method, std::size_t methods, RunObserver& observer,
                       int& failed, Fill fill) {
    try {
        fill();
    } catch (const Interrupted&) {
        throw;
    } catch (const Error& err) {
        if (methods == 1) throw;
        observer.method_failed(method, err.what());
        ++failed;
        return err.what();
    }
    return {};
}

/// Whether `bytes` fit in half the physical memory (0 if unknown: assume they do).
bool fits_in_memory(double bytes) {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages <= 0 || page <= 0 || bytes <= 0.5 * static_cast<double>(pages) * page;
}

nlohmann::json probe_series(const ProbeSeries& probes, std::size_t p) {
    nlohmann::json series = nlohmann::json::array();
    for (const auto& at : probes) series.push_back(to_std(at[p]));
    return series;
}

/// The fine run every other run is compared with.
struct FineReference {
    const sim::Trajectory* run = nullptr;
    const ProbeSeries* probes = nullptr;
};

/// A run's saved frames on the fine mesh, u = frame(i) for each saved time i: each goes to the
/// observer as frame `i` of run `name` and is compared with the fine frame of the same time.
template <class Frame>
void compare_with_fine(const scene::Scene& sc, const mesh::Mesh& mesh, const FineReference& ref,
                       const std::vector<double>& times, Frame frame, const std::string& name,
                       RunObserver& observer, ModelDynamics& r) {
    const scene::ProbeSampler probes(sc, mesh);
    double diff2 = 0, norm2 = 0, probe_diff = 0, probe_max = 0;
    for (std::size_t i = 0; i < times.size(); ++i) {
        if (interrupt_requested()) throw Interrupted("interrupted while carrying frames");
        const Vector u = frame(i);
        r.probes.push_back(probes(u));
        const Vector& u_fine = ref.run->u[i];
        diff2 += (u - u_fine).squaredNorm();
        norm2 += u_fine.squaredNorm();
        for (std::size_t p = 0; p < sc.probes.size(); ++p) {
            probe_diff = std::max(probe_diff, (r.probes.back()[p] - (*ref.probes)[i][p]).norm());
            probe_max = std::max(probe_max, (*ref.probes)[i][p].norm());
        }
        observer.frame(name, i, times[i], u, &u_fine);
    }
    observer.run_done(name);
    r.trajectory_l2_rel = norm2 > 0 ? std::sqrt(diff2 / norm2) : std::sqrt(diff2);
    r.probe_max_rel = probe_max > 0 ? probe_diff / probe_max : probe_diff;
}

const char* axis_name(int d) { return d == 0 ? "x" : d == 1 ? "y" : "z"; }

/// A number, or null for none.
nlohmann::json optional_json(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
}

/// errors.phase: per probe, the coarse phase against the fine one (sim::compare_phase) on the
/// probe's dominant component, the one of largest fine range (max - min) over the run.
nlohmann::json phase_json(const std::vector<double>& times, const ProbeSeries& fine,
                          const ProbeSeries& coarse, std::size_t probes, int dim) {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t p = 0; p < probes; ++p) {
        int dominant = 0;
        double widest = -1;
        for (int d = 0; d < dim; ++d) {
            double lo = 0, hi = 0;
            for (const auto& at : fine) {
                lo = std::min(lo, at[p][d]);
                hi = std::max(hi, at[p][d]);
            }
            if (hi - lo > widest) {
                widest = hi - lo;
                dominant = d;
            }
        }
        std::vector<double> f, c;
        for (std::size_t i = 0; i < times.size(); ++i) {
            f.push_back(fine[i][p][dominant]);
            c.push_back(coarse[i][p][dominant]);
        }
        const sim::PhaseComparison ph = sim::compare_phase(times, f, c);
        out.push_back({{"component", axis_name(dominant)},
                       {"crossings_fine", ph.crossings_fine},
                       {"crossings", ph.crossings},
                       {"period_fine", optional_json(ph.period_fine)},
                       {"period", optional_json(ph.period)},
                       {"period_rel", optional_json(ph.period_rel)},
                       {"lag", optional_json(ph.lag)}});
    }
    return out;
}

/// A model's wall time per saved frame: output_every steps and the frame's warp, if any.
double frame_seconds(const Timings& t, const sim::DynamicsOptions& o) {
    return o.output_every * t["per_step"] + t["warp_per_frame"];
}

/// Steps the coarse model from the state matching the fine start (corotated if the scene's
/// kinematics are and the model has elements to rotate; else linear, and with "warp": "rs"
/// each frame is post-warped on the fine mesh), carries every saved frame to the fine mesh
/// and compares it with the fine frame of the same time. Its "frames" go to `frames`.
void run_coarse(const scene::Scene& sc, FineDynamics& fine, const FineReference& ref,
                CoarseDynamics& c, const std::string& method, RunObserver& observer,
                ModelDynamics& r, nlohmann::json& frames) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    const CoarseModel& m = c.model;
    // The initial velocity is one nodal velocity; the model's DOFs must be nodal displacements
    // (they are not where DOFs are held in combination, homogenize::carry_dirichlet).
    const int dim = fine.model.mesh.dim();
    CG_VERIFY(o.initial_velocity.isZero() || m.K.rows() == dim * m.nodes,
              "{}: dynamics.initial_velocity: the {} model's {} DOFs are not the displacements "
              "of its {} nodes (conditions held in combination), so a nodal velocity does not "
              "apply to them; start from rest or put coarse nodes on the clamped faces",
              sc.source, method, m.K.rows(), m.nodes);
    const Vector v0 = sim::uniform_field(m.K.rows(), o.initial_velocity);
    const bool corotated =
        sc.kinematics == sim::Kinematics::Corotational && m.element_model.has_value();
    std::optional<fem::CorotatedModel> model;
    if (corotated) model.emplace(corotated_model(m, sc.corotation.frame));
    sim::Trajectory run = step_model(
        sc, m.K, c.M, m.f, m.bc, v0, corotated ? &*model : nullptr,
        corotated ? node_solver_options(m, scene::direct_solver(sc)) : scene::direct_solver(sc),
        method, c.timings);
    frames = frames_json(run, o.steps, corotated);
    frames["kinematics"] = corotated ? "corotational" : "linear";
    const fem::RsWarp* warp = sc.rs_warp && !corotated ? &fine_warp(sc, fine) : nullptr;
    frames["warp"] = warp ? "rs" : "none";
    double warp_seconds = 0;
    const auto begin = std::chrono::steady_clock::now();
    compare_with_fine(
        sc, fine.model.mesh, ref, run.times,
        [&](std::size_t i) {
            Vector u = m.to_fine * run.u[i];
            if (warp) {
                const auto warp_begin = std::chrono::steady_clock::now();
                u = (*warp)(u);
                warp_seconds += seconds_since(warp_begin);
            }
            return u;
        },
        method, observer, r);
    if (warp) c.timings.add("warp_per_frame", warp_seconds / static_cast<double>(run.times.size()));
    c.timings.add("write frames", seconds_since(begin) - warp_seconds);
    r.u = std::move(run.u);
}

/// Steps the fine model from the scene's start (corotated with corotational kinematics; linear
/// otherwise, its frames post-warped with "warp": "rs") and hands its frames to the observer
/// (phase "write frames") with their probes.
sim::Trajectory run_fine(const scene::Scene& sc, FineDynamics& fine, RunObserver& observer,
                         ProbeSeries& probes) {
    const scene::FineModel& fm = fine.model;
    const Vector v0 = sim::uniform_field(fm.K.rows(), sc.dynamics->initial_velocity);
    sim::Trajectory run;
    if (sc.kinematics == sim::Kinematics::Corotational) {
        const fem::CorotatedModel model(fm.mesh, fm.materials, sc.formulation, sc.corotation.frame);
        solve::SolverOptions node_options = sc.solver;
        node_options.node_dofs = fm.mesh.dim();
        run = step_model(sc, fm.K, fine.M, fm.f, fm.bc, v0, &model, node_options, "fine",
                         fine.timings);
    } else {
        run = step_model(sc, fm.K, fine.M, fm.f, fm.bc, v0, nullptr, scene::fine_solver(sc, fm),
                         "fine", fine.timings);
        if (sc.rs_warp) {
            const fem::RsWarp& warp = fine_warp(sc, fine);
            const auto begin = std::chrono::steady_clock::now();
            for (Vector& u : run.u) u = warp(u);
            fine.timings.add("warp_per_frame",
                             seconds_since(begin) / static_cast<double>(run.u.size()));
        }
    }
    const Phase phase("write frames", &fine.timings);
    observer.fine_stepped(run);
    const scene::ProbeSampler sampler(sc, fm.mesh);
    for (std::size_t i = 0; i < run.times.size(); ++i) {
        probes.push_back(sampler(run.u[i]));
        observer.frame("fine", i, run.times[i], run.u[i], nullptr);
    }
    observer.run_done("fine");
    return run;
}

/// With corotational kinematics, the linear fine model's run beside the corotated one (what
/// corotation changes): carried and compared as a coarse model's, the run "fine-linear".
ModelDynamics run_fine_linear(const scene::Scene& sc, FineDynamics& fine, const FineReference& ref,
                              RunObserver& observer) {
    const scene::FineModel& fm = fine.model;
    Timings timings;
    const sim::Trajectory run =
        step_model(sc, fm.K, fine.M, fm.f, fm.bc,
                   sim::uniform_field(fm.K.rows(), sc.dynamics->initial_velocity), nullptr,
                   scene::fine_solver(sc, fm), "fine-linear", timings);
    ModelDynamics r;
    r.name = "fine-linear";
    compare_with_fine(
        sc, fm.mesh, ref, run.times, [&](std::size_t i) { return run.u[i]; }, r.name, observer, r);
    r.entry = {{"timings", timings_json(timings)},
               {"frames", frames_json(run, sc.dynamics->steps, false)},
               {"errors",
                {{"trajectory_l2_rel", r.trajectory_l2_rel}, {"probe_max_rel", r.probe_max_rel}}}};
    return r;
}

/// The summary with its method entries: one method's keys at the top level, several in
/// "methods" (with "failed_methods"); and the peak memory.
nlohmann::json with_methods(nlohmann::json summary, const std::vector<nlohmann::json>& entries,
                            int failed) {
    if (entries.size() == 1 && !entries[0].contains("error")) {
        summary.update(entries[0]);
    } else if (!entries.empty()) {
        summary["methods"] = entries;
        summary["failed_methods"] = failed;
    }
    summary["peak_memory_mb"] = peak_resident_mb();
    return summary;
}

nlohmann::json fine_json(const FineDynamics& f) {
    nlohmann::json j = fine_sizes(f.model);
    j["timings"] = timings_json(f.timings);
    return j;
}

const char* mass_name(fem::MassType mass) {
    return mass == fem::MassType::Consistent ? "consistent" : "lumped";
}

}  // namespace

FineDynamics fine_dynamics(const scene::FineModel& model, fem::MassType mass, Timings timings) {
    FineDynamics f{model, {}, std::move(timings), nullptr};
    const Phase phase("mass", &f.timings);
    f.M = fem::mass_matrix(model.mesh, model.materials, mass);
    return f;
}

const fem::RsWarp& fine_warp(const scene::Scene& sc, FineDynamics& fine) {
    if (!fine.warp) {
        const Phase phase("warp", &fine.timings);
        fine.warp =
            std::make_unique<fem::RsWarp>(fine.model.mesh, fine.model.bc, scene::direct_solver(sc));
    }
    return *fine.warp;
}

CoarseDynamics coarse_dynamics(CoarseModel model, const FineDynamics& fine, const scene::Scene& sc,
                               const std::string& method) {
    CoarseDynamics c;
    c.model = std::move(model);
    CG_VERIFY(static_cast<bool>(c.model.mass), "{}: method {} defines no coarse mass", sc.source,
              method);
    c.timings.add("build", sum(c.model.timings));
    const Phase phase("mass", &c.timings);
    c.M = c.model.mass(fine.M);
    return c;
}

CoarseDynamics build_coarse_dynamics(const scene::Scene& sc, const FineDynamics& fine,
                                     const std::string& method) {
    return coarse_dynamics(build_coarse_model(sc, fine.model, method), fine, sc, method);
}

void check_dynamics(const scene::Scene& sc) {
    CG_VERIFY_AS(InvalidScene, sc.dynamics.has_value(),
                 "{}: simulate needs a \"dynamics\" block (at least \"dt\" and \"steps\"; "
                 "docs/guide.md, \"Dynamics\")",
                 sc.source);
}

void check_frames_fit(const scene::Scene& sc, const scene::FineModel& fm) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    const double frames = 1.0 + o.steps / o.output_every;
    CG_VERIFY(fits_in_memory(frames * static_cast<double>(fm.K.rows()) * 8),
              "{}: dynamics.output_every: {:.0f} saved frames of {} DOFs need {:.1f} GB, more "
              "than half this machine's memory; save fewer frames",
              sc.source, frames, fm.K.rows(), frames * static_cast<double>(fm.K.rows()) * 8e-9);
}

SimulateResult simulate_models(const scene::Scene& sc, FineDynamics& fine,
                               const std::vector<std::string>& methods, const CoarseSource& source,
                               RunObserver& observer, bool keep_models) {
    check_dynamics(sc);
    const sim::DynamicsOptions& o = *sc.dynamics;
    const int dim = fine.model.mesh.dim();
    SimulateResult out;
    out.fine = run_fine(sc, fine, observer, out.fine_probes);
    out.fine_frames =
        frames_json(out.fine, o.steps, sc.kinematics == sim::Kinematics::Corotational);
    const FineReference ref{&out.fine, &out.fine_probes};
    if (sc.kinematics == sim::Kinematics::Corotational)
        out.fine_linear = run_fine_linear(sc, fine, ref, observer);

    for (const std::string& method : methods) {
        ModelDynamics& r = out.methods.emplace_back();
        r.name = method;
        const std::string error = try_method(method, methods.size(), observer, out.failed, [&] {
            CoarseDynamics c = source(method);
            observer.coarse_built(method, c);
            nlohmann::json frames;
            run_coarse(sc, fine, ref, c, method, observer, r, frames);
            nlohmann::json probes = nlohmann::json::array();
            for (std::size_t p = 0; p < sc.probes.size(); ++p)
                probes.push_back({{"point", to_std(sc.probes[p])},
                                  {"u_fine", probe_series(out.fine_probes, p)},
                                  {"u", probe_series(r.probes, p)}});
            nlohmann::json& e = r.entry;
            e = {{"method", method}};
            e["coarse"] = coarse_json(c);
            e["coarse"]["frames"] = frames;
            e["probes"] = probes;
            e["timings"] = {{"coarse", timings_json(c.timings)}};
            e["speedup"] = {
                {"per_step", out.fine.per_step_seconds / c.timings["per_step"]},
                {"per_frame", frame_seconds(fine.timings, o) / frame_seconds(c.timings, o)}};
            e["errors"] = {{"trajectory_l2_rel", r.trajectory_l2_rel},
                           {"probe_max_rel", r.probe_max_rel},
                           {"phase", phase_json(out.fine.times, out.fine_probes, r.probes,
                                                sc.probes.size(), dim)}};
            if (keep_models) r.coarse = std::move(c);
        });
        if (!error.empty()) {
            r = ModelDynamics{};
            r.name = method;
            r.error = error;
            r.entry = {{"method", method}, {"error", error}};
        }
    }
    return out;
}

nlohmann::json simulate_summary(const scene::Scene& sc, const FineDynamics& fine,
                                const SimulateResult& result, const nlohmann::json& top) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    nlohmann::json summary = top;
    summary.update({
        {"command", "simulate"},
        {"scene", sc.source},
        {"fine", fine_json(fine)},
        {"dynamics",
         {{"integrator", sim::integrator_name(o.integrator)},
          {"dt", o.dt},
          {"steps", o.steps},
          {"output_every", o.output_every},
          {"start", o.start == sim::Start::Rest ? "rest" : "static"},
          {"mass", mass_name(o.mass)}}},
        {"kinematics", sim::kinematics_name(sc.kinematics)},
        {"warp", sc.rs_warp ? "rs" : "none"},
        {"times", result.fine.times},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"warnings", fine.model.warnings},
    });
    summary["fine"]["frames"] = result.fine_frames;
    if (sc.kinematics == sim::Kinematics::Corotational) {
        const sim::CorotationOptions& c = sc.corotation;
        summary["corotation"] = {{"frame", fem::corotation_frame_name(c.frame)},
                                 {"tangent", sim::tangent_name(c.tangent)},
                                 {"step", sim::step_iterations_name(c.step)},
                                 {"linear_solve", sim::linear_solve_name(c.linear_solve)},
                                 {"tolerance", c.tolerance}};
        if (result.fine_linear) summary["fine"]["linear"] = result.fine_linear->entry;
    }
    nlohmann::json probes = nlohmann::json::array();
    for (std::size_t p = 0; p < sc.probes.size(); ++p)
        probes.push_back(
            {{"point", to_std(sc.probes[p])}, {"u_fine", probe_series(result.fine_probes, p)}});
    summary["probes"] = probes;
    summary["timings"] = {{"fine", timings_json(fine.timings)}};
    std::vector<nlohmann::json> entries;
    for (const ModelDynamics& r : result.methods) {
        nlohmann::json e = r.entry;
        // The fine timings are complete only now: every entry reports them.
        if (r.error.empty()) e["timings"]["fine"] = timings_json(fine.timings);
        entries.push_back(std::move(e));
    }
    return with_methods(std::move(summary), entries, result.failed);
}

ModesResult modes_models(const scene::Scene& sc, FineDynamics& fine,
                         const std::vector<std::string>& methods, int count, RunObserver& observer,
                         bool keep_models) {
    const scene::FineModel& fm = fine.model;
    ModesResult out;
    {
        const Phase phase("eigenpairs", &fine.timings);
        out.fine = sim::modes(fm.K, fine.M, fm.bc, count, scene::fine_solver(sc, fm));
    }
    const Index k = out.fine.eigenvalues.size();
    for (const std::string& method : methods) {
        ModesMethod& r = out.methods.emplace_back();
        r.method = method;
        const std::string error = try_method(method, methods.size(), observer, out.failed, [&] {
            CoarseDynamics c = build_coarse_dynamics(sc, fine, method);
            observer.coarse_built(method, c);
            {
                const Phase phase("eigenpairs", &c.timings);
                r.modes = sim::modes(c.model.K, c.M, c.model.bc, count, scene::direct_solver(sc));
            }
            r.carried = c.model.to_fine * r.modes.vectors;
            r.pairs = sim::pair_modes(out.fine.vectors, r.carried);
            std::vector<double> rel, mac, paired;
            for (Index i = 0; i < k; ++i) {
                const sim::ModePair& p = r.pairs[static_cast<std::size_t>(i)];
                const double fc = r.modes.frequencies_hz[p.coarse];
                const double ff = out.fine.frequencies_hz[i];
                rel.push_back(std::abs(fc - ff) / ff);
                mac.push_back(p.mac);
                paired.push_back(static_cast<double>(p.coarse));
            }
            nlohmann::json& e = r.entry;
            e = {{"method", method}};
            e["coarse"] = coarse_json(c);
            e["coarse"]["frequencies_hz"] = to_std(r.modes.frequencies_hz);
            e["errors"] = {{"frequency_rel", rel}};
            e["mac"] = mac;
            e["mac_pairs"] = paired;
            if (keep_models) r.coarse = std::move(c);
        });
        if (!error.empty()) {
            r = ModesMethod{};
            r.method = method;
            r.error = error;
            r.entry = {{"method", method}, {"error", error}};
        }
    }
    return out;
}

nlohmann::json modes_summary(const scene::Scene& sc, const FineDynamics& fine,
                             const ModesResult& result, const nlohmann::json& top) {
    const fem::MassType mass = sc.dynamics ? sc.dynamics->mass : fem::MassType::Consistent;
    nlohmann::json fj = fine_json(fine);
    fj["frequencies_hz"] = to_std(result.fine.frequencies_hz);
    nlohmann::json summary = top;
    summary.update({{"command", "modes"},
                    {"scene", sc.source},
                    {"fine", fj},
                    {"count", result.fine.eigenvalues.size()},
                    {"mass", mass_name(mass)},
                    {"solver", solve::backend_name(sc.solver.backend)},
                    {"threads", omp_get_max_threads()},
                    {"warnings", fine.model.warnings}});
    std::vector<nlohmann::json> entries;
    for (const ModesMethod& r : result.methods) entries.push_back(r.entry);
    return with_methods(std::move(summary), entries, result.failed);
}

}  // namespace coarsegrain::coarsen
