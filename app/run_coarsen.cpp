#include "run_coarsen.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "export.hpp"
#include "method_json.hpp"
#include "output.hpp"
#include "plots.hpp"
#include "report.hpp"
#include "run_dynamics.hpp"

namespace coarsegrain::app {

namespace {

namespace fs = std::filesystem;

double sum(const Timings& t) {
    double s = 0;
    for (const auto& [phase, seconds] : t.entries()) s += seconds;
    return s;
}

// The fine model and its solution (coarsen::solve_fine); the solution keeps the factorization if
// one of `methods` uses it.
FineRun solve_fine(const scene::Scene& sc, const std::vector<std::string>& methods,
                   double read_seconds) {
    Timings timings;
    timings.add("read", read_seconds);
    scene::FineModel model = scene::build_fine_model(sc, &timings);
    print_warnings(model.warnings);
    return coarsen::solve_fine(sc, std::move(model), methods, std::move(timings));
}

void write_fine(FineRun& f, const fs::path& dir) {
    const Phase phase("write", &f.timings);
    io::write_vtu((dir / "solution_fine.vtu").string(), f.model.mesh,
                  solution_fields(f.model, f.solution.u));
}

// summary.json "fine": sizes, timings and, if corotated, the Newton solve and the linear
// solution's largest displacement and strain energy beside the corotated ones.
nlohmann::json fine_json_of(const scene::Scene& sc, const FineRun& f) {
    nlohmann::json j = fine_sizes(f.model);
    j["timings"] = timings_json(f.timings);
    if (f.solution.newton) j["newton"] = newton_json(*f.solution.newton, sc.corotation);
    if (f.linear) {
        j["linear_max_displacement"] = nodal_magnitude(f.linear->u, f.model.mesh.dim()).maxCoeff();
        j["linear_strain_energy"] = f.linear->strain_energy;
    }
    return j;
}

// Builds, solves (as the scene asks: coarsen::run_method) and compares the method's coarse
// model, and adds the solve's "newton", "factorize", "solve" and "warp" seconds to `timings`. A
// coarse solve of a few milliseconds is at the mercy of the scheduler (one descheduled OpenMP
// worker costs more than the whole factorization), so short solves are repeated, up to 5 times
// and 0.1 s in all, and the fastest run of each phase is reported.
coarsen::MethodRun timed_method_run(const scene::Scene& sc, FineRun& f, const std::string& method,
                                    Timings& timings) {
    Timings first;
    coarsen::MethodRun run = coarsen::run_method(sc, f, method, &first);
    timings = run.model.timings;
    const std::vector<std::string> phases = {"newton", "factorize", "solve"};
    std::vector<double> best;
    double total = 0;
    for (const std::string& p : phases) {
        best.push_back(first[p]);
        total += first[p];
    }
    for (int repeat = 1; repeat < 5 && total < 0.1; ++repeat) {
        Timings t;
        coarsen::solve_coarse_for_scene(run.model, sc, &t);
        for (std::size_t i = 0; i < phases.size(); ++i) {
            best[i] = std::min(best[i], t[phases[i]]);
            total += t[phases[i]];
        }
    }
    for (std::size_t i = 0; i < phases.size(); ++i)
        if (best[i] > 0 || phases[i] != "newton") timings.add(phases[i], best[i]);
    if (sc.rs_warp && !run.solution.newton) timings.add("warp", first["warp"]);
    return run;
}

// Writes solution_<name>.vtu of a fine displacement u_c (fields as the fine solution's, plus its
// error against u) and returns its summary figures: "errors", "probes" and "vtu".
nlohmann::json write_solution(const fs::path& dir, const std::string& name, const scene::Scene& sc,
                              const scene::FineModel& fine, const Vector& u, const Vector& u_c) {
    const std::string file = "solution_" + name + ".vtu";
    io::VtuFields fields = solution_fields(fine, u_c);
    fields.add_point_vector("error", u_c - u, fine.mesh.dim());
    io::write_vtu((dir / file).string(), fine.mesh, fields);
    return {{"errors", coarsen::errors_json(coarsen::compare(fine, u, u_c))},
            {"probes", probes_json(sc, scene::probe_displacements(sc, fine.mesh, u_c))},
            {"vtu", file}};
}

// The method's figures and files that need the fine solution (CoarseModel::compare_with_fine):
// its report goes into `coarse_json` (add_comparison_json), its files and tables (as CSV) to
// `dir`, and the tables' plots are made last. Returns the plot images
// made. The phase "compare" goes to `timings`.
nlohmann::json compare_with_fine(const coarsen::CoarseModel& coarse, const scene::Scene& sc,
                                 const scene::FineModel& fine,
                                 const scene::StaticSolution& solution, const fs::path& dir,
                                 nlohmann::json& coarse_json, Timings& timings) {
    nlohmann::json made = nlohmann::json::array();
    if (!coarse.compare_with_fine) return made;
    const Phase phase("compare", &timings);
    const Vector& u = solution.u;
    const coarsen::FineComparison c = coarse.compare_with_fine(sc, fine, solution);
    add_comparison_json(coarse_json, coarse.report, c.report);
    for (const coarsen::Reconstruction& r : c.reconstructions)
        coarse_json.at("levels").at(r.level).update(write_solution(dir, r.name, sc, fine, u, r.u));
    for (const coarsen::VtuOutput& o : c.outputs)
        io::write_vtu((dir / o.file).string(), o.mesh, o.fields);
    std::vector<PlotOutput> plots;
    for (const io::Table& t : c.tables) {
        io::write_csv(t, (dir / (t.name + ".csv")).string());
        for (PlotOutput& p : table_plots(t)) plots.push_back(std::move(p));
    }
    for (const PlotOutput& p : plots)
        if (make_plot(dir.string(), p))
            for (const std::string& file : p.files) made.push_back(file);
    return made;
}

/// Builds, solves and compares one method against the fine run; writes its files and its
/// summary.json to `dir`. `fine_vtu` is the fine solution's file as seen from `dir`; if
/// `write_fine_vtu`, it is written there once the coarse model is built and solved (so that a
/// method that fails on its input leaves no file). With `keep_model` the result holds the coarse
/// model.
MethodResult run_method(const scene::Scene& sc, FineRun& f, const std::string& method,
                        const fs::path& dir, const std::string& fine_vtu, bool write_fine_vtu,
                        const Exports& exports, bool keep_model = false) {
    const scene::FineModel& fine = f.model;
    const Vector& u = f.solution.u;
    const int dim = fine.mesh.dim();
    Timings tc;
    coarsen::MethodRun run = timed_method_run(sc, f, method, tc);
    if (write_fine_vtu) write_fine(f, dir);
    coarsen::CoarseModel& coarse = run.model;
    const coarsen::CoarseSolution& uc = run.solution;
    MethodResult r;
    r.method = method;
    r.errors = run.errors;
    r.u_fine = uc.u_fine;
    {
        const Phase phase("write", &tc);
        io::VtuFields fields = solution_fields(fine, uc.u_fine);
        fields.add_point_vector("error", uc.u_fine - u, dim);
        io::write_vtu((dir / "solution_coarse.vtu").string(), fine.mesh, fields);
        for (const coarsen::VtuOutput& o : coarse.outputs)
            io::write_vtu((dir / o.file).string(), o.mesh, o.fields);
        if (exports.calculix) write_export(sc, fine, coarse, dir);
    }
    nlohmann::json coarse_json = method_json(coarse.report);
    const nlohmann::json plots =
        compare_with_fine(coarse, sc, fine, f.linear_solution(), dir, coarse_json, tc);
    r.dofs = coarse.K.rows();
    r.build_seconds = sum(coarse.timings);
    r.factorize_and_solve = tc["newton"] + tc["factorize"] + tc["solve"] + tc["warp"];
    r.speedup = f.factorize_and_solve() / r.factorize_and_solve;
    coarse_json["nodes"] = coarse.nodes;
    coarse_json["elements"] = coarse.elements;
    coarse_json["dofs"] = coarse.K.rows();
    coarse_json["free_dofs"] = coarse.K.rows() - static_cast<Index>(coarse.bc.dofs.size());
    coarse_json["nonzeros"] = coarse.K.nonZeros();
    coarse_json["timings"] = timings_json(tc);
    coarse_json["timings"]["build"] = r.build_seconds;
    coarse_json["kinematics"] =
        sim::kinematics_name(uc.newton ? sim::Kinematics::Corotational : sim::Kinematics::Linear);
    if (uc.newton) coarse_json["newton"] = newton_json(*uc.newton, sc.corotation);
    coarse_json["warp"] = sc.rs_warp && !uc.newton ? "rs" : "none";
    nlohmann::json fine_json = fine_json_of(sc, f);
    r.summary = {
        {"command", "coarsen"},
        {"method", method},
        {"scene", sc.source},
        {"fine", fine_json},
        {"coarse", coarse_json},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"probes",
         probes_json(sc, scene::probe_displacements(sc, fine.mesh, uc.u_fine), &f.probes)},
        {"errors", coarsen::errors_json(r.errors)},
        {"warnings", fine.warnings},
        {"speedup",
         {{"solve", f.timings["solve"] / tc["solve"]}, {"factorize_and_solve", r.speedup}}},
        {"max_displacement", nodal_magnitude(uc.u_fine, dim).maxCoeff()},
        {"kinematics", sim::kinematics_name(sc.kinematics)},
        {"warp", sc.rs_warp ? "rs" : "none"},
        {"strain_energy", uc.strain_energy},
        {"compliance", coarse.f.dot(uc.u)},
        {"fine_max_displacement", nodal_magnitude(u, dim).maxCoeff()},
        {"fine_strain_energy", f.solution.strain_energy},
        {"fine_vtu", fine_vtu},
        {"plots", plots},
        {"peak_memory_mb", peak_resident_mb()},
    };
    write_summary(dir.string(), r.summary);
    if (keep_model) {
        coarse.outputs.clear();
        coarse.compare_with_fine = nullptr;
        r.model = std::move(coarse);
    }
    return r;
}

void print_method_table(const scene::Scene& sc, const std::string& method, const FineRun& f,
                        const MethodResult& r) {
    const scene::FineModel& fine = f.model;
    const nlohmann::json& c = r.summary["coarse"];
    const Timings& tf = f.timings;
    std::printf("coarsegrain coarsen --method %s: %s\n", method.c_str(), sc.source.c_str());
    std::printf("  %-7s %9s %9s %9s %10s %10s %10s\n", "model", "nodes", "elements", "DOFs",
                "build s", "factor s", "solve s");
    std::printf("  %-7s %9d %9d %9d %10.3f %10.4f %10.4f\n", "fine", fine.mesh.num_nodes(),
                fine.mesh.num_elements(), fine.mesh.num_dofs(), tf["assemble"], tf["factorize"],
                tf["solve"]);
    std::printf("  %-7s %9d %9d %9d %10.3f %10.4f %10.4f\n", "coarse", c["nodes"].get<Index>(),
                c["elements"].get<Index>(), r.dofs, r.build_seconds,
                c["timings"]["factorize"].get<double>(), c["timings"]["solve"].get<double>());
    std::printf("  speedup (factorize + solve) %.1fx\n", r.speedup);
    std::printf("  errors: l2 %.4g, energy %.4g, max |u| %.4g, compliance ratio %.4f\n",
                r.errors.l2_rel, r.errors.energy_rel, r.errors.max_displacement_rel,
                r.errors.compliance_ratio);
}

void run_one(const scene::Scene& sc, const std::string& method, const fs::path& dir,
             double read_seconds, const Exports& exports) {
    FineRun f = solve_fine(sc, {method}, read_seconds);
    const MethodResult r = run_method(sc, f, method, dir, "solution_fine.vtu", true, exports);
    print_method_table(sc, method, f, r);
    std::printf(
        "  wrote %s/summary.json, solution_fine.vtu, solution_coarse.vtu and the method's "
        "files (peak memory %.0f MB)\n",
        dir.c_str(), peak_resident_mb());
}

// One method of a comparison: its result, or its failure (the reason, and no folder) if it
// cannot run on this scene or fails while it builds or solves.
MethodResult try_method(const scene::Scene& sc, FineRun& f, const std::string& method,
                        const fs::path& dir, const Exports& exports, bool keep_model) {
    const fs::path sub = dir / method;
    try {
        io::ensure_writable_dir(sub.string());
        return run_method(sc, f, method, sub, "../solution_fine.vtu", false, exports, keep_model);
    } catch (const Error& e) {
        std::error_code ec;
        fs::remove_all(sub, ec);
        std::fprintf(stderr, "coarsegrain: method %s failed: %s\n", method.c_str(), e.what());
        MethodResult r;
        r.method = method;
        r.failure = e.what();
        return r;
    }
}

/// A comparison's fine run and every method's result.
struct Comparison {
    FineRun fine;
    std::vector<MethodResult> results;
};

/// The fine solve, then every method against it (their folders in `dir`), and the fine
/// solution's file. With `keep_models` each result holds its coarse model.
Comparison compare_methods(const scene::Scene& sc, const std::vector<std::string>& methods,
                           const fs::path& dir, double read_seconds, const Exports& exports,
                           bool keep_models) {
    Comparison c{solve_fine(sc, methods, read_seconds), {}};
    for (const std::string& method : methods)
        c.results.push_back(try_method(sc, c.fine, method, dir, exports, keep_models));
    c.fine.solution.factorization.reset();  // used by the methods only
    if (c.fine.linear) c.fine.linear->factorization.reset();
    write_fine(c.fine, dir);
    return c;
}

/// The comparison's report, summary.json and table; the demo's dynamic run (its summary, if
/// given) goes into the report and under the summary's "dynamics". Returns the methods that
/// failed.
int finish_comparison(const scene::Scene& sc, const std::string& command, const Comparison& c,
                      const fs::path& dir, const nlohmann::json* dynamics) {
    const FineRun& f = c.fine;
    const std::vector<MethodResult>& results = c.results;
    const nlohmann::json plots = write_report(sc, command, f, results, dir, dynamics);
    const nlohmann::json fine_json = fine_json_of(sc, f);
    nlohmann::json rows = nlohmann::json::array();
    int failed = 0;
    for (const MethodResult& r : results) {
        if (!r.failure.empty()) {
            rows.push_back({{"method", r.method}, {"error", r.failure}});
            ++failed;
            continue;
        }
        rows.push_back(
            {{"method", r.method},
             {"folder", r.method},
             {"coarse",
              {{"dofs", r.dofs},
               {"timings",
                {{"build", r.build_seconds}, {"factorize_and_solve", r.factorize_and_solve}}}}},
             {"errors", coarsen::errors_json(r.errors)},
             {"speedup", {{"factorize_and_solve", r.speedup}}},
             {"max_displacement", r.summary["max_displacement"]}});
    }
    nlohmann::json summary = {
        {"command", command},
        {"scene", sc.source},
        {"fine", fine_json},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"kinematics", sim::kinematics_name(sc.kinematics)},
        {"warp", sc.rs_warp ? "rs" : "none"},
        {"probes", probes_json(sc, f.probes)},
        {"warnings", f.model.warnings},
        {"max_displacement", nodal_magnitude(f.solution.u, f.model.mesh.dim()).maxCoeff()},
        {"strain_energy", f.solution.strain_energy},
        {"compliance", f.model.f.dot(f.solution.u)},
        {"methods", rows},
        {"failed_methods", failed},
        {"report", "report.md"},
        {"plots", plots},
        {"peak_memory_mb", peak_resident_mb()},
    };
    if (dynamics) summary["dynamics"] = *dynamics;
    write_summary(dir.string(), summary);
    print_comparison_table(sc, command, f, results);
    return failed;
}

int run_comparison(const scene::Scene& sc, const std::vector<std::string>& methods,
                   const fs::path& dir, const std::string& command, double read_seconds,
                   const Exports& exports) {
    const Comparison c = compare_methods(sc, methods, dir, read_seconds, exports, false);
    const int failed = finish_comparison(sc, command, c, dir, nullptr);
    std::printf(
        "  wrote %s/report.md, summary.json, solution_fine.vtu and a folder per method "
        "(peak memory %.0f MB)\n",
        dir.c_str(), peak_resident_mb());
    return failed;
}

}  // namespace

int run_coarsen(scene::Scene scene, const std::vector<std::string>& methods,
                const std::string& out_dir, const std::string& command, double read_seconds,
                const Exports& exports) {
    check_methods(scene, methods);
    const scene::Scene sc = coarsen::with_automatic_levels(std::move(scene), methods);
    const OutputFolder folder(out_dir);
    if (methods.size() == 1) {
        run_one(sc, methods.front(), out_dir, read_seconds, exports);
        return 0;
    }
    return run_comparison(sc, methods, out_dir, command, read_seconds, exports);
}

int run_demo(const scene::Scene& sc, const std::string& out_dir, double read_seconds) {
    CG_VERIFY_AS(InvalidScene, sc.dynamics.has_value(), "{}: the demo needs a \"dynamics\" block",
                 sc.source);
    const std::vector<std::string> methods = coarsen::configured_methods(sc);
    check_methods(sc, methods);
    const OutputFolder folder(out_dir);
    const fs::path dir(out_dir);
    Comparison c = compare_methods(sc, methods, dir, read_seconds, {}, true);
    std::vector<BuiltModel> built;
    for (MethodResult& r : c.results) {
        if (r.model) built.push_back({r.method, std::move(*r.model)});
        r.model.reset();
    }
    int failed = 0;
    const nlohmann::json dynamics = simulate_built(sc, c.fine.model, std::move(built),
                                                   (dir / kDemoDynamicsFolder).string(), failed);
    const nlohmann::json overview = simulate_overview(dynamics, kDemoDynamicsFolder);
    failed += finish_comparison(sc, "demo", c, dir, &overview);
    print_simulate_table(sc, dynamics, "coarsegrain demo, released from rest");
    std::printf(
        "  wrote %s/report.md, summary.json, solution_fine.vtu, a folder per method and %s/ "
        "(peak memory %.0f MB)\n",
        dir.c_str(), kDemoDynamicsFolder, peak_resident_mb());
    return failed;
}

}  // namespace coarsegrain::app
