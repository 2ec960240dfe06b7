#include "run_coarsen.hpp"

#include <fmt/ranges.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "output.hpp"
#include "plots.hpp"

namespace coarsegrain::app {

namespace {

double sum(const Timings& t) {
    double s = 0;
    for (const auto& [phase, seconds] : t.entries()) s += seconds;
    return s;
}

nlohmann::json errors_json(const coarsen::Errors& e) {
    return {{"energy_rel", e.energy_rel},
            {"energy_over_load", e.energy_over_load},
            {"l2_rel", e.l2_rel},
            {"max_displacement_rel", e.max_displacement_rel},
            {"compliance_ratio", e.compliance_ratio},
            {"stress_rel", e.stress_rel}};
}

void print_table(const scene::Scene& sc, const std::string& method, const scene::FineModel& fine,
                 const coarsen::CoarseModel& coarse, const Timings& tf, const Timings& tc,
                 const coarsen::Errors& e) {
    std::printf("coarsegrain coarsen --method %s: %s\n", method.c_str(), sc.source.c_str());
    std::printf("  %-7s %9s %9s %9s %10s %10s %10s\n", "model", "nodes", "elements", "DOFs",
                "build s", "factor s", "solve s");
    std::printf("  %-7s %9d %9d %9d %10.3f %10.4f %10.4f\n", "fine", fine.mesh.num_nodes(),
                fine.mesh.num_elements(), fine.mesh.num_dofs(), tf["assemble"], tf["factorize"],
                tf["solve"]);
    std::printf("  %-7s %9d %9d %9d %10.3f %10.4f %10.4f\n", "coarse", coarse.nodes,
                coarse.elements, static_cast<Index>(coarse.K.rows()), sum(coarse.timings),
                tc["factorize"], tc["solve"]);
    std::printf("  speedup (factorize + solve) %.1fx\n",
                (tf["factorize"] + tf["solve"]) / (tc["factorize"] + tc["solve"]));
    std::printf("  errors: l2 %.4g, energy %.4g, max |u| %.4g, compliance ratio %.4f\n", e.l2_rel,
                e.energy_rel, e.max_displacement_rel, e.compliance_ratio);
}

// Solves the coarse model and adds its "factorize" and "solve" seconds to `timings`. A coarse
// solve of a few milliseconds is at the mercy of the scheduler (one descheduled OpenMP worker
// costs more than the whole factorization), so short solves are repeated, up to 5 times and
// 0.1 s in all, and the fastest run of each phase is reported.
coarsen::CoarseSolution timed_coarse_solve(const coarsen::CoarseModel& model,
                                           const solve::SolverOptions& options, Timings& timings) {
    Timings first;
    coarsen::CoarseSolution s = coarsen::solve_static(model, options, &first);
    double factorize = first["factorize"], solve = first["solve"], total = factorize + solve;
    for (int repeat = 1; repeat < 5 && total < 0.1; ++repeat) {
        Timings t;
        coarsen::solve_static(model, options, &t);
        factorize = std::min(factorize, t["factorize"]);
        solve = std::min(solve, t["solve"]);
        total += t["factorize"] + t["solve"];
    }
    timings.add("factorize", factorize);
    timings.add("solve", solve);
    return s;
}

// Writes solution_<name>.vtu of a fine displacement u_c (fields as the fine solution's, plus its
// error against u) and returns its summary figures: "errors", "probes" and "vtu".
nlohmann::json write_solution(const std::filesystem::path& dir, const std::string& name,
                              const scene::Scene& sc, const scene::FineModel& fine, const Vector& u,
                              const Vector& u_c) {
    const std::string file = "solution_" + name + ".vtu";
    io::VtuFields fields = solution_fields(fine, u_c);
    fields.add_point_vector("error", u_c - u, fine.mesh.dim());
    io::write_vtu((dir / file).string(), fine.mesh, fields);
    return {{"errors", errors_json(coarsen::compare(fine, u, u_c))},
            {"probes", probes_json(sc, scene::probe_displacements(sc, fine.mesh, u_c))},
            {"vtu", file}};
}

// The method's figures and files that need the fine solution (CoarseModel::compare_with_fine):
// merged into `coarse_json`, written to `dir`; plots are made last. Returns the plot images
// made. The phase "compare" goes to `timings`.
nlohmann::json compare_with_fine(const coarsen::CoarseModel& coarse, const scene::Scene& sc,
                                 const scene::FineModel& fine, const Vector& u,
                                 const std::filesystem::path& dir, nlohmann::json& coarse_json,
                                 Timings& timings) {
    nlohmann::json made = nlohmann::json::array();
    if (!coarse.compare_with_fine) return made;
    const Phase phase("compare", &timings);
    const coarsen::FineComparison c = coarse.compare_with_fine(sc, fine, u);
    coarse_json.merge_patch(c.report);
    for (const coarsen::Reconstruction& r : c.reconstructions)
        coarse_json[nlohmann::json::json_pointer(r.report_pointer)].update(
            write_solution(dir, r.name, sc, fine, u, r.u));
    for (const coarsen::VtuOutput& o : c.outputs)
        io::write_vtu((dir / o.file).string(), o.mesh, o.fields);
    for (const coarsen::FileOutput& f : c.files)
        io::write_atomically((dir / f.file).string(), [&](std::ostream& os) { os << f.content; });
    for (const coarsen::PlotOutput& p : c.plots)
        if (make_plot(dir.string(), p))
            for (const std::string& f : p.files) made.push_back(f);
    return made;
}

}  // namespace

void run_coarsen(const scene::Scene& sc, const std::string& method, const std::string& out_dir,
                 double read_seconds) {
    io::ensure_writable_dir(out_dir);
    const std::filesystem::path dir(out_dir);
    Timings tf;
    tf.add("read", read_seconds);
    const scene::FineModel fine = scene::build_fine_model(sc, &tf);
    const coarsen::CoarseModel coarse = coarsen::build_coarse_model(sc, fine, method);
    const scene::StaticSolution u = scene::solve_static(fine, sc.solver, &tf);
    Timings tc = coarse.timings;
    const coarsen::CoarseSolution uc = timed_coarse_solve(coarse, sc.solver, tc);
    const coarsen::Errors e = coarsen::compare(fine, u.u, uc.u_fine);

    const std::vector<Eigen::VectorXd> probes_fine = scene::probe_displacements(sc, fine.mesh, u.u);
    const std::vector<Eigen::VectorXd> probes =
        scene::probe_displacements(sc, fine.mesh, uc.u_fine);
    const int dim = fine.mesh.dim();
    {
        const Phase phase("write", &tc);
        io::write_vtu((dir / "solution_fine.vtu").string(), fine.mesh, solution_fields(fine, u.u));
        io::VtuFields fields = solution_fields(fine, uc.u_fine);
        fields.add_point_vector("error", uc.u_fine - u.u, dim);
        io::write_vtu((dir / "solution_coarse.vtu").string(), fine.mesh, fields);
        for (const coarsen::VtuOutput& o : coarse.outputs)
            io::write_vtu((dir / o.file).string(), o.mesh, o.fields);
    }

    nlohmann::json fine_json = fine_sizes(fine);
    fine_json["timings"] = timings_json(tf);
    nlohmann::json coarse_json = coarse.report;
    const nlohmann::json plots = compare_with_fine(coarse, sc, fine, u.u, dir, coarse_json, tc);
    coarse_json["nodes"] = coarse.nodes;
    coarse_json["elements"] = coarse.elements;
    coarse_json["dofs"] = coarse.K.rows();
    coarse_json["free_dofs"] = coarse.K.rows() - static_cast<Index>(coarse.bc.dofs.size());
    coarse_json["nonzeros"] = coarse.K.nonZeros();
    coarse_json["timings"] = timings_json(tc);
    coarse_json["timings"]["build"] = sum(coarse.timings);
    const double fine_fs = tf["factorize"] + tf["solve"], coarse_fs = tc["factorize"] + tc["solve"];
    write_summary(
        out_dir,
        {
            {"command", "coarsen"},
            {"method", method},
            {"scene", sc.source},
            {"fine", fine_json},
            {"coarse", coarse_json},
            {"solver", solve::backend_name(sc.solver.backend)},
            {"threads", omp_get_max_threads()},
            {"probes", probes_json(sc, probes, &probes_fine)},
            {"errors", errors_json(e)},
            {"speedup",
             {{"solve", tf["solve"] / tc["solve"]}, {"factorize_and_solve", fine_fs / coarse_fs}}},
            {"max_displacement", nodal_magnitude(uc.u_fine, dim).maxCoeff()},
            {"strain_energy", 0.5 * uc.u.dot(coarse.K * uc.u)},
            {"compliance", coarse.f.dot(uc.u)},
            {"fine_max_displacement", nodal_magnitude(u.u, dim).maxCoeff()},
            {"fine_strain_energy", u.strain_energy},
            {"plots", plots},
            {"peak_memory_mb", peak_rss_mb()},
        });
    print_table(sc, method, fine, coarse, tf, tc, e);
    std::printf(
        "  wrote %s/summary.json, solution_fine.vtu, solution_coarse.vtu%s (peak memory %.0f MB)\n",
        out_dir.c_str(), coarse.outputs.empty() ? "" : ", method files", peak_rss_mb());
}

}  // namespace coarsegrain::app
