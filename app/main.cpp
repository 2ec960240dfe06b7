// The coarsegrain command-line tool (DESIGN.md, "The command-line contract").
#include <fmt/ranges.h>
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/progress.hpp"
#include "run_coarsen.hpp"
#include "run_dynamics.hpp"
#include "run_solve.hpp"

namespace cg = coarsegrain;

namespace {

constexpr int kExitError = 1;  // bad input or a numerical failure
constexpr int kExitUsage = 2;  // bad command line

std::vector<std::string> split_methods(const std::string& list) {
    std::vector<std::string> methods;
    std::size_t start = 0;
    for (std::size_t comma; (comma = list.find(',', start)) != std::string::npos; start = comma + 1)
        methods.push_back(list.substr(start, comma - start));
    methods.push_back(list.substr(start));
    return methods;
}

/// --method's check: "all" or known method names separated by commas, each once.
std::string check_methods(const std::string& list) {
    if (list == "all") return {};
    const std::vector<std::string>& known = cg::coarsen::method_names();
    const std::vector<std::string> methods = split_methods(list);
    for (std::size_t i = 0; i < methods.size(); ++i) {
        if (std::find(known.begin(), known.end(), methods[i]) == known.end())
            return fmt::format(
                "unknown method '{}': expected all or one or more of {} separated "
                "by commas",
                methods[i], fmt::join(known, ", "));
        if (std::find(methods.begin(), methods.begin() + static_cast<std::ptrdiff_t>(i),
                      methods[i]) != methods.begin() + static_cast<std::ptrdiff_t>(i))
            return fmt::format("method '{}' is given twice", methods[i]);
    }
    return {};
}

std::vector<std::string> selected_methods(const cg::scene::Scene& scene, const std::string& list) {
    return list == "all" ? cg::coarsen::configured_methods(scene) : split_methods(list);
}

/// selected_methods, or none for an empty --method (the fine model alone).
std::vector<std::string> optional_methods(const cg::scene::Scene& scene, const std::string& list) {
    return list.empty() ? std::vector<std::string>{} : selected_methods(scene, list);
}

}  // namespace

int main(int argc, char** argv) {
    coarsegrain::retain_freed_memory();
    CLI::App app{
        "coarsegrain: numerical coarsening of heterogeneous linear-elastic materials.\n"
        "Every command writes DIR/summary.json and DIR/*.vtu (open them in ParaView)."};
    app.require_subcommand(1);
    app.fallthrough();  // global options may also follow the subcommand
    bool quiet = false;
    int threads = 0;
    app.add_flag("-q,--quiet", quiet, "no progress lines on stderr");
    app.add_option("--threads", threads, "OpenMP threads (default: all cores)")
        ->check(CLI::Range(1, 1024));

    std::string scene_file, out_dir = "out/solve", demo_out = "out/demo";
    std::string coarsen_scene, coarsen_out = "out/coarsen", method = "effective-tensor";
    double demo_scale = 1.0;
    CLI::App* solve = app.add_subcommand("solve", "static solve of a scene on its fine mesh");
    solve->add_option("scene", scene_file, "scene file (JSON)")->required();
    solve->add_option("--out", out_dir, "output folder")->capture_default_str();
    CLI::App* coarsen = app.add_subcommand(
        "coarsen", "build a coarse model with one method and compare it with the fine solve");
    coarsen->add_option("scene", coarsen_scene, "scene file (JSON) with a \"coarse\" block")
        ->required();
    coarsen
        ->add_option("--method", method,
                     "coarsening method, several separated by commas, or all (every method the "
                     "scene's coarse block configures)")
        ->check(CLI::Validator(check_methods, "METHOD[,METHOD...]|all"))
        ->capture_default_str();
    coarsen->add_option("--out", coarsen_out, "output folder")->capture_default_str();
    std::string coarsen_export;
    coarsen
        ->add_option("--export", coarsen_export,
                     "inp: also write each coarse element model as a CalculiX / Abaqus deck, "
                     "coarse_model.inp, and the hierarchy's matrices as Matrix Market files")
        ->check(CLI::IsMember({"inp"}));
    coarsen->footer(
        "Methods: effective-tensor (Kharevych et al. 2009: one anisotropic tensor per element of\n"
        "coarse.mesh); naive, voigt, reuss (averages of the Lame parameters, tensors, compliances\n"
        "over the same coarse mesh); mra (Chen et al. 2019), mra-linear and mra-dirac (mra with\n"
        "coarse.refinement linear / dirac), mra-linear-blind and mra-dirac-blind (the same with\n"
        "coarse.dirichlet ignore: built without the Dirichlet conditions, as Chen et al. 2018).\n"
        "effective-tensor reads coarse.mesh, coarse.normals (coarse|fine), coarse.boundary\n"
        "(neumann|mixed) and coarse.map (barycentric|harmonic); the averages read coarse.mesh.\n"
        "Files: summary.json, solution_fine.vtu, solution_coarse.vtu; with a coarse.mesh method\n"
        "also coarse_model.vtu (the coarse mesh with its tensors: a scene mesh that `coarsegrain\n"
        "solve` simulates without the fine mesh) and, for effective-tensor, harmonic.vtu;\n"
        "with --export inp, coarse_model.inp (a CalculiX / Abaqus deck of that model; the\n"
        "hierarchy: coarse_K.mtx, coarse_M.mtx, coarse_f.mtx and to_fine.mtx). The mra methods\n"
        "on a triangle or tet mesh without coarse.level_meshes make its coarser levels and write\n"
        "them as level_<k>.vtu.\n"
        "Several methods compare them: DIR/<method>/ holds each one's files, and DIR/report.md\n"
        "the table and pictures (as `coarsegrain demo`).\n"
        "See docs/guide.md, \"Coarsening\".");
    std::string sim_scene, sim_out = "out/simulate", sim_methods, modes_scene,
                           modes_out = "out/modes", modes_methods;
    int modes_count = 10;
    CLI::App* simulate = app.add_subcommand(
        "simulate", "time stepping (scene \"dynamics\"), fine and coarse, compared");
    simulate->add_option("scene", sim_scene, "scene file (JSON) with a \"dynamics\" block")
        ->required();
    simulate
        ->add_option("--method", sim_methods,
                     "coarse models to step beside the fine one: methods separated by commas, "
                     "or all (default: the fine model alone)")
        ->check(CLI::Validator(check_methods, "METHOD[,METHOD...]|all"));
    simulate->add_option("--out", sim_out, "output folder")->capture_default_str();
    std::string sim_export;
    simulate
        ->add_option("--export", sim_export,
                     "inp: also write each coarse element model as a CalculiX / Abaqus deck with "
                     "the run as a *DYNAMIC step, coarse_model.inp, and the hierarchy's matrices "
                     "as Matrix Market files")
        ->check(CLI::IsMember({"inp"}));
    simulate->footer(
        "Scene: \"dynamics\": {\"integrator\": \"midpoint\"|\"implicit_euler\", \"dt\", "
        "\"steps\",\n"
        "\"output_every\", \"start\": \"rest\"|\"static\", \"initial_velocity\", \"damping\":\n"
        "{\"rayleigh\": [alpha, beta]}, \"mass\": \"consistent\"|\"lumped\"}; coarse.mass\n"
        "(lumped|consistent|galerkin) chooses the effective tensors' and baselines' coarse mass.\n"
        "Files: fine.pvd (+ fine/), <method>.pvd (+ <method>/) for ParaView, trajectory.csv,\n"
        "trajectory.png, animation.gif (every model side by side; its data animation_data.bin),\n"
        "summary.json; an mra method on automatic levels also <method>/level_<k>.vtu.\n"
        "See docs/guide.md, \"Dynamics\".");
    CLI::App* modes = app.add_subcommand(
        "modes", "natural frequencies and modes, fine and coarse, paired by MAC");
    modes->add_option("scene", modes_scene, "scene file (JSON)")->required();
    modes
        ->add_option("--method", modes_methods,
                     "coarse models to compare: methods separated by commas, or all (default: "
                     "the fine model alone)")
        ->check(CLI::Validator(check_methods, "METHOD[,METHOD...]|all"));
    modes->add_option("--count", modes_count, "number of lowest modes")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    modes->add_option("--out", modes_out, "output folder")->capture_default_str();
    modes->footer(
        "Files: mode_NN.vtu (fine mode \"mode\" and each method's paired mode), frequencies.csv,\n"
        "frequencies.png, summary.json; an mra method on automatic levels also\n"
        "<method>/level_<k>.vtu. See docs/guide.md, \"Dynamics\".");
    CLI::App* demo = app.add_subcommand(
        "demo",
        "the built-in scene, a layered beam (stiff/soft, contrast 1000) hung under gravity: fine\n"
        "solve, every coarsening method, a table and out/demo/report.md with pictures; then the\n"
        "same models released from rest under gravity and stepped in time (out/demo/dynamics/)");
    demo->add_option("--out", demo_out, "output folder")->capture_default_str();
    demo->add_option("--scale", demo_scale,
                     "grid resolution factor: 1 = 48x12x12 hexes, 0.67 = 32x8x8, 0.33 = 16x4x4\n"
                     "(16b x 4b x 4b hexes, b = round(3 S)); 1.33 = 64x16x16 and 1.67 = 80x20x20\n"
                     "take minutes and GBs (docs/guide.md, \"The demo\")")
        ->check(CLI::Range(0.25, 1.67))
        ->capture_default_str();

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return kExitUsage;
    }
    cg::set_progress_enabled(!quiet);
    if (threads > 0) omp_set_num_threads(threads);

    int failed = 0;  // methods of a comparison that could not run
    try {
        const auto start = std::chrono::steady_clock::now();
        const auto since_start = [&] {
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        };
        if (*solve) {
            const cg::scene::Scene sc = cg::scene::load_scene(scene_file);
            const double read = since_start();
            cg::app::run_solve(sc, out_dir, read);
        } else if (*coarsen) {
            cg::scene::Scene sc = cg::scene::load_scene(coarsen_scene);
            const double read = since_start();
            const std::vector<std::string> methods = selected_methods(sc, method);
            failed = cg::app::run_coarsen(std::move(sc), methods, coarsen_out, "coarsen", read,
                                          {coarsen_export == "inp"});
        } else if (*simulate) {
            const cg::scene::Scene sc = cg::scene::load_scene(sim_scene);
            const double read = since_start();
            failed = cg::app::run_simulate(sc, optional_methods(sc, sim_methods), sim_out, read,
                                           {sim_export == "inp"});
        } else if (*modes) {
            const cg::scene::Scene sc = cg::scene::load_scene(modes_scene);
            const double read = since_start();
            failed = cg::app::run_modes(sc, optional_methods(sc, modes_methods), modes_count,
                                        modes_out, read);
        } else if (*demo) {
            const cg::scene::Scene sc =
                cg::scene::parse_scene(cg::scene::demo_scene(demo_scale), "demo", "");
            const double read = since_start();
            failed = cg::app::run_demo(sc, demo_out, read);
        }
    } catch (const cg::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return kExitError;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "error: out of memory\n");
        return kExitError;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: internal: %s\n", e.what());
        return kExitError;
    }
    if (failed > 0) {
        std::fprintf(stderr, "error: %d method%s failed (see the table and summary.json)\n", failed,
                     failed == 1 ? "" : "s");
        return kExitError;
    }
    return 0;
}
