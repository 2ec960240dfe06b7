// Time stepping and modal analysis, fine against coarse, measured in one run: prints the table of
// docs/performance.md ("Dynamics").
//
//   build/release/bench/bench_dynamics            # demo beam and the 56K-DOF accordion
//   build/release/bench/bench_dynamics --small    # the demo beam at scale 0.67 only (seconds)
//
// Per scene (the demo's layered beam at 48x12x12 hexes, 24,843 DOFs, and the accordion example's
// 64x16x16, 56,355 DOFs; effective tensors on the scene's coarse tet mesh, lumped coarse mass;
// implicit midpoint, dt = 1e-3, consistent fine mass): the factorization of the step operator,
// the wall time per step over `steps` steps (fine and coarse, one back-substitution each), their
// ratio, and the 10 lowest fine eigenpairs (shift-invert Lanczos on one CHOLMOD factorization).
#include <fmt/format.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"

using namespace coarsegrain;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void run(const std::string& name, const nlohmann::json& scene_json, int steps) {
    const scene::Scene sc = scene::parse_scene(scene_json, name, COARSEGRAIN_SOURCE_DIR);
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    sim::DynamicsOptions o;
    o.dt = 1e-3;
    o.steps = steps;
    o.output_every = steps;
    const auto [s0, f] = sim::initial_state(fine.K, fine.f, fine.bc, Vector(), o);
    const sim::Trajectory tf = sim::simulate(fine.K, M, fine.bc, s0, f, o);

    const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, "effective-tensor");
    const SparseMatrix Mc = c.mass(M);
    const auto [c0, fc] = sim::initial_state(c.K, c.f, c.bc, Vector(), o);
    const sim::Trajectory tc = sim::simulate(c.K, Mc, c.bc, c0, fc, o);

    const auto t0 = std::chrono::steady_clock::now();
    const sim::Modes modes = sim::modes(fine.K, M, fine.bc, 10);
    const double eig = seconds_since(t0);
    const double err = (c.to_fine * tc.u.back() - tf.u.back()).norm() / tf.u.back().norm();

    fmt::print("| {} | {} | {} | {:.3f} | {:.2e} | {:.4f} | {:.2e} | {:.0f}x | {:.2f} / {:.4f} s | "
               "{:.1f} s ({:.3g} .. {:.3g} Hz) | {:.3f} |\n",
               name, fine.K.rows(), c.K.rows(), tf.factorize_seconds, tf.per_step_seconds,
               tc.factorize_seconds, tc.per_step_seconds,
               tf.per_step_seconds / tc.per_step_seconds, steps * tf.per_step_seconds,
               steps * tc.per_step_seconds, eig, modes.frequencies_hz[0],
               modes.frequencies_hz[9], err);
}

}  // namespace

int main(int argc, char** argv) {
    const bool small = argc > 1 && std::strcmp(argv[1], "--small") == 0;
    fmt::print("| scene | fine DOFs | coarse DOFs | fine factorize s | fine s/step | "
               "coarse factorize s | coarse s/step | step speedup | {} steps fine / coarse | "
               "10 fine eigenpairs | u(T) l2 error |\n",
               small ? 100 : 1000);
    fmt::print("|---|---|---|---|---|---|---|---|---|---|---|\n");
    if (small) {
        run("demo beam 32x8x8", scene::demo_scene(0.67), 100);
        return 0;
    }
    run("demo beam 48x12x12", scene::demo_scene(1.0), 1000);
    std::ifstream in(std::string(COARSEGRAIN_SOURCE_DIR) + "/examples/accordion/accordion.json");
    run("accordion 64x16x16", nlohmann::json::parse(in), 1000);
    return 0;
}
