// RS post-warp (Chen 2019, Eq. 13) on the 64x16x16 hex beam clamped at x = 0 (56,355 DOFs):
// construction (Laplacian assembly and its one scalar CHOLMOD factorization) and one warp, split
// into the RS transforms with the right-hand sides and the back-substitution; on the regular
// grid (one cell's quadrature data for all) and on the same grid with its interior distorted
// (data per element). For context, one CHOLMOD factorization and solve of the elasticity
// stiffness of the same mesh and clamp; the ratios are printed at the end.
// Run: ./build/release/bench/bench_rs_warp
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "bench_times.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;

namespace {

/// The 4 x 1 x 1 beam in 64 x 16 x 16 hexes, interior nodes optionally moved by up to 20% of
/// the spacing (deterministic, GridInfo dropped).
mesh::Mesh beam(bool distorted) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                                   Eigen::Vector3d(4, 1, 1), Eigen::Vector3i(64, 16, 16));
    if (distorted) {
        for (Index v = 0; v < m.num_nodes(); ++v) {
            auto x = m.rest_positions.row(v);
            if ((x.array() > 1e-12).all() &&
                (x.array() < Eigen::Array<double, 1, 3>(4, 1, 1) - 1e-12).all())
                for (int d = 0; d < 3; ++d) x[d] += 0.2 / 16 * std::sin(12.9898 * v + 78.233 * d);
        }
        m.grid.reset();
    }
    return m;
}

fem::Dirichlet clamp(const mesh::Mesh& m) {
    std::vector<Index> face;
    for (Index v = 0; v < m.num_nodes(); ++v)
        if (m.rest_positions(v, 0) < 1e-12) face.push_back(v);
    fem::Dirichlet bc;
    bc.fix_nodes(face, Eigen::Vector3d::Zero());
    return bc;
}

/// A linearized bending of the beam by about a radian at its tip (what a coarse linear solve
/// under a tip load looks like): u_z = 0.1 x², u_x = -0.2 x (z - 0.5).
Vector bent(const mesh::Mesh& m) {
    Vector u(m.num_dofs());
    for (Index v = 0; v < m.num_nodes(); ++v) {
        const double x = m.rest_positions(v, 0), z = m.rest_positions(v, 2);
        u.segment<3>(3 * v) = Eigen::Vector3d(-0.2 * x * (z - 0.5), 0, 0.1 * x * x);
    }
    return u;
}

void BM_RsWarpConstruct(benchmark::State& state, bool distorted) {
    const mesh::Mesh m = beam(distorted);
    const fem::Dirichlet bc = clamp(m);
    Timings t;
    for (auto _ : state) {
        t = {};
        const fem::RsWarp warp(m, bc, {}, &t);
        benchmark::DoNotOptimize(&warp);
    }
    state.counters["dofs"] = m.num_dofs();
    const solve::FactorStats stats = fem::RsWarp(m, bc).factor_stats().front();
    state.counters["nnz_L"] = stats.nonzeros;
    state.counters["gflop"] = 1e-9 * stats.flops;
    state.SetLabel(stats.ordering);
    state.counters["assemble_ms"] = 1e3 * t["assemble"];
    state.counters["analyze_ms"] = 1e3 * t["analyze"];
    state.counters["factorize_ms"] = 1e3 * t["factorize"];
}

void BM_RsWarpApply(benchmark::State& state, bool distorted) {
    const mesh::Mesh m = beam(distorted);
    const fem::RsWarp warp(m, clamp(m));
    const Vector u = bent(m);
    Timings t;
    for (auto _ : state) benchmark::DoNotOptimize(warp(u, &t).data());
    const double n = static_cast<double>(state.iterations());
    state.counters["rs_ms"] = 1e3 * t["rs"] / n;
    state.counters["solve_ms"] = 1e3 * t["solve"] / n;
}

/// Factorization and solve of the elasticity stiffness K_ff of the same beam and clamp
/// (assembly and reduction outside the timing), CHOLMOD with the node ordering.
void BM_ElasticityFactorizeSolve(benchmark::State& state) {
    const mesh::Mesh m = beam(false);
    const SparseMatrix K =
        fem::stiffness_matrix(m, material::uniform(m, material::isotropic(3, 1e5, 0.3, 1.0)));
    const fem::ReducedSystem sys = fem::reduce(K, Vector::Ones(m.num_dofs()), clamp(m));
    solve::SolverOptions options;
    options.node_dofs = 3;
    solve::FactorStats stats;
    for (auto _ : state) {
        solve::SpdSolver solver(options);
        solver.compute(sys.K);
        benchmark::DoNotOptimize(solver.solve(sys.rhs).data());
        stats = solver.factor_stats();
    }
    state.counters["dofs"] = sys.K.rows();
    state.counters["nnz_L"] = stats.nonzeros;
    state.counters["gflop"] = 1e-9 * stats.flops;
    state.SetLabel(stats.ordering);
}

}  // namespace

BENCHMARK_CAPTURE(BM_RsWarpConstruct, Grid, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RsWarpConstruct, Distorted, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_RsWarpApply, Grid, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RsWarpApply, Distorted, true)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ElasticityFactorizeSolve)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    // The real times of this run, to print the ratios to the elasticity solve.
    const std::map<std::string, double> times = coarsegrain::bench::run_and_collect_times();
    const auto time = [&](const std::string& prefix) {
        for (const auto& entry : times)
            if (entry.first.rfind(prefix, 0) == 0) return entry.second;
        return 0.0;
    };
    const double elasticity = time("BM_ElasticityFactorizeSolve");
    if (elasticity > 0) {
        for (const char* name : {"BM_RsWarpConstruct/Grid", "BM_RsWarpConstruct/Distorted",
                                 "BM_RsWarpApply/Grid", "BM_RsWarpApply/Distorted"}) {
            const double t = time(name);
            if (t > 0)
                std::printf("%-30s %8.1f ms = %.3f x elasticity factorize + solve (%.0f ms)\n",
                            name, t, t / elasticity, elasticity);
        }
    }
    benchmark::Shutdown();
    return 0;
}
