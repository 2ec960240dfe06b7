#include "run_dynamics.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "animation.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/io/table.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"
#include "coarsegrain/sim/phase.hpp"
#include "export.hpp"
#include "output.hpp"
#include "plots.hpp"

namespace coarsegrain::app {

namespace {

namespace fs = std::filesystem;

/// The fine model (held by reference: it outlives the run) with its mass.
struct FineDynamics {
    const scene::FineModel& model;
    SparseMatrix M;
    Timings timings;  ///< the model's phases so far, "mass", then the run's
    /// The RS post-warp on the fine mesh, factorized on first use (phase "warp").
    std::unique_ptr<fem::RsWarp> warp;
};

double seconds_since(std::chrono::steady_clock::time_point begin) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

/// The run's RS post-warp (scene "warp": "rs") of fine displacements, factorized on first use:
/// only a run with a linear model to warp pays for it.
const fem::RsWarp& fine_warp(const scene::Scene& sc, FineDynamics& fine) {
    if (!fine.warp) {
        const Phase phase("warp", &fine.timings);
        fine.warp = std::make_unique<fem::RsWarp>(fine.model.mesh, fine.model.bc, sc.solver);
    }
    return *fine.warp;
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

FineDynamics with_fine_mass(const scene::FineModel& model, fem::MassType mass, Timings timings) {
    FineDynamics f{model, {}, std::move(timings), nullptr};
    const Phase phase("mass", &f.timings);
    f.M = fem::mass_matrix(model.mesh, model.materials, mass);
    return f;
}

/// The scene's fine model, its phases ("read" = read_seconds, then the assembly's) in `timings`.
scene::FineModel build_fine(const scene::Scene& sc, double read_seconds, Timings& timings) {
    timings.add("read", read_seconds);
    scene::FineModel model = scene::build_fine_model(sc, &timings);
    print_warnings(model.warnings);
    return model;
}

double sum(const Timings& t) {
    double s = 0;
    for (const auto& [phase, seconds] : t.entries()) s += seconds;
    return s;
}

/// A coarse model and its mass for the fine mass M, with the phase "mass" in its timings.
struct CoarseDynamics {
    coarsen::CoarseModel model;
    SparseMatrix M;
    Timings timings;  ///< "build" (the method's phases summed), "mass", then the run's
};

/// A built coarse model with its mass for the fine model's.
CoarseDynamics with_mass(coarsen::CoarseModel model, const FineDynamics& fine,
                         const std::string& source, const std::string& method) {
    CoarseDynamics c;
    c.model = std::move(model);
    CG_VERIFY(static_cast<bool>(c.model.mass), "{}: method {} defines no coarse mass", source,
              method);
    c.timings.add("build", sum(c.model.timings));
    const Phase phase("mass", &c.timings);
    c.M = c.model.mass(fine.M);
    return c;
}

CoarseDynamics build_coarse(const scene::Scene& sc, const FineDynamics& fine,
                            const std::string& method) {
    return with_mass(coarsen::build_coarse_model(sc, fine.model, method), fine, sc.source, method);
}

/// A coarse model's sizes and timings for summary "coarse".
nlohmann::json coarse_json(const CoarseDynamics& c) {
    return {{"nodes", c.model.nodes},
            {"elements", c.model.elements},
            {"dofs", c.model.K.rows()},
            {"timings", timings_json(c.timings)}};
}

/// The summary entry of one method, {"method": method} completed by fill(entry). With several
/// methods a failure is reported instead of thrown, as `coarsen` does: on stderr, as the entry's
/// "error", and counted in `failed`; the method's files (DIR/<method>, DIR/<method>.pvd) are
/// removed.
template <class Fill>
nlohmann::json method_entry(const std::string& method, std::size_t methods, const fs::path& dir,
                            int& failed, Fill fill) {
    nlohmann::json e = {{"method", method}};
    try {
        fill(e);
    } catch (const Error& err) {
        if (methods == 1) throw;
        std::error_code ec;
        fs::remove_all(dir / method, ec);
        fs::remove(dir / (method + ".pvd"), ec);
        std::fprintf(stderr, "coarsegrain: method %s failed: %s\n", method.c_str(), err.what());
        e = {{"method", method}, {"error", err.what()}};
        ++failed;
    }
    return e;
}

/// Whether `bytes` fit in half the physical memory (0 if unknown: assume they do).
bool fits_in_memory(double bytes) {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages <= 0 || page <= 0 || bytes <= 0.5 * static_cast<double>(pages) * page;
}

/// Checks before the run that its saved frames of the fine model fit in memory.
void check_frames_fit(const scene::Scene& sc, const scene::FineModel& fm) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    const double frames = 1.0 + o.steps / o.output_every;
    CG_VERIFY(fits_in_memory(frames * static_cast<double>(fm.K.rows()) * 8),
              "{}: dynamics.output_every: {:.0f} saved frames of {} DOFs need {:.1f} GB, more "
              "than half this machine's memory; save fewer frames",
              sc.source, frames, fm.K.rows(), frames * static_cast<double>(fm.K.rows()) * 8e-9);
}

std::string frame_file(const std::string& series, std::size_t i) {
    return fmt::format("{}/frame_{:05d}.vtu", series, i);
}

/// Writes one frame of a series (displacement, its magnitude, and its error against `reference`
/// if given) and returns its (time, file) for the .pvd.
std::pair<double, std::string> write_frame(const fs::path& dir, const std::string& series,
                                           std::size_t i, double time, const mesh::Mesh& mesh,
                                           const Vector& u, const Vector* reference) {
    const int dim = mesh.dim();
    io::VtuFields fields;
    fields.add_point_vector("displacement", u, dim);
    fields.add_point_scalar("displacement_magnitude", nodal_magnitude(u, dim));
    if (reference) fields.add_point_vector("error", u - *reference, dim);
    const std::string file = frame_file(series, i);
    io::write_vtu((dir / file).string(), mesh, fields);
    return {time, file};
}

/// One model's run carried to the fine mesh: probe trajectories, its errors against the fine
/// trajectory, and its frames for the animation.
struct RunResult {
    std::vector<std::vector<Eigen::VectorXd>> probes;  ///< [time][probe]
    double trajectory_l2_rel = 0, probe_max_rel = 0;
    std::vector<float> animation;  ///< append_animation_frame of each frame shown
};

nlohmann::json probe_series(const std::vector<std::vector<Eigen::VectorXd>>& probes,
                            std::size_t p) {
    nlohmann::json series = nlohmann::json::array();
    for (const auto& at : probes) series.push_back(to_std(at[p]));
    return series;
}

/// The fine run every coarse run is compared with, and what the run writes.
struct FineReference {
    const sim::Trajectory* run = nullptr;
    RunResult result;
    AnimationView view;
    std::vector<std::size_t> shown;  ///< the saved frames the animation shows
    bool series = true;              ///< whether the ParaView series are written
};

/// A model's saved frames on the fine mesh, u = frame(i) for each saved time i: its probes and
/// animation frames go to `r`, then compare(u, i) runs (if given), and the frame is written to
/// the series `name` (DIR/<name>/, DIR/<name>.pvd) if the run writes series, with its error
/// against the fine frame if `with_error`.
template <class Frame>
void carry_frames(const scene::Scene& sc, const mesh::Mesh& mesh, const FineReference& ref,
                  const std::vector<double>& times, Frame frame, const std::string& name,
                  const fs::path& dir, bool with_error, RunResult& r,
                  const std::function<void(const Vector& u, std::size_t i)>& compare) {
    const scene::ProbeSampler probes(sc, mesh);
    std::vector<std::pair<double, std::string>> written;
    if (ref.series) fs::create_directories(dir / name);
    std::size_t next_shown = 0;
    for (std::size_t i = 0; i < times.size(); ++i) {
        const Vector u = frame(i);
        r.probes.push_back(probes(u));
        if (compare) compare(u, i);
        if (next_shown < ref.shown.size() && ref.shown[next_shown] == i) {
            append_animation_frame(ref.view, u, r.animation);
            ++next_shown;
        }
        if (ref.series)
            written.push_back(write_frame(dir, name, i, times[i], mesh, u,
                                          with_error ? &ref.run->u[i] : nullptr));
    }
    if (ref.series) io::write_pvd((dir / (name + ".pvd")).string(), written);
}

/// A run's frames on the fine mesh, u = frame(i) for each saved time i, carried (carry_frames:
/// probes, animation, the series `name` with its error) and compared with the fine frame of
/// the same time.
template <class Frame>
RunResult compare_with_fine(const scene::Scene& sc, const mesh::Mesh& mesh,
                            const FineReference& ref, const std::vector<double>& times, Frame frame,
                            const std::string& name, const fs::path& dir) {
    RunResult r;
    double diff2 = 0, norm2 = 0, probe_diff = 0, probe_max = 0;
    const std::vector<std::vector<Eigen::VectorXd>>& fine_probes = ref.result.probes;
    const auto compare = [&](const Vector& u, std::size_t i) {
        const Vector& u_fine = ref.run->u[i];
        diff2 += (u - u_fine).squaredNorm();
        norm2 += u_fine.squaredNorm();
        for (std::size_t p = 0; p < sc.probes.size(); ++p) {
            probe_diff = std::max(probe_diff, (r.probes.back()[p] - fine_probes[i][p]).norm());
            probe_max = std::max(probe_max, fine_probes[i][p].norm());
        }
    };
    carry_frames(sc, mesh, ref, times, frame, name, dir, true, r, compare);
    r.trajectory_l2_rel = norm2 > 0 ? std::sqrt(diff2 / norm2) : std::sqrt(diff2);
    r.probe_max_rel = probe_max > 0 ? probe_diff / probe_max : probe_diff;
    return r;
}

/// Steps the coarse model from the state matching the fine start (corotated if the scene's
/// kinematics are and the model has elements to rotate; else linear, and with "warp": "rs"
/// each frame is post-warped on the fine mesh), carries every saved frame to the fine mesh
/// and compares it with the fine frame of the same time. Its "frames" go to `frames`.
RunResult run_coarse(const scene::Scene& sc, FineDynamics& fine, const FineReference& ref,
                     CoarseDynamics& c, const std::string& method, const fs::path& dir,
                     nlohmann::json& frames) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    const coarsen::CoarseModel& m = c.model;
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
    if (corotated) model.emplace(coarsen::corotated_model(m, sc.corotation.frame));
    const sim::Trajectory run = step_model(
        sc, m.K, c.M, m.f, m.bc, v0, corotated ? &*model : nullptr,
        corotated ? coarsen::node_solver_options(m, sc.solver) : sc.solver, method, c.timings);
    frames = frames_json(run, o.steps, corotated);
    frames["kinematics"] = corotated ? "corotational" : "linear";
    const fem::RsWarp* warp = sc.rs_warp && !corotated ? &fine_warp(sc, fine) : nullptr;
    frames["warp"] = warp ? "rs" : "none";
    double warp_seconds = 0;
    const auto begin = std::chrono::steady_clock::now();
    RunResult r = compare_with_fine(
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
        method, dir);
    if (warp) c.timings.add("warp_per_frame", warp_seconds / static_cast<double>(run.times.size()));
    c.timings.add("write frames", seconds_since(begin) - warp_seconds);
    return r;
}

const char* axis_name(int d) { return d == 0 ? "x" : d == 1 ? "y" : "z"; }

/// trajectory.csv: time, then <model>_p<probe>_<axis> for the fine model and each method.
io::Table trajectory_table(const std::vector<double>& times,
                           const std::vector<std::pair<std::string, const RunResult*>>& runs,
                           std::size_t probes, int dim) {
    io::Table t;
    t.name = "trajectory";
    t.columns.push_back("time");
    for (const auto& [name, run] : runs)
        for (std::size_t p = 0; p < probes; ++p)
            for (int d = 0; d < dim; ++d)
                t.columns.push_back(fmt::format("{}_p{}_{}", name, p, axis_name(d)));
    t.values.resize(static_cast<Index>(times.size()), static_cast<Index>(t.columns.size()));
    for (std::size_t i = 0; i < times.size(); ++i) {
        Index c = 0;
        t.values(static_cast<Index>(i), c++) = times[i];
        for (const auto& [name, run] : runs)
            for (std::size_t p = 0; p < probes; ++p)
                for (int d = 0; d < dim; ++d)
                    t.values(static_cast<Index>(i), c++) = run->probes[i][p][d];
    }
    return t;
}

/// A number, or null for none.
nlohmann::json optional_json(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
}

/// errors.phase: per probe, the coarse phase against the fine one (sim::compare_phase) on the
/// probe's dominant component, the one of largest fine range (max - min) over the run.
nlohmann::json phase_json(const std::vector<double>& times, const RunResult& fine,
                          const RunResult& coarse, std::size_t probes, int dim) {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t p = 0; p < probes; ++p) {
        int dominant = 0;
        double widest = -1;
        for (int d = 0; d < dim; ++d) {
            double lo = 0, hi = 0;
            for (const auto& at : fine.probes) {
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
            f.push_back(fine.probes[i][p][dominant]);
            c.push_back(coarse.probes[i][p][dominant]);
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
    summary["peak_memory_mb"] = peak_rss_mb();
    return summary;
}

nlohmann::json fine_json(const FineDynamics& f) {
    nlohmann::json j = fine_sizes(f.model);
    j["timings"] = timings_json(f.timings);
    return j;
}

/// Steps the fine model from the scene's start (corotated with corotational kinematics; linear
/// otherwise, its frames post-warped with "warp": "rs") and carries its frames (probes,
/// animation, the series "fine" if written).
sim::Trajectory run_fine(const scene::Scene& sc, FineDynamics& fine, FineReference& ref,
                         const fs::path& dir) {
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
        run =
            step_model(sc, fm.K, fine.M, fm.f, fm.bc, v0, nullptr, sc.solver, "fine", fine.timings);
        if (sc.rs_warp) {
            const fem::RsWarp& warp = fine_warp(sc, fine);
            const auto begin = std::chrono::steady_clock::now();
            for (Vector& u : run.u) u = warp(u);
            fine.timings.add("warp_per_frame",
                             seconds_since(begin) / static_cast<double>(run.u.size()));
        }
    }
    const Phase phase("write frames", &fine.timings);
    ref.view = animation_view(fm.mesh, fm.boundary, run.u);
    ref.shown = animation_frames(run.times.size());
    carry_frames(sc, fm.mesh, ref, run.times, [&](std::size_t i) { return run.u[i]; }, "fine", dir,
                 false, ref.result, {});
    return run;
}

/// With corotational kinematics, the linear fine model's run beside the corotated one (what
/// corotation changes): carried and compared as a coarse model's, the series "fine-linear".
RunResult run_fine_linear(const scene::Scene& sc, FineDynamics& fine, const FineReference& ref,
                          const fs::path& dir, nlohmann::json& entry) {
    const scene::FineModel& fm = fine.model;
    Timings timings;
    const sim::Trajectory run =
        step_model(sc, fm.K, fine.M, fm.f, fm.bc,
                   sim::uniform_field(fm.K.rows(), sc.dynamics->initial_velocity), nullptr,
                   sc.solver, "fine-linear", timings);
    RunResult r = compare_with_fine(
        sc, fm.mesh, ref, run.times, [&](std::size_t i) { return run.u[i]; }, "fine-linear", dir);
    entry = {{"timings", timings_json(timings)},
             {"frames", frames_json(run, sc.dynamics->steps, false)},
             {"errors",
              {{"trajectory_l2_rel", r.trajectory_l2_rel}, {"probe_max_rel", r.probe_max_rel}}}};
    if (ref.series) entry["pvd"] = "fine-linear.pvd";
    return r;
}

/// Writes animation_data.bin and makes animation.gif from it (phase "animation" of the fine
/// timings); returns whether the GIF was made.
bool write_animation(const scene::Scene& sc, FineDynamics& fine, const FineReference& ref,
                     const std::vector<std::pair<std::string, const RunResult*>>& runs,
                     const fs::path& dir) {
    const Phase phase("animation", &fine.timings);
    std::vector<double> times;
    for (const std::size_t i : ref.shown) times.push_back(ref.run->times[i]);
    std::vector<AnimationModel> models;
    for (const auto& [name, run] : runs) models.push_back({name, &run->animation});
    write_animation_data((dir / "animation_data.bin").string(), sc.source, fine.model.mesh,
                         ref.view, times, models);
    return make_plot(
        dir.string(),
        {"plot_animation.py", {"animation.gif", "animation_data.bin"}, {"animation.gif"}});
}

/// A model's wall time per saved frame: output_every steps and the frame's warp, if any.
double frame_seconds(const Timings& t, const sim::DynamicsOptions& o) {
    return o.output_every * t["per_step"] + t["warp_per_frame"];
}

using CoarseSource = std::function<CoarseDynamics(const std::string& method)>;

/// What simulate_models made: the summary (not yet written) and the methods that failed.
struct SimulateRun {
    nlohmann::json summary;
    int failed = 0;
};

/// The run shared by `simulate` and the demo: steps the fine model and the coarse model that
/// `source` gives for each method, compares them and writes every file but summary.json to
/// `dir` (the ParaView series only if `series`).
SimulateRun simulate_models(const scene::Scene& sc, FineDynamics& fine,
                            const std::vector<std::string>& methods, const CoarseSource& source,
                            const fs::path& dir, bool series, const Exports& exports = {}) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    const scene::FineModel& fm = fine.model;
    const int dim = fm.mesh.dim();
    FineReference ref;
    ref.series = series;
    const sim::Trajectory run = run_fine(sc, fine, ref, dir);
    ref.run = &run;
    nlohmann::json fine_linear;
    RunResult fine_linear_result;
    if (sc.kinematics == sim::Kinematics::Corotational)
        fine_linear_result = run_fine_linear(sc, fine, ref, dir, fine_linear);

    std::vector<RunResult> results(methods.size());
    std::vector<nlohmann::json> entries;
    SimulateRun out;
    for (std::size_t k = 0; k < methods.size(); ++k) {
        const std::string& method = methods[k];
        entries.push_back(
            method_entry(method, methods.size(), dir, out.failed, [&](nlohmann::json& e) {
                CoarseDynamics c = source(method);
                if (exports.calculix) {
                    fs::create_directories(dir / method);
                    write_export(sc, fm, c.model, dir / method, &c.M);
                }
                nlohmann::json frames;
                results[k] = run_coarse(sc, fine, ref, c, method, dir, frames);
                nlohmann::json probes = nlohmann::json::array();
                for (std::size_t p = 0; p < sc.probes.size(); ++p)
                    probes.push_back({{"point", to_std(sc.probes[p])},
                                      {"u_fine", probe_series(ref.result.probes, p)},
                                      {"u", probe_series(results[k].probes, p)}});
                e["coarse"] = coarse_json(c);
                e["coarse"]["frames"] = frames;
                e["probes"] = probes;
                e["timings"] = {{"coarse", timings_json(c.timings)}};
                e["speedup"] = {
                    {"per_step", run.per_step_seconds / c.timings["per_step"]},
                    {"per_frame", frame_seconds(fine.timings, o) / frame_seconds(c.timings, o)}};
                e["errors"] = {{"trajectory_l2_rel", results[k].trajectory_l2_rel},
                               {"probe_max_rel", results[k].probe_max_rel},
                               {"phase", phase_json(run.times, ref.result, results[k],
                                                    sc.probes.size(), dim)}};
                if (series) e["pvd"] = method + ".pvd";
            }));
    }

    std::vector<std::pair<std::string, const RunResult*>> runs = {{"fine", &ref.result}};
    if (!fine_linear.is_null()) runs.emplace_back("fine-linear", &fine_linear_result);
    for (std::size_t k = 0; k < methods.size(); ++k)
        if (!entries[k].contains("error")) runs.emplace_back(methods[k], &results[k]);
    io::write_csv(trajectory_table(run.times, runs, sc.probes.size(), dim),
                  (dir / "trajectory.csv").string());
    nlohmann::json plots = nlohmann::json::array();
    if (!sc.probes.empty() &&
        make_plot(dir.string(),
                  {"plot_trajectory.py", {"trajectory.png", "trajectory.csv"}, {"trajectory.png"}}))
        plots.push_back("trajectory.png");
    if (write_animation(sc, fine, ref, runs, dir)) plots.push_back("animation.gif");

    // The fine timings are complete only now (animation): every entry reports them.
    for (nlohmann::json& e : entries)
        if (!e.contains("error")) e["timings"]["fine"] = timings_json(fine.timings);
    nlohmann::json summary = {
        {"command", "simulate"},
        {"scene", sc.source},
        {"fine", fine_json(fine)},
        {"dynamics",
         {{"integrator", sim::integrator_name(o.integrator)},
          {"dt", o.dt},
          {"steps", o.steps},
          {"output_every", o.output_every},
          {"start", o.start == sim::Start::Rest ? "rest" : "static"},
          {"mass", o.mass == fem::MassType::Consistent ? "consistent" : "lumped"}}},
        {"kinematics", sim::kinematics_name(sc.kinematics)},
        {"warp", sc.rs_warp ? "rs" : "none"},
        {"times", run.times},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"warnings", fm.warnings},
        {"plots", plots},
        {"animation_frames", ref.shown.size()},
    };
    summary["fine"]["frames"] =
        frames_json(run, o.steps, sc.kinematics == sim::Kinematics::Corotational);
    if (sc.kinematics == sim::Kinematics::Corotational) {
        const sim::CorotationOptions& c = sc.corotation;
        summary["corotation"] = {{"frame", fem::corotation_frame_name(c.frame)},
                                 {"tangent", sim::tangent_name(c.tangent)},
                                 {"step", sim::step_iterations_name(c.step)},
                                 {"linear_solve", sim::linear_solve_name(c.linear_solve)},
                                 {"tolerance", c.tolerance}};
        summary["fine"]["linear"] = fine_linear;
    }
    if (series) summary["pvd"] = "fine.pvd";
    nlohmann::json probes = nlohmann::json::array();
    for (std::size_t p = 0; p < sc.probes.size(); ++p)
        probes.push_back(
            {{"point", to_std(sc.probes[p])}, {"u_fine", probe_series(ref.result.probes, p)}});
    summary["probes"] = probes;
    summary["timings"] = {{"fine", timings_json(fine.timings)}};
    out.summary = with_methods(std::move(summary), entries, out.failed);
    return out;
}

/// The lag of the first probe's phase, or "-" if there is none.
std::string lag_text(const nlohmann::json& entry) {
    const nlohmann::json& phase = entry["errors"]["phase"];
    if (phase.empty() || phase[0]["lag"].is_null()) return "-";
    return fmt::format("{:+.3g}", phase[0]["lag"].get<double>());
}

/// The entries of a summary's methods: "methods", or the one method at the top level.
std::vector<nlohmann::json> method_entries(const nlohmann::json& summary) {
    if (summary.contains("methods")) return {summary["methods"].begin(), summary["methods"].end()};
    if (summary.contains("method")) return {summary};
    return {};
}

}  // namespace

nlohmann::json simulate_overview(const nlohmann::json& summary, const std::string& folder) {
    nlohmann::json methods = nlohmann::json::array();
    nlohmann::json period = nullptr;
    for (const nlohmann::json& e : method_entries(summary)) {
        if (e.contains("error")) {
            methods.push_back({{"method", e["method"]}, {"error", e["error"]}});
            continue;
        }
        nlohmann::json row = {{"method", e["method"]},
                              {"coarse", e["coarse"]},
                              {"speedup", e["speedup"]},
                              {"errors", e["errors"]}};
        row["coarse"]["timings"] = e["timings"]["coarse"];
        methods.push_back(row);
        if (period.is_null() && !e["errors"]["phase"].empty())
            period = e["errors"]["phase"][0]["period_fine"];
    }
    nlohmann::json plots = nlohmann::json::array();
    for (const auto& p : summary["plots"]) plots.push_back(folder + "/" + p.get<std::string>());
    const nlohmann::json& d = summary["dynamics"];
    return {{"folder", folder},
            {"integrator", d["integrator"]},
            {"dt", d["dt"]},
            {"steps", d["steps"]},
            {"start", d["start"]},
            {"fine",
             {{"dofs", summary["fine"]["dofs"]},
              {"timings", {{"per_step", summary["fine"]["timings"]["per_step"]}}},
              {"period", period}}},
            {"methods", methods},
            {"failed_methods", summary.value("failed_methods", 0)},
            {"plots", plots}};
}

void print_simulate_table(const scene::Scene& sc, const nlohmann::json& summary,
                          const std::string& command) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    std::printf("%s: %s, %s, %s, dt %g, %d steps\n", command.c_str(), sc.source.c_str(),
                sim::kinematics_name(sc.kinematics).c_str(),
                sim::integrator_name(o.integrator).c_str(), o.dt, o.steps);
    std::printf("  %-20s %9s %12s %12s %7s %10s %12s %10s\n", "model", "DOFs", "factorize s",
                "per step s", "solves", "speedup", "traj. l2", "lag p0");
    const nlohmann::json& fine = summary["fine"];
    const auto solves = [](const nlohmann::json& frames) {
        return frames["solves_per_step"].get<double>();
    };
    std::printf("  %-20s %9d %12.4f %12.3e %7.2f %10s %12s %10s\n", "fine", fine["dofs"].get<int>(),
                fine["timings"]["factorize"].get<double>(),
                fine["timings"]["per_step"].get<double>(), solves(fine["frames"]), "", "", "");
    if (fine.contains("linear")) {
        const nlohmann::json& l = fine["linear"];
        std::printf("  %-20s %9d %12.4f %12.3e %7.2f %10s %12.4g %10s\n", "fine (linear)",
                    fine["dofs"].get<int>(), l["timings"]["factorize"].get<double>(),
                    l["timings"]["per_step"].get<double>(), solves(l["frames"]), "",
                    l["errors"]["trajectory_l2_rel"].get<double>(), "");
    }
    for (const nlohmann::json& e : method_entries(summary)) {
        if (e.contains("error")) {
            std::printf("  %-20s failed: %s\n", e["method"].get<std::string>().c_str(),
                        e["error"].get<std::string>().c_str());
            continue;
        }
        const nlohmann::json& frames = e["coarse"]["frames"];
        const bool linear_here = frames["kinematics"] != summary["kinematics"];
        const std::string name =
            e["method"].get<std::string>() + (frames["warp"] == "rs"
                                                  ? (linear_here ? " (linear+warp)" : " (+warp)")
                                                  : (linear_here ? " (linear)" : ""));
        std::printf("  %-20s %9d %12.4f %12.3e %7.2f %9.1fx %12.4g %10s\n", name.c_str(),
                    e["coarse"]["dofs"].get<int>(),
                    e["timings"]["coarse"]["factorize"].get<double>(),
                    e["timings"]["coarse"]["per_step"].get<double>(), solves(frames),
                    e["speedup"]["per_frame"].get<double>(),
                    e["errors"]["trajectory_l2_rel"].get<double>(), lag_text(e).c_str());
    }
    std::printf(
        "  (solves: linear solves per step, Newton iterations when corotated; speedup: per "
        "saved frame, steps and warp; lag p0: the coarse model's last upward crossing of probe "
        "0's mean minus the fine model's, in time units; + is late)\n");
}

int run_simulate(const scene::Scene& sc, const std::vector<std::string>& methods,
                 const std::string& out_dir, double read_seconds, const Exports& exports) {
    CG_VERIFY_AS(InvalidScene, sc.dynamics.has_value(),
                 "{}: simulate needs a \"dynamics\" block (at least \"dt\" and \"steps\"; "
                 "docs/guide.md, \"Dynamics\")",
                 sc.source);
    if (exports.calculix) check_dynamic_export(sc);
    check_methods(sc, methods);
    const OutputFolder folder(out_dir);
    Timings timings;
    const scene::FineModel model = build_fine(sc, read_seconds, timings);
    check_frames_fit(sc, model);
    FineDynamics fine = with_fine_mass(model, sc.dynamics->mass, std::move(timings));
    const SimulateRun run = simulate_models(
        sc, fine, methods,
        [&](const std::string& method) { return build_coarse(sc, fine, method); }, out_dir, true,
        exports);
    write_summary(out_dir, run.summary);
    print_simulate_table(sc, run.summary);
    std::printf("  wrote %s/fine.pvd, trajectory.csv, animation.gif and summary.json\n",
                out_dir.c_str());
    return run.failed;
}

nlohmann::json simulate_built(const scene::Scene& sc, const scene::FineModel& fine_model,
                              std::vector<BuiltModel> coarse, const std::string& out_dir,
                              int& failed) {
    CG_VERIFY_AS(InvalidScene, sc.dynamics.has_value(), "{}: no \"dynamics\" block", sc.source);
    io::ensure_writable_dir(out_dir);
    check_frames_fit(sc, fine_model);
    FineDynamics fine = with_fine_mass(fine_model, sc.dynamics->mass, {});
    std::vector<std::string> methods;
    for (const BuiltModel& m : coarse) methods.push_back(m.method);
    const auto source = [&](const std::string& method) {
        const auto it = std::find_if(coarse.begin(), coarse.end(),
                                     [&](const BuiltModel& m) { return m.method == method; });
        // Each model is stepped once: it moves into the run (and is freed after it).
        return with_mass(std::move(it->model), fine, sc.source, method);
    };
    SimulateRun run = simulate_models(sc, fine, methods, source, out_dir, false);
    write_summary(out_dir, run.summary);
    failed += run.failed;
    return run.summary;
}

int run_modes(const scene::Scene& sc, const std::vector<std::string>& methods, int count,
              const std::string& out_dir, double read_seconds) {
    check_methods(sc, methods);
    const OutputFolder folder(out_dir);
    const fs::path dir(out_dir);
    const fem::MassType mass = sc.dynamics ? sc.dynamics->mass : fem::MassType::Consistent;
    Timings timings;
    const scene::FineModel model = build_fine(sc, read_seconds, timings);
    FineDynamics fine = with_fine_mass(model, mass, std::move(timings));
    const scene::FineModel& fm = fine.model;
    sim::Modes fine_modes;
    {
        const Phase phase("eigenpairs", &fine.timings);
        fine_modes = sim::modes(fm.K, fine.M, fm.bc, count, sc.solver);
    }
    const Index k = fine_modes.eigenvalues.size();
    std::vector<io::VtuFields> mode_fields(static_cast<std::size_t>(k));
    for (Index i = 0; i < k; ++i)
        mode_fields[static_cast<std::size_t>(i)].add_point_vector("mode", fine_modes.vectors.col(i),
                                                                  fm.mesh.dim());

    io::Table table;
    table.name = "frequencies";
    table.columns = {"mode", "fine_hz"};
    Matrix columns(k, 0);
    std::vector<nlohmann::json> entries;
    int failed = 0;
    for (const std::string& method : methods) {
        entries.push_back(method_entry(method, methods.size(), dir, failed, [&](nlohmann::json& e) {
            CoarseDynamics c = build_coarse(sc, fine, method);
            sim::Modes cm;
            {
                const Phase phase("eigenpairs", &c.timings);
                cm = sim::modes(c.model.K, c.M, c.model.bc, count, sc.solver);
            }
            const Matrix carried = c.model.to_fine * cm.vectors;
            const std::vector<sim::ModePair> pairs = sim::pair_modes(fine_modes.vectors, carried);
            std::vector<double> rel, mac, paired, paired_hz;
            for (Index i = 0; i < k; ++i) {
                const sim::ModePair& p = pairs[static_cast<std::size_t>(i)];
                const double fc = cm.frequencies_hz[p.coarse], ff = fine_modes.frequencies_hz[i];
                rel.push_back(std::abs(fc - ff) / ff);
                mac.push_back(p.mac);
                paired.push_back(static_cast<double>(p.coarse));
                paired_hz.push_back(fc);
                mode_fields[static_cast<std::size_t>(i)].add_point_vector(
                    "mode_" + method, carried.col(p.coarse), fm.mesh.dim());
            }
            e["coarse"] = coarse_json(c);
            e["coarse"]["frequencies_hz"] = to_std(cm.frequencies_hz);
            e["errors"] = {{"frequency_rel", rel}};
            e["mac"] = mac;
            e["mac_pairs"] = paired;
            table.columns.push_back(method + "_hz");
            table.columns.push_back(method + "_mac");
            columns.conservativeResize(k, columns.cols() + 2);
            columns.col(columns.cols() - 2) = Eigen::Map<const Vector>(paired_hz.data(), k);
            columns.col(columns.cols() - 1) = Eigen::Map<const Vector>(mac.data(), k);
        }));
    }
    {
        const Phase phase("write", &fine.timings);
        for (Index i = 0; i < k; ++i)
            io::write_vtu((dir / fmt::format("mode_{:02d}.vtu", i + 1)).string(), fm.mesh,
                          mode_fields[static_cast<std::size_t>(i)]);
        table.values.resize(k, 2 + columns.cols());
        for (Index i = 0; i < k; ++i) {
            table.values(i, 0) = static_cast<double>(i + 1);
            table.values(i, 1) = fine_modes.frequencies_hz[i];
        }
        table.values.rightCols(columns.cols()) = columns;
        io::write_csv(table, (dir / "frequencies.csv").string());
    }
    nlohmann::json plots = nlohmann::json::array();
    if (columns.cols() > 0 && make_plot(out_dir, {"plot_frequencies.py",
                                                  {"frequencies.png", "frequencies.csv"},
                                                  {"frequencies.png"}}))
        plots.push_back("frequencies.png");

    nlohmann::json fj = fine_json(fine);
    fj["frequencies_hz"] = to_std(fine_modes.frequencies_hz);
    nlohmann::json summary = {{"command", "modes"},
                              {"scene", sc.source},
                              {"fine", fj},
                              {"count", k},
                              {"mass", mass == fem::MassType::Consistent ? "consistent" : "lumped"},
                              {"solver", solve::backend_name(sc.solver.backend)},
                              {"threads", omp_get_max_threads()},
                              {"warnings", fm.warnings},
                              {"plots", plots}};
    write_summary(out_dir, with_methods(std::move(summary), entries, failed));

    std::printf("coarsegrain modes: %s, %d lowest modes (Hz)\n", sc.source.c_str(),
                static_cast<int>(k));
    std::printf("  %4s %12s", "mode", "fine");
    for (const nlohmann::json& e : entries)
        if (!e.contains("error")) std::printf(" %18s", e["method"].get<std::string>().c_str());
    std::printf("\n");
    for (Index i = 0; i < k; ++i) {
        std::printf("  %4d %12.6g", static_cast<int>(i + 1), fine_modes.frequencies_hz[i]);
        for (const nlohmann::json& e : entries)
            if (!e.contains("error"))
                std::printf(" %12.6g (%+7.2f%%)",
                            e["coarse"]["frequencies_hz"][e["mac_pairs"][i].get<std::size_t>()]
                                .get<double>(),
                            100 * e["errors"]["frequency_rel"][i].get<double>());
        std::printf("\n");
    }
    std::printf("  wrote %s/mode_*.vtu, frequencies.csv and summary.json\n", out_dir.c_str());
    return failed;
}

}  // namespace coarsegrain::app
