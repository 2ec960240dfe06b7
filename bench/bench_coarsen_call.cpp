// The C++ calls behind the Python module's coarsegrain.coarsen(load_scene(SCENE), METHOD), made
// directly: load_scene, validate_method, build_fine_model, coarsen::solve_fine and
// coarsen::run_method. Prints the best wall-clock seconds of --repeat runs (default 1) as one
// line, "seconds <best>", which bench/python_vs_cli.py compares with the Python call.
// A plain main (not Google Benchmark): each figure is one end-to-end measurement.
//   bench_coarsen_call SCENE.json METHOD [REPEAT]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/common/error.hpp"

namespace cg = coarsegrain;

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: bench_coarsen_call SCENE.json METHOD [REPEAT]\n");
        return 2;
    }
    const std::string file = argv[1], method = argv[2];
    const int repeat = argc > 3 ? std::max(1, std::stoi(argv[3])) : 1;
    double best = 1e300, energy = 0;
    try {
        for (int i = 0; i < repeat; ++i) {
            const auto start = std::chrono::steady_clock::now();
            const cg::scene::Scene scene = cg::scene::load_scene(file);
            cg::coarsen::validate_method(scene, method);
            cg::coarsen::FineRun run =
                cg::coarsen::solve_fine(scene, cg::scene::build_fine_model(scene), {method});
            const cg::coarsen::MethodRun r = cg::coarsen::run_method(scene, run, method);
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            best = std::min(best, seconds);
            energy = r.errors.energy_rel;
        }
    } catch (const cg::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    std::printf("seconds %.6f energy_rel %.17g\n", best, energy);
    return 0;
}
