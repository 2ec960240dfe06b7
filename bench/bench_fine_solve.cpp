// Fine static solve of a 64x16x16 hex cantilever (about 55K DOFs), end to end (assemble,
// factorize, solve), with CHOLMOD supernodal and Eigen SimplicialLDLT in the same run.
// Prints the ratio LDLT / CHOLMOD and the peak resident memory.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cstdio>

#include "bench_times.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace cg = coarsegrain;

namespace {

cg::scene::Scene cantilever() {
    // Scale 2: 64x16x16 hexes (the demo itself is 32x8x8), two materials in layers.
    nlohmann::json j = cg::scene::demo_scene(2.0);
    return cg::scene::parse_scene(j, "bench", "");
}

void run(benchmark::State& state, cg::solve::Backend backend) {
    const cg::scene::Scene sc = cantilever();
    cg::solve::SolverOptions opt;
    opt.backend = backend;
    cg::Timings t;
    for (auto _ : state) {
        t = {};
        const cg::scene::FineModel model = cg::scene::build_fine_model(sc, &t);
        const cg::scene::StaticSolution s = cg::scene::solve_static(model, opt, &t);
        benchmark::DoNotOptimize(s.u.data());
        state.counters["dofs"] = model.mesh.num_dofs();
    }
    state.counters["assemble_s"] = t["assemble"];
    state.counters["factorize_s"] = t["factorize"];
    state.counters["solve_s"] = t["solve"];
}

void BM_CantileverCholmod(benchmark::State& s) { run(s, cg::solve::Backend::Cholmod); }
void BM_CantileverLDLT(benchmark::State& s) { run(s, cg::solve::Backend::SimplicialLDLT); }

}  // namespace

BENCHMARK(BM_CantileverCholmod)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();
BENCHMARK(BM_CantileverLDLT)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    // Per-benchmark real times, to print the ratio measured in this run.
    double chol = 0, ldlt = 0;
    for (const auto& [name, time] : coarsegrain::bench::run_and_collect_times()) {
        if (name.find("Cholmod") != std::string::npos) chol = time;
        if (name.find("LDLT") != std::string::npos) ldlt = time;
    }
    if (chol > 0 && ldlt > 0)
        std::printf(
            "end to end: CHOLMOD %.0f ms, SimplicialLDLT %.0f ms, ratio LDLT/CHOLMOD %.2f\n", chol,
            ldlt, ldlt / chol);
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    std::printf("peak resident memory: %.0f MB\n", static_cast<double>(r.ru_maxrss) / 1024.0);
    benchmark::Shutdown();
    return 0;
}
