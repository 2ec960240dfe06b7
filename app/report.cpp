#include "report.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <cstdio>
#include <map>

#include "coarsegrain/io/file_util.hpp"
#include "output.hpp"
#include "plots.hpp"

namespace coarsegrain::app {

namespace {

namespace fs = std::filesystem;

/// The surface the pictures draw: boundary facets in 3D, every element in 2D, with their nodes
/// renumbered 0.. in order of first use.
struct Surface {
    IndexMatrix faces;          ///< facets by surface point
    std::vector<Index> points;  ///< fine node of each surface point
};

Surface surface(const scene::FineModel& fine) {
    const IndexMatrix& cells = fine.mesh.dim() == 3 ? fine.boundary.facets : fine.mesh.elements;
    Surface s;
    s.faces.resize(cells.rows(), cells.cols());
    std::map<Index, Index> number;
    for (Index f = 0; f < cells.rows(); ++f)
        for (Index j = 0; j < cells.cols(); ++j) {
            const auto [it, added] =
                number.emplace(cells(f, j), static_cast<Index>(s.points.size()));
            if (added) s.points.push_back(cells(f, j));
            s.faces(f, j) = it->second;
        }
    return s;
}

/// Displacement of every surface point, rounded to 6 significant digits (enough for a picture).
nlohmann::json surface_displacements(const Surface& s, const Vector& u, int dim) {
    nlohmann::json j = nlohmann::json::array();
    for (const Index n : s.points) {
        nlohmann::json p = nlohmann::json::array();
        for (int d = 0; d < dim; ++d) p.push_back(std::stod(fmt::format("{:.6g}", u[dim * n + d])));
        j.push_back(p);
    }
    return j;
}

nlohmann::json errors_row(const coarsen::Errors& e) {
    return {{"energy_rel", e.energy_rel},
            {"l2_rel", e.l2_rel},
            {"max_displacement_rel", e.max_displacement_rel},
            {"compliance_ratio", e.compliance_ratio}};
}

void write_report_data(const scene::Scene& sc, const FineRun& f,
                       const std::vector<MethodResult>& results, const fs::path& file) {
    const int dim = f.model.mesh.dim();
    const Surface s = surface(f.model);
    nlohmann::json points = nlohmann::json::array(), faces = nlohmann::json::array();
    for (const Index n : s.points)
        points.push_back(to_std(f.model.mesh.rest_positions.row(n).transpose()));
    for (Index i = 0; i < s.faces.rows(); ++i) {
        nlohmann::json face = nlohmann::json::array();
        for (Index j = 0; j < s.faces.cols(); ++j) face.push_back(s.faces(i, j));
        faces.push_back(face);
    }
    nlohmann::json methods = nlohmann::json::array();
    for (const MethodResult& r : results)
        if (r.failure.empty())
            methods.push_back({{"method", r.method},
                               {"dofs", r.dofs},
                               {"build_seconds", r.build_seconds},
                               {"solve_seconds", r.factorize_and_solve},
                               {"speedup", r.speedup},
                               {"errors", errors_row(r.errors)},
                               {"u", surface_displacements(s, r.u_fine, dim)}});
    const nlohmann::json data = {
        {"scene", sc.source},
        {"dimension", dim},
        {"points", points},
        {"faces", faces},
        {"fine",
         {{"dofs", f.model.mesh.num_dofs()},
          {"solve_seconds", f.factorize_and_solve()},
          {"u", surface_displacements(s, f.solution.u, dim)}}},
        {"methods", methods},
    };
    io::write_atomically(file.string(), [&](std::ostream& os) { os << data.dump() << '\n'; });
}

std::string table_markdown(const FineRun& f, const std::vector<MethodResult>& results) {
    std::string t =
        "| method | coarse DOFs | build s | solve s | speedup | energy error | l2 error | "
        "max \\|u\\| error | compliance ratio |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    t += fmt::format("| fine | {} | | {:.3f} | 1 | 0 | 0 | 0 | 1 |\n", f.model.mesh.num_dofs(),
                     f.factorize_and_solve());
    for (const MethodResult& r : results)
        t += r.failure.empty()
                 ? fmt::format(
                       "| {} | {} | {:.2f} | {:.4f} | {:.0f}x | {:.3f} | {:.3f} | {:.3f} | "
                       "{:.3f} |\n",
                       r.method, r.dofs, r.build_seconds, r.factorize_and_solve, r.speedup,
                       r.errors.energy_rel, r.errors.l2_rel, r.errors.max_displacement_rel,
                       r.errors.compliance_ratio)
                 : fmt::format("| {} | failed: {} | | | | | | | |\n", r.method, r.failure);
    return t;
}

bool contains(const nlohmann::json& made, const std::string& file) {
    for (const auto& m : made)
        if (m == file) return true;
    return false;
}

std::string picture(const nlohmann::json& made, const std::string& file, const std::string& title,
                    const std::string& caption) {
    if (!contains(made, file))
        return fmt::format(
            "## {}\n\n({} was not made: Python 3 with matplotlib is needed; see the "
            "note on stderr.)\n\n",
            title, file);
    return fmt::format("## {}\n\n![{}]({})\n\n{}\n\n", title, title, file, caption);
}

/// A figure of the dynamics table: the number, or "-" for null.
std::string figure(const nlohmann::json& v, const char* format) {
    return v.is_null() ? "-" : fmt::format(fmt::runtime(format), v.get<double>());
}

/// The dynamic run's section of report.md, from its overview (simulate_overview).
std::string dynamics_markdown(const nlohmann::json& d) {
    const std::string folder = d["folder"];
    std::string md = fmt::format(
        "## Dynamics: released from rest under the loads\n\n"
        "The same fine model and the same coarse models (built once, for the table above), "
        "released from rest with the loads switched on at t = 0 and stepped by {} with dt = {} for "
        "{} steps. Every saved frame of each coarse model is carried to the fine mesh and "
        "compared with the fine frame of the same time. Files in `{}/` (as `coarsegrain "
        "simulate` writes them, without the ParaView series).\n\n",
        d["integrator"].get<std::string>(), d["dt"].get<double>(), d["steps"].get<int>(), folder);
    md +=
        "| model | DOFs | per step s | speedup per step | trajectory l2 error | period error | "
        "lag |\n|---|---:|---:|---:|---:|---:|---:|\n";
    const nlohmann::json& fine = d["fine"];
    md += fmt::format("| fine | {} | {:.2e} | 1 | 0 | period {} | 0 |\n", fine["dofs"].get<int>(),
                      fine["timings"]["per_step"].get<double>(), figure(fine["period"], "{:.4f}"));
    for (const nlohmann::json& m : d["methods"]) {
        if (m.contains("error")) {
            md += fmt::format("| {} | failed: {} | | | | | |\n", m["method"].get<std::string>(),
                              m["error"].get<std::string>());
            continue;
        }
        const nlohmann::json& probe0 =
            m["errors"]["phase"].empty() ? nlohmann::json::object() : m["errors"]["phase"][0];
        md += fmt::format(
            "| {} | {} | {:.2e} | {:.0f}x | {:.3g} | {} | {} |\n", m["method"].get<std::string>(),
            m["coarse"]["dofs"].get<int>(), m["coarse"]["timings"]["per_step"].get<double>(),
            m["speedup"]["per_step"].get<double>(), m["errors"]["trajectory_l2_rel"].get<double>(),
            figure(probe0.value("period_rel", nlohmann::json()), "{:+.3g}"),
            figure(probe0.value("lag", nlohmann::json()), "{:+.3g}"));
    }
    md +=
        "\nHow to read it:\n\n"
        "- *per step s*: wall time of one time step (one back-substitution with the step "
        "operator factorized once per run); *speedup per step*: the fine step's over the "
        "coarse one, measured in this run.\n"
        "- *trajectory l2 error*: sqrt(sum over saved times of |u_c - u|^2) / sqrt(sum of "
        "|u|^2), over every fine node.\n"
        "- *period error* and *lag*, on the first probe's dominant component, each "
        "signal minus its mean over the run: the period is the mean spacing of its upward zero "
        "crossings, the period error the coarse period over the fine one minus 1, the lag the "
        "coarse model's last upward crossing minus the fine one's of the same index (positive: "
        "the coarse model is late). \"-\" where a signal crosses its mean upward fewer than "
        "twice. A lag pairs the n-th crossings of both models, so it says how far apart they "
        "drifted only where the period error is small; with a period error of tens of percent "
        "it pairs unrelated crossings.\n\n";
    nlohmann::json made = nlohmann::json::array();
    for (const auto& p : d["plots"]) made.push_back(p);
    md += picture(made, folder + "/trajectory.png", "Probe displacements over time",
                  "Each probe's largest component against time: the fine model (black) and "
                  "every method.");
    md += picture(made, folder + "/animation.gif", "Animation",
                  "The fine model and every method side by side on one colour scale of |u|, "
                  "at up to 60 of the saved frames.");
    return md;
}

std::string report_markdown(const scene::Scene& sc, const std::string& command, const FineRun& f,
                            const std::vector<MethodResult>& results, const nlohmann::json& made,
                            const nlohmann::json* dynamics) {
    const scene::FineModel& fine = f.model;
    std::string md = fmt::format("# coarsegrain {}: {}\n\n", command, sc.source);
    md += fmt::format(
        "Fine model: {}D, {} {} elements, {} nodes, {} DOFs; assembled in {:.2f} s, factorized "
        "and solved in {:.2f} s ({} threads). Each method builds a coarse model, solves the same "
        "load on it and carries its solution back to the fine mesh, where it is compared with "
        "the fine solution.\n\n",
        fine.mesh.dim(), fine.mesh.num_elements(), mesh::element_name(fine.mesh.type),
        fine.mesh.num_nodes(), fine.mesh.num_dofs(), f.timings["assemble"], f.factorize_and_solve(),
        omp_get_max_threads());
    md += table_markdown(f, results);
    md +=
        "\nHow to read it:\n\n"
        "- *build s*: seconds to build the coarse model (done once, before any simulation). "
        "*solve s*: coarse factorization + solve. *speedup*: the fine factorization + solve "
        "over the coarse one, measured in this run.\n"
        "- *energy error*: ||u_c - u||_K / ||u||_K with K the fine stiffness. It is the natural "
        "measure for the material-adapted hierarchy (mra), whose basis functions carry the fine "
        "strain; methods that carry their solution to the fine mesh by barycentric "
        "interpolation (effective-tensor, naive, voigt, reuss) spread strain into the stiff "
        "material and score high on it even when the shape is right, so compare those by the "
        "*l2 error* |u_c - u| / |u| and the *compliance ratio* f.u_c / f.u (1 is perfect, below "
        "1 too stiff, above 1 too soft).\n"
        "- *max |u| error*: relative error of the largest displacement.\n\n";
    md += picture(made, "deformed.png", "Deformed shapes",
                  "The fine solution and each method's, on the fine mesh's surface, displaced by "
                  "the same magnified factor and coloured by |u| on one scale.");
    md += picture(made, "methods.png", "Error and speedup per method",
                  "Left: energy and l2 errors (log scale). Right: speedup of the coarse solve "
                  "over the fine solve.");
    bool mra = false;
    for (const MethodResult& r : results)
        mra = mra || (r.failure.empty() && r.summary["coarse"].contains("levels"));
    if (mra)
        md += picture(made, "mra_levels.png", "Material-adapted hierarchy: error per level",
                      "||u^k - u||_A / ||g||_2 of the single-level solve on every level k "
                      "(Chen et al. 2019, Fig. 9; level 1 is the coarsest). Per-level figures "
                      "are in each mra folder's summary.json and mra_levels.csv.");
    if (dynamics) md += dynamics_markdown(*dynamics);
    md +=
        "## Files\n\n"
        "- `summary.json`: the table's figures (`methods`) and the fine model's.\n"
        "- `solution_fine.vtu`: the fine solution (open in ParaView, Warp By Vector with "
        "`displacement`).\n";
    for (const MethodResult& r : results)
        if (r.failure.empty())
            md += fmt::format(
                "- `{}/`: `summary.json`, `solution_coarse.vtu` (its solution on the "
                "fine mesh, with `error`) and the method's own files.\n",
                r.method);
    if (dynamics)
        md += fmt::format(
            "- `{}/`: the dynamic run: `summary.json` (as `coarsegrain simulate`'s), "
            "`trajectory.csv`, `trajectory.png`, `animation_data.bin` and `animation.gif`.\n",
            (*dynamics)["folder"].get<std::string>());
    md += "\nThe scene, every key and each method's options: docs/guide.md.\n";
    return md;
}

}  // namespace

nlohmann::json write_report(const scene::Scene& sc, const std::string& command, const FineRun& f,
                            const std::vector<MethodResult>& results, const fs::path& dir,
                            const nlohmann::json* dynamics) {
    const Phase phase("report");
    write_report_data(sc, f, results, dir / "report_data.json");
    nlohmann::json made = nlohmann::json::array();
    const auto plot = [&](const PlotOutput& p) {
        if (make_plot(dir.string(), p))
            for (const std::string& file : p.files) made.push_back(file);
    };
    plot({"plot_report.py", {"report_data.json"}, {"deformed.png", "methods.png"}});
    std::vector<std::string> csvs = {"mra_levels.png"};
    for (const MethodResult& r : results)
        if (fs::exists(dir / r.method / "mra_levels.csv"))
            csvs.push_back(r.method + "/mra_levels.csv");
    if (csvs.size() > 1) plot({"plot_mra.py", csvs, {"mra_levels.png"}});
    const std::string md = report_markdown(sc, command, f, results, made, dynamics);
    io::write_atomically((dir / "report.md").string(), [&](std::ostream& os) { os << md; });
    return made;
}

void print_comparison_table(const scene::Scene& sc, const std::string& command, const FineRun& f,
                            const std::vector<MethodResult>& results) {
    std::printf("coarsegrain %s: %s\n", command.c_str(), sc.source.c_str());
    std::printf("  %-18s %9s %9s %9s %9s %8s %8s %8s %8s\n", "method", "DOFs", "build s", "solve s",
                "speedup", "energy", "l2", "max|u|", "compl.");
    std::printf("  %-18s %9d %9s %9.4f %9s %8s %8s %8s %8s\n", "fine", f.model.mesh.num_dofs(), "-",
                f.factorize_and_solve(), "1", "0", "0", "0", "1");
    for (const MethodResult& r : results)
        if (r.failure.empty())
            std::printf("  %-18s %9d %9.3f %9.4f %8.0fx %8.4f %8.4f %8.4f %8.4f\n",
                        r.method.c_str(), r.dofs, r.build_seconds, r.factorize_and_solve, r.speedup,
                        r.errors.energy_rel, r.errors.l2_rel, r.errors.max_displacement_rel,
                        r.errors.compliance_ratio);
        else
            std::printf("  %-18s failed: %s\n", r.method.c_str(), r.failure.c_str());
    std::printf(
        "  (errors against the fine solution: energy and l2 relative, max|u| relative "
        "error of the largest displacement, compliance ratio f.u_c / f.u)\n");
}

}  // namespace coarsegrain::app
