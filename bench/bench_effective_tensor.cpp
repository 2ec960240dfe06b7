// Effective-tensor coarsening (Kharevych et al. 2009) of a ~200K-tet two-material object: a
// 32^3 Tet4 grid of the unit cube (196,608 tets, 107,811 DOFs) with eight stiff balls (E = 1e4)
// in a soft matrix (E = 1e2), clamped at x = 0 under gravity, coarsened to 600 coarse tets
// (5 x 5 x 4 cells). Prints the build phases (harmonic solves, intersections, tensor assembly)
// with a finer breakdown of the harmonic and tensor phases, and the fine CHOLMOD factorize +
// solve time against the coarse one for the same static scene (best of several runs each).
// Beside wall-clock seconds it prints the process CPU seconds (all threads) of the build and of
// its dominant phase: on a shared, loaded machine the wall time grows with the load while the
// CPU time does not, and CHOLMOD runs its BLAS on one thread (solve::SpdSolver), so on an idle
// machine the wall time of that phase is about its CPU time.
// A plain main (not Google Benchmark): each figure is one end-to-end measurement.
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/homogenize/harmonic.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace cg = coarsegrain;
using nlohmann::json;

namespace {

double seconds_of(const std::function<void()>& f) {
    const auto start = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// User + system CPU seconds of the process so far (all threads).
double cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Wall seconds of f; its CPU seconds in *cpu.
double seconds_of(const std::function<void()>& f, double* cpu) {
    const double start = cpu_seconds();
    const double wall = seconds_of(f);
    *cpu = cpu_seconds() - start;
    return wall;
}

/// Best wall time of `runs` calls.
double best_of(int runs, const std::function<void()>& f) {
    double best = 1e300;
    for (int i = 0; i < runs; ++i) best = std::min(best, seconds_of(f));
    return best;
}

json scene_json() {
    json centres = json::array();
    for (double x : {0.25, 0.75})
        for (double y : {0.25, 0.75})
            for (double z : {0.25, 0.75}) centres.push_back({x, y, z});
    return {
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {32, 32, 32}}, {"element", "tet"}}}}},
        {"material_field",
         {{"spheres", {{"centres", centres}, {"radius", 0.18}, {"inside", 2}, {"outside", 1}}}}},
        {"materials",
         {{"1", {{"E", 1e2}, {"nu", 0.45}, {"density", 1.0}}},
          {"2", {{"E", 1e4}, {"nu", 0.3}, {"density", 2.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 2, 2}}}}}}},
        {"loads", {{"gravity", {0, 0, -9.81}}}},
        {"coarse",
         {{"mesh",
           {{"grid",
             {{"min", {0, 0, 0}},
              {"max", {1, 1, 1}},
              {"cells", {5, 5, 4}},
              {"element", "tet"}}}}}}}};
}

/// Factorize + solve of K u = f with the Dirichlet DOFs eliminated (reduction included).
cg::Vector factorize_and_solve(const cg::SparseMatrix& K, const cg::Vector& f,
                               const cg::fem::Dirichlet& bc) {
    const cg::fem::ReducedSystem sys = cg::fem::reduce(K, f, bc);
    cg::solve::SpdSolver solver;
    solver.compute(sys.K);
    return cg::fem::expand(sys, solver.solve(sys.rhs), bc, static_cast<cg::Index>(K.rows()));
}

}  // namespace

int main() {
    const cg::scene::Scene sc = cg::scene::parse_scene(scene_json(), "bench", "");
    cg::scene::FineModel fine;
    const double t_fine_assemble = seconds_of([&] { fine = cg::scene::build_fine_model(sc); });
    std::printf("fine: %d tets, %d DOFs, assembled in %.2f s\n", fine.mesh.num_elements(),
                fine.mesh.num_dofs(), t_fine_assemble);

    cg::coarsen::CoarseModel model;
    double cpu_build = 0;
    const double t_build = seconds_of(
        [&] { model = cg::homogenize::build_coarse_model(sc, fine, "effective-tensor"); },
        &cpu_build);
    std::printf("coarse: %d tets, %d DOFs\n", model.elements, static_cast<int>(model.K.rows()));
    std::printf("effective-tensor build %.2f s wall, %.2f s CPU (%d OpenMP threads):\n", t_build,
                cpu_build, omp_get_max_threads());
    for (const auto& [phase, s] : model.timings.entries())
        std::printf("  %-10s %7.3f s\n", phase.c_str(), s);

    // Where the time goes inside the harmonic and tensor phases (same building blocks again).
    const cg::homogenize::Coarsening c = cg::homogenize::coarsening(sc, fine, "effective-tensor");
    cg::Matrix N, h, H;
    std::printf("breakdown:\n");
    std::printf("  coarse normals       %7.3f s\n", seconds_of([&] {
                    N = cg::homogenize::coarse_boundary_normals(c.fine, fine.boundary, c.coarse);
                }));
    double cpu_harmonic = 0;
    const double t_harmonic = seconds_of(
        [&] { h = cg::homogenize::harmonic_displacements(c.fine, fine.boundary, fine.K, N); },
        &cpu_harmonic);
    std::printf(
        "  harmonic solve (x6)  %7.3f s  (%.3f s CPU; one CHOLMOD factorization, 6 "
        "right-hand sides)\n",
        t_harmonic, cpu_harmonic);
    std::vector<cg::Mandel6> G;
    std::printf("  fine mollifiers      %7.3f s\n",
                seconds_of([&] { G = cg::homogenize::mollifiers(c.fine, h); }));
    std::printf("  sample at coarse     %7.3f s  (point locator built inside)\n", seconds_of([&] {
                    const cg::mesh::PointLocator loc(c.fine);
                    H = cg::homogenize::sample_harmonic(c.fine, loc, h, c.coarse.rest_positions);
                }));
    std::vector<cg::Mandel6> A;
    std::printf("  energy averages      %7.3f s\n", seconds_of([&] {
                    A = cg::homogenize::energy_averages(3, G, c.fine_materials, c.overlaps,
                                                        c.coarse_measures);
                }));
    std::printf("  intersections        %7.3f s  (%zu overlaps)\n",
                seconds_of([&] { cg::mesh::intersect(c.fine, c.coarse); }), c.overlaps.size());

    cg::Vector u_fine, u_coarse;
    double cpu_fine = 0;
    seconds_of([&] { u_fine = factorize_and_solve(fine.K, fine.f, fine.bc); }, &cpu_fine);
    const double t_fine =
        best_of(3, [&] { u_fine = factorize_and_solve(fine.K, fine.f, fine.bc); });
    const double t_coarse =
        best_of(50, [&] { u_coarse = factorize_and_solve(model.K, model.f, model.bc); });
    // The same coarse solve on one OpenMP thread: SpdSolver's parallel checks (symmetry, pattern
    // hash) cost more than the whole solve of a 540-DOF matrix when the cores are busy.
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const double t_coarse_1 =
        best_of(50, [&] { u_coarse = factorize_and_solve(model.K, model.f, model.bc); });
    omp_set_num_threads(threads);
    const cg::Vector u_mapped = model.to_fine * u_coarse;
    std::printf("static solve (reduce + CHOLMOD factorize + solve), best of runs:\n");
    std::printf(
        "  fine   %9.4f s  (%.3f s CPU, first run)\n  coarse %9.6f s  (%9.6f s on one OpenMP "
        "thread)\n",
        t_fine, cpu_fine, t_coarse, t_coarse_1);
    std::printf("  ratio  %9.0fx  (%.0fx)\n", t_fine / t_coarse, t_fine / t_coarse_1);
    std::printf("coarse vs fine: l2_rel %.4f, compliance ratio %.4f\n",
                (u_mapped - u_fine).norm() / u_fine.norm(),
                fine.f.dot(u_mapped) / fine.f.dot(u_fine));
    return 0;
}
