// Build cost of the material-adapted hierarchy on 3D hex grids (Chen et al. 2019, Table 1):
// build time phase by phase, storage, peak memory, and the coarsest factorize + solve against the
// fine CHOLMOD factorize + solve of the same problem, measured in one run.
//
//   bench_mra NX NY NZ [levels=2] [radius=5|inf|r1,r2,..] [truncation=1e-7]
//             [radius_grid=fine|coarse] [refinement=linear|dirac] [patch=1|Nc (N clipped)]
//             [scene=checker|FILE] [invariance=1|0] [localization=node|cell]
//             [relaxation=0] [fine_timing=1|0] [wavelet_stiffness=1|0]
//
// scene "checker": the grid spans [0, NX/NY] x [0, 1] x [0, NZ/NY] (cubic cells), hung from its
// face y = 1 under gravity and a traction on y = 0, with the checker inclusions of the hierarchy
// tests (contrast 1000). Otherwise a scene file (e.g. examples/accordion/accordion.json) whose
// grid is given NX x NY x NZ cells. Times are wall seconds on a shared 2-core machine. The
// build's peak is the process high-water mark from the start of the build (the fine problem's
// memory included, its reference solves not). The fine factorize + solve (Dirichlet DOFs
// eliminated, as a fine FEM solves) runs before the build, so that its factor is freed first;
// factorize and solve times are medians of up to 5 runs (as many as fit in 2 s). fine_timing 0
// skips that timing (at 64^3 hexes it takes as long as the reference solve: about 15 minutes).
// wavelet_stiffness 0 builds without keeping B^k (Options::store_wavelet_stiffness), which the
// coarse model and the coarsest solve do not read.
// Phases longer than a second are reported on stderr as they end, with the process's peak
// resident memory so far (the phase where it grows is where the memory went).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "mra/mra_test_util.hpp"

namespace cg = coarsegrain;

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Seconds of factorize and solve of A x = b by a new SpdSolver (analysis included; A its lower
/// triangle if `lower`): the median of 5 runs, or of as many as fit in 2 s after the first (at
/// least one).
std::pair<double, double> factorize_and_solve(const cg::SparseMatrix& A, const cg::Vector& b,
                                              bool lower) {
    std::vector<double> factorize, solve;
    const auto start = std::chrono::steady_clock::now();
    while (factorize.size() < 5 && (factorize.empty() || since(start) < 2.0)) {
        auto t0 = std::chrono::steady_clock::now();
        cg::solve::SolverOptions options;
        options.lower_triangle = lower;
        cg::solve::SpdSolver s(options);
        s.compute(A);
        factorize.push_back(since(t0));
        t0 = std::chrono::steady_clock::now();
        const cg::Vector x = s.solve(b);
        solve.push_back(since(t0));
        if (!x.allFinite()) std::printf("warning: non-finite solution\n");
    }
    const auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    return {median(factorize), median(solve)};
}

/// Starts a new high-water mark for cg::peak_resident_mb (Linux: 5 > /proc/self/clear_refs).
void reset_peak() { std::ofstream("/proc/self/clear_refs") << "5"; }

/// The fine problem: the checker bench problem or a scene file with the given grid cells.
cg::test::GridProblem make_problem(const Eigen::Vector3i& cells, const std::string& scene) {
    if (scene == "checker")
        return cg::test::hung_problem(3, cells, 1.0, 1e3, cg::test::checker_pattern,
                                      cells.cast<double>() / cells[1]);
    std::ifstream in(scene);
    if (!in) throw std::runtime_error("bench_mra: cannot read scene file " + scene);
    nlohmann::json j = nlohmann::json::parse(in);
    j["mesh"]["grid"]["cells"] = {cells[0], cells[1], cells[2]};
    const cg::scene::Scene sc = cg::scene::parse_scene(j, scene, ".");
    cg::scene::FineModel fine = cg::scene::build_fine_model(sc);
    cg::test::GridProblem p;
    p.u = cg::scene::solve_static(fine, {}).u;
    p.mesh = std::move(fine.mesh);
    p.materials = std::move(fine.materials);
    p.K = std::move(fine.K);
    p.f = std::move(fine.f);
    p.bc = std::move(fine.bc);
    return p;
}

int run(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(
            stderr,
            "usage: bench_mra NX NY NZ [levels=2] [radius=5|inf|r1,r2,..] [truncation=1e-7] "
            "[radius_grid=fine|coarse] [refinement=linear|dirac] [patch=1|Nc (N clipped)] "
            "[scene=checker|FILE] [invariance=1|0] [localization=node|cell] [relaxation=0] "
            "[fine_timing=1|0] [wavelet_stiffness=1|0]\n");
        return 2;
    }
    const Eigen::Vector3i cells(std::atoi(argv[1]), std::atoi(argv[2]), std::atoi(argv[3]));
    cg::mra::Options o;
    o.levels = argc > 4 ? std::atoi(argv[4]) : 2;
    // Radius per step, comma-separated (entry k-1 builds level k), or one for every step.
    const std::string radius = argc > 5 ? argv[5] : "5";
    o.radius.clear();
    for (std::size_t a = 0; a <= radius.size();) {
        const std::size_t b = std::min(radius.find(',', a), radius.size());
        const std::string r = radius.substr(a, b - a);
        o.radius.push_back(r == "inf" ? std::numeric_limits<double>::infinity() : std::stod(r));
        a = b + 1;
    }
    o.truncation = argc > 6 ? std::atof(argv[6]) : 1e-7;
    o.radius_grid = argc > 7 && std::string(argv[7]) == "coarse" ? cg::mra::RadiusGrid::Coarse
                                                                 : cg::mra::RadiusGrid::Fine;
    o.refinement = argc > 8 && std::string(argv[8]) == "dirac" ? cg::mra::Refinement::Dirac
                                                               : cg::mra::Refinement::Linear;
    const std::string patch = argc > 9 ? argv[9] : "1";
    o.patch = std::atoi(patch.c_str());
    o.patch_clip = patch.back() == 'c';
    const std::string scene = argc > 10 ? argv[10] : "checker";
    o.invariance = argc > 11 ? std::atoi(argv[11]) != 0 : true;
    o.localization = argc > 12 && std::string(argv[12]) == "cell" ? cg::mra::Localization::Cell
                                                                  : cg::mra::Localization::Node;
    o.relaxation = argc > 13 ? std::atof(argv[13]) : 0.0;
    const bool fine_timing = argc > 14 ? std::atoi(argv[14]) != 0 : true;
    o.store_wavelet_stiffness = argc > 15 ? std::atoi(argv[15]) != 0 : true;
    auto t0 = std::chrono::steady_clock::now();
    const cg::test::GridProblem p = make_problem(cells, scene);
    std::printf("%s grid %dx%dx%d: %ld nodes, %ld DOFs; problem set up in %.2f s, peak %.0f MB\n",
                scene.c_str(), cells[0], cells[1], cells[2], static_cast<long>(p.mesh.num_nodes()),
                static_cast<long>(p.mesh.num_dofs()), since(t0), cg::peak_resident_mb());
    std::printf(
        "levels %d, %s refinement, radius %s (%s rings), patch %d%s, truncation %g, invariance "
        "%d, localization %s, relaxation %g\n",
        o.levels, cg::mra::refinement_name(o.refinement).c_str(), radius.c_str(),
        cg::mra::radius_grid_name(o.radius_grid).c_str(), o.patch, o.patch_clip ? " clipped" : "",
        o.truncation, static_cast<int>(o.invariance),
        cg::mra::localization_name(o.localization).c_str(), o.relaxation);
    std::fflush(stdout);
    // The fine reference first, its factor freed before the build: at 64^3 it takes 19 GB.
    const auto [ff, fs] = [&] {
        if (!fine_timing) return std::pair(0.0, 0.0);
        const cg::fem::ReducedSystem fine = cg::fem::reduce(p.K, p.f, p.bc);
        return factorize_and_solve(fine.K, fine.rhs, false);
    }();
    if (fine_timing)
        std::printf("fine (Dirichlet DOFs eliminated) factorize %.4f s + solve %.5f s\n", ff, fs);
    std::fflush(stdout);
    reset_peak();
    t0 = std::chrono::steady_clock::now();
    const cg::mra::Hierarchy h = cg::mra::build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
    const double build = since(t0);
    // Table 1's storage: C̃^k, A^k, B^k (and Φ^k, Ψ^k when kept) and the canonical W^k, C^{k,†}.
    std::size_t bytes = 0, canonical = 0;
    for (int k = 1; k < h.num_levels(); ++k) {
        const cg::mra::Level& L = h.level(k);
        bytes += cg::mra::storage_bytes(L.C_adapted) + cg::mra::storage_bytes(L.A) +
                 cg::mra::storage_bytes(L.B) + cg::mra::storage_bytes(L.Phi) +
                 cg::mra::storage_bytes(L.Psi);
        canonical += cg::mra::storage_bytes(L.W) + cg::mra::storage_bytes(L.C_dagger);
        std::printf("level %d: %ld DOFs, nnz C %ld A (lower) %ld B (lower) %ld Phi %ld Psi %ld\n",
                    k, static_cast<long>(L.A.rows()), static_cast<long>(L.C_adapted.nonZeros()),
                    static_cast<long>(L.A.nonZeros()), static_cast<long>(L.B.nonZeros()),
                    static_cast<long>(L.Phi.nonZeros()), static_cast<long>(L.Psi.nonZeros()));
        // Table 1's columns: the fraction of zeros of B^k (if kept), C̃^k and A^k (whole
        // matrices).
        const auto zeros = [](double nonzeros, double rows, double cols) {
            return 100.0 * (1.0 - nonzeros / (rows * cols));
        };
        char b_sparsity[32] = "not kept";
        if (L.B.rows() > 0)
            std::snprintf(b_sparsity, sizeof b_sparsity, "%.2f%%",
                          zeros(cg::mra::symmetric_nonzeros(L.B), L.B.rows(), L.B.cols()));
        std::printf("level %d: sparsity (Table 1) B %s, C %.2f%%, A %.2f%%\n", k, b_sparsity,
                    zeros(L.C_adapted.nonZeros(), L.C_adapted.rows(), L.C_adapted.cols()),
                    zeros(cg::mra::symmetric_nonzeros(L.A), L.A.rows(), L.A.cols()));
    }
    std::printf(
        "build %.2f s, storage %.1f MB (adapted %.1f MB, W and C^+ %.1f MB), peak %.0f MB\n", build,
        static_cast<double>(bytes + canonical) / 1e6, static_cast<double>(bytes) / 1e6,
        static_cast<double>(canonical) / 1e6, cg::peak_resident_mb());
    for (const auto& [phase, s] : h.timings.entries())
        std::printf("  %-40s %8.3f s\n", phase.c_str(), s);
    std::fflush(stdout);

    const auto [cf, cs] = factorize_and_solve(h.level(1).A, cg::mra::coarse_grain(h, p.f, 1), true);
    std::printf("coarsest factorize %.5f s + solve %.6f s", cf, cs);
    if (fine_timing) std::printf("; fine over coarsest %.1fx", (ff + fs) / (cf + cs));
    std::printf("\n");
    cg::mra::MultilevelSolver solver(h);
    const cg::Vector e = solver.solve_level(p.f, 1) - p.u;
    std::printf("coarsest energy error ||u^1 - u||_A / ||u||_A = %.4f\n",
                cg::test::energy_norm(p.K, e) / cg::test::energy_norm(p.K, p.u));
    if (o.refinement == cg::mra::Refinement::Linear)
        std::printf("baseline: trilinear FEM on the coarsest grid, energy error %.4f\n",
                    cg::test::canonical_energy_error(h, p));
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    cg::retain_freed_memory();
    cg::set_progress_enabled(true);  // phases over a second on stderr, with the peak so far
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_mra: error: %s\n", e.what());
        return 1;
    }
}
