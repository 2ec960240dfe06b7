// Phases of the fine static solve of bench/ccx_vs_coarsegrain.py's problem (a layered
// 48x18x18 hex box, 52K free DOFs): CHOLMOD analyze, factorize and solve, with CHOLMOD's
// default ordering (node_dofs = 1: AMD, then METIS on the DOF matrix) and with the ordering of
// the node graph (node_dofs = 3); the factorization also with 1 and 2 threads (OpenMP, which
// the solver passes on to OpenBLAS). Counters: nnz(L) and the factorization's flops.
//   bench_spd_ordering [--benchmark_filter=Factorize]
#include <benchmark/benchmark.h>
#include <omp.h>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace cg = coarsegrain;

namespace {

// The scene of bench/ccx_vs_coarsegrain.py (clamped at x = 0, gravity and an end pressure).
const cg::fem::ReducedSystem& ccx_system() {
    static const cg::fem::ReducedSystem sys = [] {
        const double eps = 1e-9;
        const nlohmann::json j = {
            {"dimension", 3},
            {"mesh",
             {{"grid",
               {{"min", {0, 0, 0}},
                {"max", {4, 1.5, 1.5}},
                {"cells", {48, 18, 18}},
                {"element", "hex"}}}}},
            {"materials",
             {{"1", {{"E", 1000.0}, {"nu", 0.3}, {"density", 2.0}}},
              {"2", {{"E", 10.0}, {"nu", 0.45}, {"density", 0.5}}}}},
            {"material_field", {{"layers", {{"axis", 0}, {"thickness", 0.25}, {"ids", {1, 2}}}}}},
            {"dirichlet",
             {{{"box", {{"min", {-eps, -eps, -eps}}, {"max", {eps, 1.5 + eps, 1.5 + eps}}}},
               {"value", {0, 0, 0}}}}},
            {"loads",
             {{"gravity", {0, 0, -9.81}},
              {"traction",
               {{{"box", {{"min", {4 - eps, -eps, -eps}}, {"max", {4 + eps, 2, 2}}}},
                 {"value", {-4.0, 0, 0}}}}}}},
        };
        const cg::scene::FineModel m =
            cg::scene::build_fine_model(cg::scene::parse_scene(j, "bench", ""), nullptr);
        return cg::fem::reduce(m.K, m.f, m.bc);
    }();
    return sys;
}

cg::solve::SpdSolver make_solver(int node_dofs) {
    cg::solve::SolverOptions options;
    options.node_dofs = node_dofs;
    return cg::solve::SpdSolver(options);
}

void stats_counters(benchmark::State& state, const cg::solve::SpdSolver& solver) {
    const cg::solve::FactorStats s = solver.factor_stats();
    state.counters["lnz"] = s.nonzeros;
    state.counters["flops"] = s.flops;
    state.SetLabel(s.ordering);
}

void BM_Analyze(benchmark::State& state) {
    const auto& sys = ccx_system();
    cg::solve::SpdSolver solver = make_solver(static_cast<int>(state.range(0)));
    for (auto _ : state) solver.analyze(sys.K);
    stats_counters(state, solver);
}

void BM_Factorize(benchmark::State& state) {
    const auto& sys = ccx_system();
    cg::solve::SpdSolver solver = make_solver(static_cast<int>(state.range(0)));
    solver.analyze(sys.K);
    const int threads = omp_get_max_threads();
    omp_set_num_threads(static_cast<int>(state.range(1)));
    for (auto _ : state) solver.factorize(sys.K);
    omp_set_num_threads(threads);
    stats_counters(state, solver);
}

void BM_Solve(benchmark::State& state) {
    const auto& sys = ccx_system();
    cg::solve::SpdSolver solver = make_solver(static_cast<int>(state.range(0)));
    solver.compute(sys.K);
    for (auto _ : state) benchmark::DoNotOptimize(solver.solve(sys.rhs).data());
    stats_counters(state, solver);
}

}  // namespace

BENCHMARK(BM_Analyze)
    ->ArgName("node_dofs")
    ->Arg(1)
    ->Arg(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Factorize)
    ->ArgNames({"node_dofs", "threads"})
    ->Args({1, 1})
    ->Args({3, 1})
    ->Args({3, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Solve)
    ->ArgName("node_dofs")
    ->Arg(1)
    ->Arg(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
