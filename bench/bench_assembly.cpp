/// Assembly throughput: stiffness and mass on regular grids (cached element matrices, node
/// gather) and on distorted meshes (element matrices computed per element, coloured scatter).
/// Run: ./build/bench/bench_assembly --benchmark_filter=Hex
#include <benchmark/benchmark.h>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;

namespace {

/// n^dim grid with two materials in layers (ids 0 and 1).
mesh::Mesh two_material_grid(mesh::ElementType type, int n) {
    const int dim = mesh::element_dim(type);
    mesh::Mesh m = mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                                   Eigen::VectorXi::Constant(dim, n));
    material::layers(m, 0, 0.0, 0.25, {0, 1});
    return m;
}

material::ElementMaterials two_materials(const mesh::Mesh& m) {
    const int dim = m.dim();
    return material::assign(m, {{0, material::isotropic(dim, 1e5, 0.3, 1.0)},
                                {1, material::isotropic(dim, 1e2, 0.45, 1.0)}});
}

/// Moves every interior node by up to 20% of the spacing (deterministic), dropping GridInfo.
void distort(mesh::Mesh& m, int n) {
    const double h = 1.0 / n;
    for (Index v = 0; v < m.num_nodes(); ++v) {
        auto x = m.rest_positions.row(v);
        if ((x.array() > 1e-12).all() && (x.array() < 1 - 1e-12).all())
            for (int d = 0; d < m.dim(); ++d) x[d] += 0.2 * h * std::sin(12.9898 * v + 78.233 * d);
    }
    m.grid.reset();
}

void report(benchmark::State& state, const mesh::Mesh& m) {
    state.counters["elements/s"] = benchmark::Counter(
        static_cast<double>(m.num_elements()), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["dofs"] = m.num_dofs();
}

void BM_StiffnessGrid(benchmark::State& state, mesh::ElementType type) {
    const int n = static_cast<int>(state.range(0));
    const mesh::Mesh m = two_material_grid(type, n);
    const auto mats = two_materials(m);
    for (auto _ : state) benchmark::DoNotOptimize(fem::stiffness_matrix(m, mats));
    report(state, m);
}

void BM_StiffnessDistorted(benchmark::State& state, mesh::ElementType type) {
    const int n = static_cast<int>(state.range(0));
    mesh::Mesh m = two_material_grid(type, n);
    distort(m, n);
    const auto mats = two_materials(m);
    for (auto _ : state) benchmark::DoNotOptimize(fem::stiffness_matrix(m, mats));
    report(state, m);
}

void BM_MassGrid(benchmark::State& state, mesh::ElementType type) {
    const int n = static_cast<int>(state.range(0));
    const mesh::Mesh m = two_material_grid(type, n);
    const auto mats = two_materials(m);
    for (auto _ : state)
        benchmark::DoNotOptimize(fem::mass_matrix(m, mats, fem::MassType::Consistent));
    report(state, m);
}

}  // namespace

// The headline case: 64^3 hexes = 262,144 elements, 823,875 DOFs, two materials.
BENCHMARK_CAPTURE(BM_StiffnessGrid, Hex, mesh::ElementType::Hex8)
    ->Arg(32)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_StiffnessDistorted, Hex, mesh::ElementType::Hex8)
    ->Arg(32)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_StiffnessDistorted, Tet, mesh::ElementType::Tet4)
    ->Arg(32)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_MassGrid, Hex, mesh::ElementType::Hex8)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_StiffnessGrid, Quad, mesh::ElementType::Quad4)
    ->Arg(512)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
