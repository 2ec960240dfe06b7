// Exact fine static solves at a 1e-8 relative residual on N^3 hex cubes, CHOLMOD against the
// mra-pcg backend (conjugate gradients preconditioned by a V-cycle over the radius-1
// material-adapted hierarchy, mra/preconditioner.hpp), each configuration in its own process so
// that its peak resident memory is its own. The cube is clamped at z = 0 under gravity -z; the
// materials are a checkerboard of cubes of side 1/8 or a 4^3 lattice of stiff spheres (radius
// 0.09, 18% of the volume) in a soft matrix, at the stiffness contrasts given. Per run:
//   - cholmod: assembly, analysis + factorization, the solve; a second right-hand side (gravity
//     along x) with the factorization;
//   - mra-pcg: the hierarchy's build, the V-cycle's set-up (Galerkin copies, eigenvalue
//     estimates, the coarsest factorization), the PCG iterations, and the same second
//     right-hand side with the preconditioner kept;
// each with the true relative residual ||f - K u|| / ||f|| of its answer. Prints a markdown
// table and writes it to docs/fine_pcg_bench.md.
//
//   OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 build/release/bench/bench_fine_pcg
//       [--sizes 32,48] [--contrasts 1e3,1e6] [--fields checker,spheres]
//       [--backends cholmod,mra-pcg] [--out FILE]
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/preconditioner.hpp"
#include "coarsegrain/scene/scene.hpp"

using namespace coarsegrain;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

double peak_rss_gb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB
}

nlohmann::json cube_scene(int n, const std::string& field, double contrast) {
    nlohmann::json j = {
        {"dimension", 3},
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {n, n, n}}, {"element", "hex"}}}}},
        {"materials",
         {{"1", {{"E", contrast}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", 1.0}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, -1, -1e-9}}, {"max", {2, 2, 1e-9}}}}}}},
        {"loads", {{"gravity", {0, 0, -1}}}}};
    if (field == "checker") {
        j["material_field"] = {{"checkerboard", {{"size", 0.125}, {"ids", {1, 2}}}}};
    } else {
        nlohmann::json centres = nlohmann::json::array();
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 4; ++k)
                for (int l = 0; l < 4; ++l)
                    centres.push_back({0.125 + 0.25 * i, 0.125 + 0.25 * k, 0.125 + 0.25 * l});
        j["material_field"] = {
            {"spheres", {{"centres", centres}, {"radius", 0.09}, {"inside", 1}, {"outside", 2}}}};
    }
    return j;
}

/// One configuration in this process: a JSON line on stdout.
int run_one(const std::string& backend, int n, const std::string& field, double contrast) {
    const scene::Scene sc = scene::parse_scene(cube_scene(n, field, contrast), "cube", "");
    nlohmann::json out = {{"backend", backend}, {"n", n}, {"field", field}, {"contrast", contrast}};
    auto t0 = Clock::now();
    const scene::FineModel model = scene::build_fine_model(sc);
    out["assemble_s"] = seconds_since(t0);
    const fem::ReducedSystem sys = fem::reduce(model.K, model.f, model.bc);
    Eigen::VectorXd gx = Eigen::VectorXd::Zero(3);
    gx[0] = 1;
    const fem::ReducedSystem sys2 =
        fem::reduce(model.K,
                    scene::load_vector(
                        [&] {
                            scene::Scene s = sc;
                            s.gravity = gx;
                            return s;
                        }(),
                        model.mesh, model.materials, model.boundary, "mesh"),
                    model.bc);
    out["dofs"] = sys.K.rows();
    const auto residual = [&](const Vector& u, const Vector& f) {
        Vector r;
        solve::symmetric_multiply(sys.K, u, r);
        return (f - r).norm() / f.norm();
    };
    if (backend == "cholmod") {
        solve::SolverOptions o;
        o.node_dofs = 3;
        solve::SpdSolver s(o);
        t0 = Clock::now();
        s.compute(sys.K);
        out["setup_s"] = seconds_since(t0);
        t0 = Clock::now();
        const Vector u = s.solve(sys.rhs);
        out["solve_s"] = seconds_since(t0);
        t0 = Clock::now();
        const Vector u2 = s.solve(sys2.rhs);
        out["solve2_s"] = seconds_since(t0);
        out["residual"] = residual(u, sys.rhs);
        out["nnz_L"] = s.factor_stats().nonzeros;
    } else {
        t0 = Clock::now();
        const auto factory =
            mra::hierarchy_preconditioner(model.mesh, model.bc.dofs, sc.preconditioner);
        const std::unique_ptr<solve::Preconditioner> M = factory(sys.K);
        out["setup_s"] = seconds_since(t0);
        const auto* mg = dynamic_cast<const mra::MultigridPreconditioner*>(M.get());
        double build = 0;
        for (const auto& [phase, seconds] : mg->hierarchy().timings.entries()) build += seconds;
        out["build_s"] = build;
        out["levels"] = mg->hierarchy().num_levels();
        out["coarsest_dofs"] = mg->level_sizes().front().first;
        solve::PcgOptions pcg;
        pcg.tolerance = 1e-8;
        solve::PcgReport report;
        t0 = Clock::now();
        const Vector u = solve::pcg(sys.K, sys.rhs, *M, pcg, &report);
        out["solve_s"] = seconds_since(t0);
        out["iterations"] = report.iterations;
        t0 = Clock::now();
        const Vector u2 = solve::pcg(sys.K, sys2.rhs, *M, pcg, &report);
        out["solve2_s"] = seconds_since(t0);
        out["iterations2"] = report.iterations;
        out["residual"] = residual(u, sys.rhs);
    }
    out["peak_gb"] = peak_rss_gb();
    fmt::print("{}\n", out.dump());
    return 0;
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> parts;
    std::stringstream in(s);
    for (std::string p; std::getline(in, p, ',');) parts.push_back(p);
    return parts;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc == 6 && std::string(argv[1]) == "--one")
        return run_one(argv[2], std::atoi(argv[3]), argv[4], std::atof(argv[5]));
    std::string sizes = "32,48", contrasts = "1e3,1e6", fields = "checker,spheres",
                backends = "cholmod,mra-pcg",
                out = std::string(COARSEGRAIN_SOURCE_DIR) + "/docs/fine_pcg_bench.md";
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--sizes")
            sizes = value;
        else if (key == "--contrasts")
            contrasts = value;
        else if (key == "--fields")
            fields = value;
        else if (key == "--backends")
            backends = value;
        else if (key == "--out")
            out = value;
        else {
            fmt::print(stderr, "unknown option {}\n", key);
            return 2;
        }
    }
    std::vector<std::string> rows = {
        "| cube | field | contrast | DOFs | backend | set-up s | solve s | total s | 2nd rhs s | "
        "iterations | residual | peak GB |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|"};
    for (const std::string& n : split(sizes))
        for (const std::string& field : split(fields))
            for (const std::string& contrast : split(contrasts))
                for (const std::string& backend : split(backends)) {
                    const std::string cmd =
                        fmt::format("{} --one {} {} {} {}", argv[0], backend, n, field, contrast);
                    std::FILE* pipe = popen(cmd.c_str(), "r");
                    std::string text;
                    char buffer[4096];
                    while (pipe && std::fgets(buffer, sizeof buffer, pipe)) text += buffer;
                    if (!pipe || pclose(pipe) != 0 || text.empty()) {
                        fmt::print(stderr, "{} failed\n", cmd);
                        continue;
                    }
                    const nlohmann::json r = nlohmann::json::parse(text);
                    const bool pcg = backend != "cholmod";
                    const std::string its = pcg ? fmt::format("{} / {}", r["iterations"].get<int>(),
                                                              r["iterations2"].get<int>())
                                                : "-";
                    const std::string setup =
                        pcg ? fmt::format("{:.2f} (build {:.2f}, {} levels, coarsest {})",
                                          r["setup_s"].get<double>(), r["build_s"].get<double>(),
                                          r["levels"].get<int>(), r["coarsest_dofs"].get<long>())
                            : fmt::format("{:.2f}", r["setup_s"].get<double>());
                    rows.push_back(
                        fmt::format("| {}^3 | {} | {} | {} | {} | {} | {:.2f} | {:.2f} | {:.2f} | "
                                    "{} | {:.1e} | "
                                    "{:.2f} |",
                                    n, field, contrast, r["dofs"].get<long>(), backend, setup,
                                    r["solve_s"].get<double>(),
                                    r["setup_s"].get<double>() + r["solve_s"].get<double>(),
                                    r["solve2_s"].get<double>(), its, r["residual"].get<double>(),
                                    r["peak_gb"].get<double>()));
                    fmt::print("{}\n", rows.back());
                    std::fflush(stdout);
                }
    std::ofstream file(out);
    for (const std::string& row : rows) file << row << "\n";
    fmt::print(stderr, "wrote {}\n", out);
    return 0;
}
