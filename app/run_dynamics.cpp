#include "run_dynamics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#include "animation.hpp"
#include "coarsegrain/coarsen/dynamics_run.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/io/table.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "export.hpp"
#include "output.hpp"
#include "plots.hpp"

namespace coarsegrain::app {

namespace {

namespace fs = std::filesystem;

using coarsen::CoarseDynamics;
using coarsen::FineDynamics;
using coarsen::ProbeSeries;

/// The scene's fine model, its phases ("read" = read_seconds, then the assembly's) in `timings`.
scene::FineModel build_fine(const scene::Scene& sc, double read_seconds, Timings& timings) {
    timings.add("read", read_seconds);
    scene::FineModel model = scene::build_fine_model(sc, &timings);
    print_warnings(model.warnings);
    return model;
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

/// Prints a failed method's failure on stderr (a comparison goes on with the other methods).
class FailureReport : public coarsen::RunObserver {
  public:
    void method_failed(const std::string& method, const std::string& message) override {
        std::fprintf(stderr, "coarsegrain: method %s failed: %s\n", method.c_str(),
                     message.c_str());
    }
};

/// Each coarse model's own files (CoarseModel::outputs: the level meshes of automatic levels),
/// written to DIR/<method>/ when the model is built, as `coarsen` writes them to its method
/// folders; a failed method's folder is removed and its failure printed on stderr.
class ModelFiles : public FailureReport {
  public:
    explicit ModelFiles(fs::path dir) : m_dir(std::move(dir)) {}

    void coarse_built(const std::string& method, const CoarseDynamics& c) override {
        for (const coarsen::VtuOutput& o : c.model.outputs) {
            fs::create_directories(m_dir / method);
            io::write_vtu((m_dir / method / o.file).string(), o.mesh, o.fields);
            m_files[method].push_back(method + "/" + o.file);
        }
    }
    void method_failed(const std::string& method, const std::string& message) override {
        std::error_code ec;
        fs::remove_all(m_dir / method, ec);
        m_files.erase(method);
        FailureReport::method_failed(method, message);
    }
    /// Lists the method's files in its summary entry as coarse.files (paths relative to DIR).
    void list_files(const std::string& method, nlohmann::json& entry) const {
        const auto it = m_files.find(method);
        if (it != m_files.end()) entry["coarse"]["files"] = it->second;
    }

  protected:
    fs::path m_dir;

  private:
    std::map<std::string, std::vector<std::string>> m_files;
};

/// A run's files as it goes: each run's animation frames, its ParaView series DIR/<run>/ and
/// DIR/<run>.pvd (if `series`), each coarse model's files (ModelFiles) and export
/// (exports.calculix); a failed method's files are removed and its failure printed on stderr.
class FrameWriter : public ModelFiles {
  public:
    FrameWriter(const scene::Scene& sc, const FineDynamics& fine, fs::path dir, bool series,
                const Exports& exports)
        : ModelFiles(std::move(dir)), m_sc(sc), m_fine(fine), m_series(series),
          m_exports(exports) {}

    void fine_stepped(const sim::Trajectory& fine) override {
        const scene::FineModel& fm = m_fine.model;
        m_view = animation_view(fm.mesh, fm.boundary, fine.u);
        m_shown = animation_frames(fine.times.size());
        for (const std::size_t i : m_shown) m_times.push_back(fine.times[i]);
    }
    void frame(const std::string& name, std::size_t i, double time, const Vector& u,
               const Vector* reference) override {
        Run& run = m_runs[name];
        if (run.next_shown < m_shown.size() && m_shown[run.next_shown] == i) {
            append_animation_frame(m_view, u, run.animation);
            ++run.next_shown;
        }
        if (!m_series) return;
        if (i == 0) fs::create_directories(m_dir / name);
        run.written.push_back(write_frame(m_dir, name, i, time, m_fine.model.mesh, u, reference));
    }
    void run_done(const std::string& name) override {
        if (m_series) io::write_pvd((m_dir / (name + ".pvd")).string(), m_runs[name].written);
    }
    void coarse_built(const std::string& method, const CoarseDynamics& c) override {
        ModelFiles::coarse_built(method, c);
        if (!m_exports.calculix) return;
        fs::create_directories(m_dir / method);
        write_export(m_sc, m_fine.model, c.model, m_dir / method, &c.M);
    }
    void method_failed(const std::string& method, const std::string& message) override {
        std::error_code ec;
        fs::remove(m_dir / (method + ".pvd"), ec);
        m_runs.erase(method);
        ModelFiles::method_failed(method, message);
    }

    /// Writes animation_data.bin of `runs` (in this order) and makes animation.gif from it
    /// (phase "animation" of `timings`); returns whether the GIF was made.
    bool write_animation(const std::vector<std::string>& runs, Timings& timings) {
        const Phase phase("animation", &timings);
        std::vector<AnimationModel> models;
        for (const std::string& name : runs) models.push_back({name, &m_runs[name].animation});
        write_animation_data((m_dir / "animation_data.bin").string(), m_sc.source,
                             m_fine.model.mesh, m_view, m_times, models);
        return make_plot(
            m_dir.string(),
            {"plot_animation.py", {"animation.gif", "animation_data.bin"}, {"animation.gif"}});
    }
    std::size_t animation_frames_shown() const { return m_shown.size(); }

  private:
    struct Run {
        std::vector<float> animation;  ///< append_animation_frame of each frame shown
        std::size_t next_shown = 0;
        std::vector<std::pair<double, std::string>> written;  ///< (time, file) of the series
    };
    const scene::Scene& m_sc;
    const FineDynamics& m_fine;
    bool m_series;
    Exports m_exports;
    AnimationView m_view;
    std::vector<std::size_t> m_shown;  ///< the saved frames the animation shows
    std::vector<double> m_times;       ///< their times
    std::map<std::string, Run> m_runs;
};

const char* axis_name(int d) { return d == 0 ? "x" : d == 1 ? "y" : "z"; }

/// trajectory.csv: time, then <model>_p<probe>_<axis> for the fine model and each method.
io::Table trajectory_table(const std::vector<double>& times,
                           const std::vector<std::pair<std::string, const ProbeSeries*>>& runs,
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
                    t.values(static_cast<Index>(i), c++) = (*run)[i][p][d];
    }
    return t;
}

/// What simulate_files made: the summary (not yet written) and the methods that failed.
struct SimulateRun {
    nlohmann::json summary;
    int failed = 0;
};

/// The run shared by `simulate` and the demo (coarsen::simulate_models): steps the fine model and
/// the coarse model that `source` gives for each method, compares them and writes every file but
/// summary.json to `dir` (the ParaView series only if `series`).
SimulateRun simulate_files(const scene::Scene& sc, FineDynamics& fine,
                           const std::vector<std::string>& methods,
                           const coarsen::CoarseSource& source, const fs::path& dir, bool series,
                           const Exports& exports = {}) {
    FrameWriter writer(sc, fine, dir, series, exports);
    coarsen::SimulateResult result = coarsen::simulate_models(sc, fine, methods, source, writer);
    std::vector<std::pair<std::string, const ProbeSeries*>> runs = {{"fine", &result.fine_probes}};
    if (result.fine_linear) {
        runs.emplace_back("fine-linear", &result.fine_linear->probes);
        if (series) result.fine_linear->entry["pvd"] = "fine-linear.pvd";
    }
    for (coarsen::ModelDynamics& r : result.methods)
        if (r.error.empty()) {
            runs.emplace_back(r.name, &r.probes);
            if (series) r.entry["pvd"] = r.name + ".pvd";
            writer.list_files(r.name, r.entry);
        }
    io::write_csv(
        trajectory_table(result.fine.times, runs, sc.probes.size(), fine.model.mesh.dim()),
        (dir / "trajectory.csv").string());
    nlohmann::json plots = nlohmann::json::array();
    if (!sc.probes.empty() &&
        make_plot(dir.string(),
                  {"plot_trajectory.py", {"trajectory.png", "trajectory.csv"}, {"trajectory.png"}}))
        plots.push_back("trajectory.png");
    std::vector<std::string> names;
    for (const auto& run : runs) names.push_back(run.first);
    if (writer.write_animation(names, fine.timings)) plots.push_back("animation.gif");
    nlohmann::json top = {{"plots", plots}, {"animation_frames", writer.animation_frames_shown()}};
    if (series) top["pvd"] = "fine.pvd";
    return {coarsen::simulate_summary(sc, fine, result, top), result.failed};
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

int run_simulate(const scene::Scene& given, const std::vector<std::string>& methods,
                 const std::string& out_dir, double read_seconds, const Exports& exports) {
    coarsen::check_dynamics(given);
    if (exports.calculix) check_dynamic_export(given);
    check_methods(given, methods);
    const OutputFolder folder(out_dir);
    // Automatic level meshes made once, shared by the hierarchy methods.
    const scene::Scene sc = coarsen::with_automatic_levels(given, methods);
    Timings timings;
    const scene::FineModel model = build_fine(sc, read_seconds, timings);
    coarsen::check_frames_fit(sc, model);
    FineDynamics fine = coarsen::fine_dynamics(model, sc.dynamics->mass, std::move(timings));
    const SimulateRun run = simulate_files(
        sc, fine, methods,
        [&](const std::string& method) { return coarsen::build_coarse_dynamics(sc, fine, method); },
        out_dir, true, exports);
    write_summary(out_dir, run.summary);
    print_simulate_table(sc, run.summary);
    std::printf("  wrote %s/fine.pvd, trajectory.csv, animation.gif and summary.json\n",
                out_dir.c_str());
    return run.failed;
}

nlohmann::json simulate_built(const scene::Scene& sc, const scene::FineModel& fine_model,
                              std::vector<BuiltModel> coarse, const std::string& out_dir,
                              int& failed) {
    coarsen::check_dynamics(sc);
    io::ensure_writable_dir(out_dir);
    coarsen::check_frames_fit(sc, fine_model);
    FineDynamics fine = coarsen::fine_dynamics(fine_model, sc.dynamics->mass, {});
    std::vector<std::string> methods;
    for (const BuiltModel& m : coarse) methods.push_back(m.method);
    const auto source = [&](const std::string& method) {
        const auto it = std::find_if(coarse.begin(), coarse.end(),
                                     [&](const BuiltModel& m) { return m.method == method; });
        // Each model is stepped once: it moves into the run (and is freed after it).
        return coarsen::coarse_dynamics(std::move(it->model), fine, sc, method);
    };
    SimulateRun run = simulate_files(sc, fine, methods, source, out_dir, false);
    write_summary(out_dir, run.summary);
    failed += run.failed;
    return run.summary;
}

int run_modes(const scene::Scene& given, const std::vector<std::string>& methods, int count,
              const std::string& out_dir, double read_seconds) {
    check_methods(given, methods);
    const OutputFolder folder(out_dir);
    const fs::path dir(out_dir);
    // Automatic level meshes made once, shared by the hierarchy methods.
    const scene::Scene sc = coarsen::with_automatic_levels(given, methods);
    const fem::MassType mass = sc.dynamics ? sc.dynamics->mass : fem::MassType::Consistent;
    Timings timings;
    const scene::FineModel model = build_fine(sc, read_seconds, timings);
    FineDynamics fine = coarsen::fine_dynamics(model, mass, std::move(timings));
    const scene::FineModel& fm = fine.model;
    ModelFiles files(dir);
    coarsen::ModesResult result = coarsen::modes_models(sc, fine, methods, count, files);
    for (coarsen::ModesMethod& r : result.methods)
        if (r.error.empty()) files.list_files(r.method, r.entry);
    const sim::Modes& fine_modes = result.fine;
    const Index k = fine_modes.eigenvalues.size();
    std::vector<io::VtuFields> mode_fields(static_cast<std::size_t>(k));
    for (Index i = 0; i < k; ++i)
        mode_fields[static_cast<std::size_t>(i)].add_point_vector("mode", fine_modes.vectors.col(i),
                                                                  fm.mesh.dim());
    io::Table table;
    table.name = "frequencies";
    table.columns = {"mode", "fine_hz"};
    Matrix columns(k, 0);
    for (const coarsen::ModesMethod& r : result.methods) {
        if (!r.error.empty()) continue;
        table.columns.push_back(r.method + "_hz");
        table.columns.push_back(r.method + "_mac");
        columns.conservativeResize(k, columns.cols() + 2);
        for (Index i = 0; i < k; ++i) {
            const sim::ModePair& p = r.pairs[static_cast<std::size_t>(i)];
            columns(i, columns.cols() - 2) = r.modes.frequencies_hz[p.coarse];
            columns(i, columns.cols() - 1) = p.mac;
            mode_fields[static_cast<std::size_t>(i)].add_point_vector(
                "mode_" + r.method, r.carried.col(p.coarse), fm.mesh.dim());
        }
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
    write_summary(out_dir, coarsen::modes_summary(sc, fine, result, {{"plots", plots}}));

    std::printf("coarsegrain modes: %s, %d lowest modes (Hz)\n", sc.source.c_str(),
                static_cast<int>(k));
    std::printf("  %4s %12s", "mode", "fine");
    for (const coarsen::ModesMethod& r : result.methods)
        if (r.error.empty()) std::printf(" %18s", r.method.c_str());
    std::printf("\n");
    for (Index i = 0; i < k; ++i) {
        std::printf("  %4d %12.6g", static_cast<int>(i + 1), fine_modes.frequencies_hz[i]);
        for (const coarsen::ModesMethod& r : result.methods)
            if (r.error.empty())
                std::printf(" %12.6g (%+7.2f%%)",
                            r.modes.frequencies_hz[r.pairs[static_cast<std::size_t>(i)].coarse],
                            100 * r.entry["errors"]["frequency_rel"][i].get<double>());
        std::printf("\n");
    }
    std::printf("  wrote %s/mode_*.vtu, frequencies.csv and summary.json\n", out_dir.c_str());
    return result.failed;
}

}  // namespace coarsegrain::app
