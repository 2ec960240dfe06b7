// The cost of one frame (one implicit midpoint step) of corotated elastodynamics on the accordion
// example (64x16x16 hexes of stiff and soft layers, 56,355 DOFs, clamped at x = 0, hanging
// under the scene's gravity from rest), fine against coarse, measured in one run:
//   - the fine model corotated (sim::CorotatedStepper), each Newton iteration factorizing its
//     matrix (consistent tangent: UMFPACK LU; fixed frame: CHOLMOD), or solved by Krylov
//     iterations preconditioned by one factorization of the step matrix at rest
//     (corotation.linear_solve "rest_krylov") or by the latest factorization of the run
//     ("lagged_krylov"), with both tangents;
//   - the effective tensors' coarse model (the scene's 768-tet coarse mesh) corotated, the same
//     six ways;
//   - the hierarchy's coarsest level (method mra, the scene's coarse.levels) stepped linear
//     (sim::TimeStepper), carried to the fine mesh and RS-warped (fem::RsWarp, Chen et al.
//     2019, Sec. 4.3), split into its parts.
// The fine frames start after `warmup` steps, when the swing has started; every fine variant
// steps from the same states (the consistent rest-Krylov stepper's); the lagged ones also step
// from each warm-up state, untimed, so that they enter the frames with the factorization a run
// would have. The fine reference of the ratios is the faster of refactorizing and
// rest-preconditioned Krylov solves; the lagged fine variants are reported beside it. The
// effective tensors' steppers run their own trajectory to the same frames, `repeat` times
// from the start (each frame's time the least of its repeats). Prints a markdown table and
// writes it to docs/corotated_dynamics_bench.md.
//
//   OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 build/release/bench/bench_corotated_dynamics
//       [--warmup 20] [--frames 3] [--repeat 5] [--dt 0.01] [--gravity 1] [--no-hierarchy]
//       [--no-factorize] [--out FILE]
//
// The fine step has 56,355 DOFs; the effective tensors' coarse one 675, the hierarchy's 1275
// (dense). With the defaults the run took 41 min at 1 thread on a 2-core machine shared with
// another build, of which the hierarchy's build with global solves took 819 s (peak 10.8 GB),
// the fine factorizing frames 83 s each (both tangents) and the lagged fine variants' 20
// untimed warm-up steps about 4 min: --no-hierarchy and --no-factorize skip the first two.
// Every frame count and the step are options.
#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "coarsegrain/sim/dynamics.hpp"

using namespace coarsegrain;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// A table row to stdout and to the output file, flushed.
class Table {
  public:
    explicit Table(const std::string& path) : m_file(std::fopen(path.c_str(), "w")) {
        if (!m_file) fmt::print(stderr, "cannot write {}; printing only\n", path);
    }
    ~Table() {
        if (m_file) std::fclose(m_file);
    }
    Table(const Table&) = delete;
    Table& operator=(const Table&) = delete;

    template <class... Args>
    void line(fmt::format_string<Args...> f, Args&&... args) {
        const std::string s = fmt::format(f, std::forward<Args>(args)...) + "\n";
        std::fputs(s.c_str(), stdout);
        std::fflush(stdout);
        if (m_file) {
            std::fputs(s.c_str(), m_file);
            std::fflush(m_file);
        }
    }

  private:
    std::FILE* m_file;
};

/// One variant's frames.
struct Frames {
    double seconds = 0;  ///< wall time of all frames
    int frames = 0, newton = 0, krylov = 0, factorizations = 0;
    std::vector<int> newton_per_frame;

    void add(double s, const sim::NewtonReport& r) {
        seconds += s;
        ++frames;
        newton += r.iterations;
        krylov += r.krylov_iterations;
        factorizations += r.factorizations;
        newton_per_frame.push_back(r.iterations);
    }
    double per_frame() const { return seconds / frames; }
    std::string iterations() const {
        std::string s;
        for (const int n : newton_per_frame) s += (s.empty() ? "" : ", ") + std::to_string(n);
        return s;
    }
};

/// The largest rotation angle (radians) of an element frame at a state.
double max_frame_angle(const fem::CorotatedModel::State& state, int dim) {
    double worst = 0;
    const std::size_t block = static_cast<std::size_t>(dim * dim);
    for (std::size_t e = 0; e + block <= state.frames.size(); e += block) {
        double trace = 0;
        for (int i = 0; i < dim; ++i)
            trace += state.frames[e + static_cast<std::size_t>(i * dim + i)];
        const double c = dim == 3 ? (trace - 1) / 2 : trace / 2;
        worst = std::max(worst, std::acos(std::clamp(c, -1.0, 1.0)));
    }
    return worst;
}

/// Calls `frame` until it has taken `min_seconds` (at least once); returns seconds per call.
template <class F>
double repeated(F&& frame, double min_seconds = 0.2) {
    int calls = 0;
    const auto t0 = Clock::now();
    do {
        frame();
        ++calls;
    } while (seconds_since(t0) < min_seconds);
    return seconds_since(t0) / calls;
}

struct Args {
    int warmup = 20, frames = 3;
    int repeat = 5;  ///< runs of each coarse variant
    double dt = 0.01;
    double gravity = 1;  ///< factor on the scene's gravity
    bool hierarchy = true;
    bool factorize = true;  ///< the fine factorizing variants (the slow ones)
    std::string out = std::string(COARSEGRAIN_SOURCE_DIR) + "/docs/corotated_dynamics_bench.md";
};

Args parse_args(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string key = argv[i];
        const bool has_value = i + 1 < argc;
        if (key == "--warmup" && has_value)
            a.warmup = std::stoi(argv[++i]);
        else if (key == "--frames" && has_value)
            a.frames = std::stoi(argv[++i]);
        else if (key == "--repeat" && has_value)
            a.repeat = std::stoi(argv[++i]);
        else if (key == "--dt" && has_value)
            a.dt = std::stod(argv[++i]);
        else if (key == "--gravity" && has_value)
            a.gravity = std::stod(argv[++i]);
        else if (key == "--out" && has_value)
            a.out = argv[++i];
        else if (key == "--no-hierarchy")
            a.hierarchy = false;
        else if (key == "--no-factorize")
            a.factorize = false;
        else {
            fmt::print(
                stderr,
                "usage: bench_corotated_dynamics [--warmup N] [--frames N] [--repeat N] "
                "[--dt S] [--gravity FACTOR] [--no-hierarchy] [--no-factorize] [--out FILE]\n");
            std::exit(2);
        }
    }
    return a;
}

}  // namespace

int main(int argc, char** argv) {
    const Args args = parse_args(argc, argv);
    if (args.warmup < 0 || args.frames < 1 || args.repeat < 1 || !(args.dt > 0)) {
        fmt::print(stderr, "--warmup must be >= 0, --frames and --repeat >= 1 and --dt > 0\n");
        return 2;
    }
    std::ifstream in(std::string(COARSEGRAIN_SOURCE_DIR) + "/examples/accordion/accordion.json");
    nlohmann::json j = nlohmann::json::parse(in);
    for (auto& g : j["loads"]["gravity"]) g = args.gravity * g.get<double>();
    const scene::Scene sc = scene::parse_scene(
        j, "accordion", std::string(COARSEGRAIN_SOURCE_DIR) + "/examples/accordion");
    const auto t_fine = Clock::now();
    const scene::FineModel fine = scene::build_fine_model(sc);
    const int dim = fine.mesh.dim();
    sim::DynamicsOptions o;
    o.integrator = sim::Integrator::Midpoint;
    o.dt = args.dt;
    o.steps = args.warmup + args.frames;
    o.output_every = o.steps;
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, o.mass);
    const fem::CorotatedModel model(fine.mesh, fine.materials, sc.formulation, sc.corotation.frame);
    solve::SolverOptions node_options = sc.solver;
    node_options.node_dofs = dim;
    fmt::print(stderr, "fine model: {} DOFs, {:.1f} s\n", fine.mesh.num_dofs(),
               seconds_since(t_fine));

    // The fine variants: factorizing and Krylov, both tangents.
    struct Variant {
        sim::Tangent tangent;
        sim::LinearSolve solve;
        Frames frames;
        double setup = 0;
    };
    std::vector<Variant> variants = {
        {sim::Tangent::Consistent, sim::LinearSolve::Factorize, {}, 0},
        {sim::Tangent::FixedFrame, sim::LinearSolve::Factorize, {}, 0},
        {sim::Tangent::Consistent, sim::LinearSolve::RestKrylov, {}, 0},
        {sim::Tangent::FixedFrame, sim::LinearSolve::RestKrylov, {}, 0},
        {sim::Tangent::Consistent, sim::LinearSolve::LaggedKrylov, {}, 0},
        {sim::Tangent::FixedFrame, sim::LinearSolve::LaggedKrylov, {}, 0},
    };
    const auto lagged = [&](std::size_t i) {
        return variants[i].solve == sim::LinearSolve::LaggedKrylov;
    };
    std::vector<sim::CorotationOptions> options(variants.size(), sc.corotation);
    std::vector<sim::CorotatedStepper> steppers;
    for (std::size_t i = 0; i < variants.size(); ++i) {
        options[i].tangent = variants[i].tangent;
        options[i].linear_solve = variants[i].solve;
        const auto t0 = Clock::now();
        steppers.emplace_back(model, M, fine.bc, o, options[i], node_options);
        variants[i].setup = seconds_since(t0);
    }
    // Warm-up with the consistent rest-Krylov stepper (the lagged ones stepping beside it),
    // then every variant from the same states.
    const Index n = fine.mesh.num_dofs();
    sim::State s{Vector::Zero(n), Vector::Zero(n)};
    for (int k = 0; k < args.warmup; ++k) {
        for (std::size_t i = 0; i < variants.size(); ++i) {
            if (!lagged(i)) continue;
            sim::State t = s;
            const sim::NewtonReport r = steppers[i].step(t, fine.f);
            fmt::print(stderr, "warm-up step {} {} lagged: {} Newton, {} Krylov, {} factorized\n",
                       k + 1, sim::tangent_name(variants[i].tangent), r.iterations,
                       r.krylov_iterations, r.factorizations);
        }
        const auto t0 = Clock::now();
        const sim::NewtonReport r = steppers[2].step(s, fine.f);
        fmt::print(stderr, "warm-up step {}: {} Newton, {} Krylov iterations, {:.2f} s\n", k + 1,
                   r.iterations, r.krylov_iterations, seconds_since(t0));
    }
    std::vector<double> angles, tips;
    for (int k = 0; k < args.frames; ++k) {
        sim::State next;
        for (std::size_t i = 0; i < variants.size(); ++i) {
            if (!args.factorize && variants[i].solve == sim::LinearSolve::Factorize) continue;
            sim::State t = s;
            const auto t0 = Clock::now();
            const sim::NewtonReport r = steppers[i].step(t, fine.f);
            variants[i].frames.add(seconds_since(t0), r);
            fmt::print(stderr, "frame {} {} {}: {} Newton, {} Krylov, {:.2f} s\n",
                       args.warmup + k + 1, sim::tangent_name(variants[i].tangent),
                       sim::linear_solve_name(variants[i].solve), r.iterations, r.krylov_iterations,
                       seconds_since(t0));
            if (i == 2) next = std::move(t);
        }
        s = std::move(next);
        angles.push_back(max_frame_angle(model.evaluate(s.u), dim));
        double tip = 0;
        for (Index v = 0; v < fine.mesh.num_nodes(); ++v)
            tip = std::max(tip, s.u.segment(dim * v, dim).norm());
        tips.push_back(tip);
    }

    // The effective tensors' coarse model, corotated, on its own trajectory to the same frames.
    const auto t_coarse = Clock::now();
    const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, "effective-tensor");
    const SparseMatrix Mc = c.mass(M);
    const coarsen::ElementModel& e = *c.element_model;
    solve::SolverOptions coarse_options = sc.solver;
    coarse_options.node_dofs = e.dof_map.size() == 0 ? e.mesh.dim() : 1;
    const fem::CorotatedModel coarse_model(e.mesh, e.materials, fem::Formulation::Standard,
                                           sc.corotation.frame, e.dof_map);
    const double coarse_build = seconds_since(t_coarse);
    std::vector<Variant> coarse_variants = variants;
    for (Variant& v : coarse_variants) {
        sim::CorotationOptions co = sc.corotation;
        co.tangent = v.tangent;
        co.linear_solve = v.solve;
        std::vector<double> best(static_cast<std::size_t>(args.frames),
                                 std::numeric_limits<double>::infinity());
        std::vector<sim::NewtonReport> reports(best.size());
        for (int repeat = 0; repeat < args.repeat; ++repeat) {
            const auto t0 = Clock::now();
            sim::CorotatedStepper coarse(coarse_model, Mc, c.bc, o, co, coarse_options);
            v.setup = coarse_build + seconds_since(t0);
            sim::State sc0{Vector::Zero(c.K.rows()), Vector::Zero(c.K.rows())};
            for (int k = 0; k < args.warmup; ++k) coarse.step(sc0, c.f);
            for (std::size_t k = 0; k < best.size(); ++k) {
                const auto t1 = Clock::now();
                reports[k] = coarse.step(sc0, c.f);
                best[k] = std::min(best[k], seconds_since(t1));
            }
        }
        v.frames = {};
        for (std::size_t k = 0; k < best.size(); ++k) v.frames.add(best[k], reports[k]);
    }

    // The hierarchy's coarsest level, linear, carried to the fine mesh and warped.
    struct Split {
        double step = 0, carry = 0, rs = 0, solve = 0;
        double total() const { return step + carry + rs + solve; }
    } split;
    Index hierarchy_dofs = 0;
    double hierarchy_build = 0, warp_setup = 0;
    if (args.hierarchy) {
        const auto t0 = Clock::now();
        const coarsen::CoarseModel h = coarsen::build_coarse_model(sc, fine, "mra");
        const SparseMatrix Mh = h.mass(M);
        const sim::TimeStepper stepper(h.K, Mh, h.bc, o, sc.solver);
        hierarchy_build = seconds_since(t0);
        hierarchy_dofs = h.K.rows();
        const auto t1 = Clock::now();
        const fem::RsWarp warp(fine.mesh, fine.bc, sc.solver);
        warp_setup = seconds_since(t1);
        sim::State sh{Vector::Zero(h.K.rows()), Vector::Zero(h.K.rows())};
        for (int k = 0; k < args.warmup; ++k) stepper.step(sh, h.f);
        for (int k = 0; k < args.frames; ++k) {
            split.step += repeated([&] {
                sim::State trial = sh;
                stepper.step(trial, h.f);
            });
            stepper.step(sh, h.f);
            Vector u_fine;
            split.carry += repeated([&] { u_fine = h.to_fine * sh.u; });
            Timings t;
            int calls = 0;
            repeated([&] {
                ++calls;
                warp(u_fine, &t);
            });
            split.rs += t["rs"] / calls;
            split.solve += t["solve"] / calls;
        }
        split.step /= args.frames;
        split.carry /= args.frames;
        split.rs /= args.frames;
        split.solve /= args.frames;
    }

    // The table.
    Table table(args.out);
    table.line("<!-- regenerated by build/release/bench/bench_corotated_dynamics -->");
    table.line(
        "Accordion 64x16x16 hexes ({} DOFs), implicit midpoint, dt = {:g}, from rest under "
        "{} times the scene's gravity; frames {} to {} (largest element rotation {:.3f} to {:.3f} "
        "rad, largest "
        "displacement {:.3f} to {:.3f}); {} thread(s). Fine frames step from the same "
        "states.",
        n, args.dt, args.gravity, args.warmup + 1, args.warmup + args.frames, angles.front(),
        angles.back(), tips.front(), tips.back(), omp_get_max_threads());
    table.line("");
    table.line(
        "| model | DOFs | tangent | linear solve | setup s | s / frame | Newton iterations "
        "per frame | Krylov iterations per Newton iteration | factorizations per frame | "
        "fine reference / this |");
    table.line("|---|---|---|---|---|---|---|---|---|---|");
    // The reference: refactorizing or rest-preconditioned; `fastest` also counts the lagged.
    double reference = std::numeric_limits<double>::infinity(), fastest = reference;
    for (const Variant& v : variants) {
        if (v.frames.frames == 0) continue;
        fastest = std::min(fastest, v.frames.per_frame());
        if (v.solve != sim::LinearSolve::LaggedKrylov)
            reference = std::min(reference, v.frames.per_frame());
    }
    const auto row = [&](const char* name, Index dofs, const Variant& v) {
        const Frames& f = v.frames;
        table.line("| {} | {} | {} | {} | {:.2f} | {:.3g} | {} | {} | {:.1f} | {:.1f} |", name,
                   dofs, sim::tangent_name(v.tangent), sim::linear_solve_name(v.solve), v.setup,
                   f.per_frame(), f.iterations(),
                   v.solve == sim::LinearSolve::Factorize
                       ? std::string("-")
                       : fmt::format("{:.1f}", static_cast<double>(f.krylov) / f.newton),
                   static_cast<double>(f.factorizations) / f.frames, reference / f.per_frame());
    };
    for (const Variant& v : variants)
        if (v.frames.frames > 0) row("fine corotated", n, v);
    for (const Variant& v : coarse_variants) row("effective tensors corotated", c.K.rows(), v);
    if (args.hierarchy) {
        table.line(
            "| hierarchy linear + RS warp | {} | - | factorize once | {:.1f} + {:.2f} | "
            "{:.2e} | - | - | 0 | {:.0f} |",
            hierarchy_dofs, hierarchy_build, warp_setup, split.total(), reference / split.total());
        table.line("| - coarse step | | | | | {:.2e} | | | | {:.0f} |", split.step,
                   reference / split.step);
        table.line("| - carry to the fine mesh | | | | | {:.2e} | | | | |", split.carry);
        table.line("| - RS transforms | | | | | {:.2e} | | | | |", split.rs);
        table.line("| - back-substitution | | | | | {:.2e} | | | | {:.0f} |", split.solve,
                   reference / split.solve);
    }
    table.line("");
    double coarse_best = std::numeric_limits<double>::infinity();
    for (const Variant& v : coarse_variants)
        coarse_best = std::min(coarse_best, v.frames.per_frame());
    double refactorize = std::numeric_limits<double>::infinity();
    for (const Variant& v : variants)
        if (v.frames.frames > 0 && v.solve == sim::LinearSolve::Factorize)
            refactorize = std::min(refactorize, v.frames.per_frame());
    table.line(
        "Effective tensors, fastest coarse variant: {:.3g} s per frame, {:.0f} times faster "
        "than the fine reference, {:.0f} times than the fastest fine variant{}.",
        coarse_best, reference / coarse_best, fastest / coarse_best,
        std::isfinite(refactorize)
            ? fmt::format(" ({:.0f} times than the fastest refactorizing fine variant)",
                          refactorize / coarse_best)
            : std::string());
    if (args.hierarchy)
        table.line(
            "Hierarchy + RS warp: {:.3g} s per frame, {:.0f} times faster than the fine "
            "reference; the carry to the fine mesh takes {:.0f}% of it, the warp's "
            "back-substitution {:.0f}%, the RS transforms {:.0f}%, the coarse step {:.0f}%.",
            split.total(), reference / split.total(), 100 * split.carry / split.total(),
            100 * split.solve / split.total(), 100 * split.rs / split.total(),
            100 * split.step / split.total());
    table.line("");
    table.line(
        "Fine reference: the fastest fine variant that refactorizes or preconditions by the "
        "rest state, {:.3f} s per frame; the fastest of all, {:.3f} s. Setup: the "
        "factorization of the step matrix at rest (rest_krylov), the coarse model's build "
        "and stepper; the hierarchy's build and the warp's factorization. The lagged "
        "variants' factorizations count in the frames where they happen (the fine ones' "
        "first, in the untimed warm-up).",
        reference, fastest);
    return 0;
}
