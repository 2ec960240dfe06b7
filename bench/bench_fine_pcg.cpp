// Exact fine static solves at a 1e-8 relative residual on N^3 hex cubes, CHOLMOD against the
// mra-pcg backend (conjugate gradients preconditioned by a V-cycle over the radius-1
// material-adapted hierarchy, mra/preconditioner.hpp), each configuration in its own process so
// that its peak resident memory is its own. The cube is clamped at z = 0 under gravity -z; the
// materials are a checkerboard of cubes of side 1/8 or a 4^3 lattice of stiff spheres (radius
// 0.09, 18% of the volume) in a soft matrix, at the stiffness contrasts given. Per run:
//   - cholmod: assembly, analysis + factorization, the solve; a second right-hand side (gravity
//     along x) with the factorization;
//   - mra-pcg: the hierarchy's build, the V-cycle's set-up (Galerkin copies, eigenvalue
//     estimates, the coarsest factorization), the deflation by the stiff clusters' rigid motions,
//     the PCG iterations, and the same second right-hand side with the preconditioner kept;
//   - amg: the baseline users would pick, hypre's BoomerAMG (Debian's libhypre-dev, one MPI
//     rank) as the preconditioner of hypre's PCG with the same stopping rule, set up for
//     elasticity as hypre's documentation and MFEM's elasticity options advise: nodal coarsening
//     of the 3x3 node blocks (row-sum norm), HMIS coarsening, extended+i interpolation with at
//     most 4 entries per row, the six rigid-body modes as interpolation vectors (GM variant 2,
//     Q_max 4, smoothed, one refinement), l1-Gauss-Seidel smoothing, strength threshold 0.5.
//     hypre rather than PETSc's GAMG or Trilinos' MueLu: BoomerAMG is the one Debian packages
//     without a large framework around it, and the one the elasticity literature compares with;
// each with the true relative residual ||f - K u|| / ||f|| of its answer. Prints a markdown
// table and writes it to docs/fine_pcg_bench.md.
//
//   OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 build/release/bench/bench_fine_pcg
//       [--sizes 32,48] [--contrasts 1e3,1e6] [--fields checker,spheres]
//       [--backends cholmod,mra-pcg,amg] [--levels Q] [--radius R] [--degree D]
//       [--deflation-rings N|off] [--max-iterations N] [--out FILE]
// (--levels, --radius, --degree, --deflation-rings: mra-pcg's solver.levels, solver.radius,
// solver.smoother_degree and solver.deflation_rings, "off" for solver.deflation false; default
// the scene's defaults: automatic levels, radius 1, degree 3, deflation over 2 rings.
// --max-iterations: both iterative solvers' limit, default 1000; a BoomerAMG solve stopped by it
// shows "(limit)" beside its iterations, and its residual is then above 1e-8; mra-pcg refuses.)
#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <fmt/format.h>
#include <mpi.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/preconditioner.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/deflation.hpp"

using namespace coarsegrain;

// Exported by libHYPRE, declared only in its internal header _hypre_parcsr_ls.h.
extern "C" {
HYPRE_Int HYPRE_BoomerAMGSetSmoothInterpVectors(HYPRE_Solver solver, HYPRE_Int smooth);
HYPRE_Int HYPRE_BoomerAMGSetInterpRefine(HYPRE_Solver solver, HYPRE_Int refine);
}

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

double peak_rss_gb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB
}

nlohmann::json cube_scene(int n, const std::string& field, double contrast) {
    nlohmann::json j = {
        {"dimension", 3},
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {n, n, n}}, {"element", "hex"}}}}},
        {"materials",
         {{"1", {{"E", contrast}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", 1.0}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, -1, -1e-9}}, {"max", {2, 2, 1e-9}}}}}}},
        {"loads", {{"gravity", {0, 0, -1}}}}};
    if (field == "checker") {
        j["material_field"] = {{"checkerboard", {{"size", 0.125}, {"ids", {1, 2}}}}};
    } else {
        nlohmann::json centres = nlohmann::json::array();
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 4; ++k)
                for (int l = 0; l < 4; ++l)
                    centres.push_back({0.125 + 0.25 * i, 0.125 + 0.25 * k, 0.125 + 0.25 * l});
        j["material_field"] = {
            {"spheres", {{"centres", centres}, {"radius", 0.09}, {"inside", 1}, {"outside", 2}}}};
    }
    return j;
}

/// An IJ vector of hypre's (one rank) with the values of v.
class HypreVector {
  public:
    explicit HypreVector(const Vector& v) {
        const auto n = static_cast<HYPRE_BigInt>(v.size());
        HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, n - 1, &m_ij);
        HYPRE_IJVectorSetObjectType(m_ij, HYPRE_PARCSR);
        HYPRE_IJVectorInitialize(m_ij);
        std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(n));
        for (HYPRE_BigInt i = 0; i < n; ++i) rows[static_cast<std::size_t>(i)] = i;
        HYPRE_IJVectorSetValues(m_ij, static_cast<HYPRE_Int>(n), rows.data(), v.data());
        HYPRE_IJVectorAssemble(m_ij);
        HYPRE_IJVectorGetObject(m_ij, reinterpret_cast<void**>(&m_par));
    }
    ~HypreVector() { HYPRE_IJVectorDestroy(m_ij); }
    HypreVector(const HypreVector&) = delete;
    HypreVector& operator=(const HypreVector&) = delete;
    HYPRE_ParVector par() const { return m_par; }
    Vector values(Index n) const {
        Vector v(n);
        std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(n));
        for (Index i = 0; i < n; ++i) rows[static_cast<std::size_t>(i)] = i;
        HYPRE_IJVectorGetValues(m_ij, static_cast<HYPRE_Int>(n), rows.data(), v.data());
        return v;
    }

  private:
    HYPRE_IJVector m_ij{};
    HYPRE_ParVector m_par{};
};

/// hypre's PCG preconditioned by BoomerAMG set up for elasticity (see the file comment) on the
/// free DOFs of `model` (K_ff, interleaved per node; every fixed node has all its DOFs fixed),
/// stopping at 1e-8 or after max_iterations.
class HypreAmg {
  public:
    HypreAmg(const SparseMatrix& K, const scene::FineModel& model, const IndexVector& free,
             int max_iterations) {
        const auto n = static_cast<HYPRE_BigInt>(K.rows());
        HYPRE_IJMatrixCreate(MPI_COMM_WORLD, 0, n - 1, 0, n - 1, &m_ij);
        HYPRE_IJMatrixSetObjectType(m_ij, HYPRE_PARCSR);
        std::vector<HYPRE_Int> sizes(static_cast<std::size_t>(n));
        for (HYPRE_BigInt j = 0; j < n; ++j)
            sizes[static_cast<std::size_t>(j)] = K.outerIndexPtr()[j + 1] - K.outerIndexPtr()[j];
        HYPRE_IJMatrixSetRowSizes(m_ij, sizes.data());
        HYPRE_IJMatrixInitialize(m_ij);
        std::vector<HYPRE_BigInt> cols;
        for (HYPRE_BigInt j = 0; j < n; ++j) {  // K symmetric: column j is row j
            HYPRE_Int count = sizes[static_cast<std::size_t>(j)];
            const int start = K.outerIndexPtr()[j];
            cols.assign(K.innerIndexPtr() + start, K.innerIndexPtr() + start + count);
            HYPRE_IJMatrixSetValues(m_ij, 1, &count, &j, cols.data(), K.valuePtr() + start);
        }
        HYPRE_IJMatrixAssemble(m_ij);
        HYPRE_IJMatrixGetObject(m_ij, reinterpret_cast<void**>(&m_par));
        // Rigid-body modes on the free DOFs: three translations, three rotations about the
        // cube's centre.
        for (int m = 0; m < 6; ++m) {
            Vector v = Vector::Zero(K.rows());
            for (Index i = 0; i < v.size(); ++i) {
                const Index node = free[i] / 3;
                const int d = static_cast<int>(free[i] % 3);
                const Eigen::Vector3d x =
                    model.mesh.rest_positions.row(node).transpose().array() - 0.5;
                if (m < 3) {
                    v[i] = d == m ? 1.0 : 0.0;
                } else {
                    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
                    axis[m - 3] = 1;
                    v[i] = axis.cross(x)[d];
                }
            }
            m_modes.push_back(std::make_unique<HypreVector>(v));
            m_mode_pointers.push_back(m_modes.back()->par());
        }
        HYPRE_BoomerAMGCreate(&m_amg);
        HYPRE_BoomerAMGSetNumFunctions(m_amg, 3);
        HYPRE_BoomerAMGSetNodal(m_amg, 4);
        HYPRE_BoomerAMGSetCoarsenType(m_amg, 10);
        HYPRE_BoomerAMGSetInterpType(m_amg, 6);
        HYPRE_BoomerAMGSetPMaxElmts(m_amg, 4);
        HYPRE_BoomerAMGSetStrongThreshold(m_amg, 0.5);
        HYPRE_BoomerAMGSetRelaxType(m_amg, 8);
        HYPRE_BoomerAMGSetInterpVecVariant(m_amg, 2);
        HYPRE_BoomerAMGSetInterpVecQMax(m_amg, 4);
        HYPRE_BoomerAMGSetSmoothInterpVectors(m_amg, 1);
        HYPRE_BoomerAMGSetInterpRefine(m_amg, 1);
        HYPRE_BoomerAMGSetInterpVectors(m_amg, 6, m_mode_pointers.data());
        HYPRE_BoomerAMGSetTol(m_amg, 0.0);
        HYPRE_BoomerAMGSetMaxIter(m_amg, 1);
        HYPRE_BoomerAMGSetPrintLevel(m_amg, 0);
        HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &m_pcg);
        HYPRE_ParCSRPCGSetTol(m_pcg, 1e-8);
        HYPRE_ParCSRPCGSetMaxIter(m_pcg, max_iterations);
        HYPRE_ParCSRPCGSetTwoNorm(m_pcg, 1);
        HYPRE_ParCSRPCGSetLogging(m_pcg, 1);
        HYPRE_ParCSRPCGSetPrecond(m_pcg, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, m_amg);
    }
    ~HypreAmg() {
        HYPRE_ParCSRPCGDestroy(m_pcg);
        HYPRE_BoomerAMGDestroy(m_amg);
        HYPRE_IJMatrixDestroy(m_ij);
    }
    HypreAmg(const HypreAmg&) = delete;
    HypreAmg& operator=(const HypreAmg&) = delete;

    /// Solves K u = b (the first call also sets BoomerAMG up); iterations and the final relative
    /// residual of hypre's recurrence in `iterations` and `residual`.
    Vector solve(const Vector& b, int& iterations, double& residual) {
        const HypreVector rhs(b), x(Vector::Zero(b.size()));
        if (!m_setup) {
            HYPRE_ParCSRPCGSetup(m_pcg, m_par, rhs.par(), x.par());
            m_setup = true;
        }
        HYPRE_ParCSRPCGSolve(m_pcg, m_par, rhs.par(), x.par());
        HYPRE_Int its = 0;
        HYPRE_ParCSRPCGGetNumIterations(m_pcg, &its);
        HYPRE_ParCSRPCGGetFinalRelativeResidualNorm(m_pcg, &residual);
        iterations = its;
        return x.values(b.size());
    }

  private:
    HYPRE_IJMatrix m_ij{};
    HYPRE_ParCSRMatrix m_par{};
    std::vector<std::unique_ptr<HypreVector>> m_modes;
    std::vector<HYPRE_ParVector> m_mode_pointers;
    HYPRE_Solver m_amg{}, m_pcg{};
    bool m_setup = false;
};

/// One configuration in this process: a JSON line on stdout (with "error" if the solver refused
/// or failed, e.g. CHOLMOD out of memory).
int run_one(const std::string& backend, int n, const std::string& field, double contrast,
            const mra::PreconditionerOptions& mra_options, int max_iterations);

int run_one_caught(const std::string& backend, int n, const std::string& field, double contrast,
                   const mra::PreconditionerOptions& mra_options, int max_iterations) {
    try {
        return run_one(backend, n, field, contrast, mra_options, max_iterations);
    } catch (const std::exception& e) {
        const nlohmann::json out = {
            {"backend", backend}, {"error", e.what()}, {"peak_gb", peak_rss_gb()}};
        fmt::print("{}\n", out.dump());
        return 0;
    }
}

int run_one(const std::string& backend, int n, const std::string& field, double contrast,
            const mra::PreconditionerOptions& mra_options, int max_iterations) {
    const scene::Scene sc = scene::parse_scene(cube_scene(n, field, contrast), "cube", "");
    nlohmann::json out = {{"backend", backend}, {"n", n}, {"field", field}, {"contrast", contrast}};
    auto t0 = Clock::now();
    const scene::FineModel model = scene::build_fine_model(sc);
    out["assemble_s"] = seconds_since(t0);
    const fem::ReducedSystem sys = fem::reduce(model.K, model.f, model.bc);
    // The second load, gravity along x, on the free DOFs (the clamp holds them at zero, so
    // no K_fd u_d term and no second copy of K_ff).
    scene::Scene along_x = sc;
    along_x.gravity = Eigen::Vector3d::UnitX();
    const Vector f2 =
        scene::load_vector(along_x, model.mesh, model.materials, model.boundary, "mesh");
    Vector rhs2(sys.free_dofs.size());
    for (Index i = 0; i < rhs2.size(); ++i) rhs2[i] = f2[sys.free_dofs[i]];
    out["dofs"] = sys.K.rows();
    const auto residual = [&](const Vector& u, const Vector& f) {
        Vector r;
        solve::symmetric_multiply(sys.K, u, r);
        return (f - r).norm() / f.norm();
    };
    if (backend == "cholmod") {
        solve::SolverOptions o;
        o.node_dofs = 3;
        solve::SpdSolver s(o);
        t0 = Clock::now();
        s.compute(sys.K);
        out["setup_s"] = seconds_since(t0);
        t0 = Clock::now();
        const Vector u = s.solve(sys.rhs);
        out["solve_s"] = seconds_since(t0);
        t0 = Clock::now();
        const Vector u2 = s.solve(rhs2);
        out["solve2_s"] = seconds_since(t0);
        out["residual"] = residual(u, sys.rhs);
        out["nnz_L"] = s.factor_stats().nonzeros;
    } else if (backend == "amg") {
        t0 = Clock::now();
        HypreAmg amg(sys.K, model, sys.free_dofs, max_iterations);
        int iterations = 0;
        double recurrence = 0;
        // BoomerAMG sets up in the first solve: timed apart with a zero right-hand side.
        amg.solve(Vector::Zero(sys.rhs.size()), iterations, recurrence);
        out["setup_s"] = seconds_since(t0);
        t0 = Clock::now();
        const Vector u = amg.solve(sys.rhs, iterations, recurrence);
        out["solve_s"] = seconds_since(t0);
        out["iterations"] = iterations;
        t0 = Clock::now();
        amg.solve(rhs2, iterations, recurrence);
        out["solve2_s"] = seconds_since(t0);
        out["iterations2"] = iterations;
        out["residual"] = residual(u, sys.rhs);
    } else {
        t0 = Clock::now();
        const auto factory =
            mra::hierarchy_preconditioner(model.mesh, model.materials, model.bc.dofs, mra_options);
        const std::unique_ptr<solve::Preconditioner> M = factory(sys.K);
        out["setup_s"] = seconds_since(t0);
        const mra::MultigridPreconditioner& cycle = mra::multigrid_cycle(*M);
        const auto* deflated = dynamic_cast<const solve::DeflatedPreconditioner*>(M.get());
        out["deflation_vectors"] = deflated ? deflated->vectors() : 0;
        double build = 0;
        for (const auto& [phase, seconds] : cycle.hierarchy().timings.entries()) build += seconds;
        out["build_s"] = build;
        out["levels"] = cycle.hierarchy().num_levels();
        out["coarsest_dofs"] = cycle.level_sizes().front().first;
        solve::PcgOptions pcg;
        pcg.tolerance = 1e-8;
        pcg.max_iterations = max_iterations;
        solve::PcgReport report;
        t0 = Clock::now();
        const Vector u = solve::pcg(sys.K, sys.rhs, *M, pcg, &report);
        out["solve_s"] = seconds_since(t0);
        out["iterations"] = report.iterations;
        t0 = Clock::now();
        const Vector u2 = solve::pcg(sys.K, rhs2, *M, pcg, &report);
        out["solve2_s"] = seconds_since(t0);
        out["iterations2"] = report.iterations;
        out["residual"] = residual(u, sys.rhs);
    }
    out["peak_gb"] = peak_rss_gb();
    fmt::print("{}\n", out.dump());
    return 0;
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> parts;
    std::stringstream in(s);
    for (std::string p; std::getline(in, p, ',');) parts.push_back(p);
    return parts;
}

/// mra-pcg's options from the --levels, --radius and --degree values.
/// @throws Error naming the option out of range (mra::validate)
mra::PreconditionerOptions mra_options_of(const std::string& levels, const std::string& radius,
                                          const std::string& degree, const std::string& rings) {
    mra::PreconditionerOptions o;
    o.levels = std::stoi(levels);
    o.radius = std::stod(radius);
    o.smoother_degree = std::stoi(degree);
    o.deflation = rings != "off";
    if (o.deflation) o.deflation_rings = std::stoi(rings);
    mra::validate(o);
    return o;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc == 11 && std::string(argv[1]) == "--one") {
        const mra::PreconditionerOptions mra_options =
            mra_options_of(argv[6], argv[7], argv[8], argv[9]);
        const int max_iterations = std::atoi(argv[10]);
        if (std::string(argv[2]) != "amg")
            return run_one_caught(argv[2], std::atoi(argv[3]), argv[4], std::atof(argv[5]),
                                  mra_options, max_iterations);
        MPI_Init(&argc, &argv);
        HYPRE_Init();
        const int code = run_one_caught(argv[2], std::atoi(argv[3]), argv[4], std::atof(argv[5]),
                                        mra_options, max_iterations);
        HYPRE_Finalize();
        MPI_Finalize();
        return code;
    }
    std::string sizes = "32,48", contrasts = "1e3,1e6", fields = "checker,spheres",
                backends = "cholmod,mra-pcg,amg", levels = "0", radius = "1", degree = "3",
                rings = "2", max_iterations = "1000",
                out = std::string(COARSEGRAIN_SOURCE_DIR) + "/docs/fine_pcg_bench.md";
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--sizes")
            sizes = value;
        else if (key == "--contrasts")
            contrasts = value;
        else if (key == "--fields")
            fields = value;
        else if (key == "--backends")
            backends = value;
        else if (key == "--levels")
            levels = value;
        else if (key == "--radius")
            radius = value;
        else if (key == "--degree")
            degree = value;
        else if (key == "--deflation-rings")
            rings = value;
        else if (key == "--max-iterations")
            max_iterations = value;
        else if (key == "--out")
            out = value;
        else {
            fmt::print(stderr, "unknown option {}\n", key);
            return 2;
        }
    }
    try {  // bad values fail here, before any run
        mra_options_of(levels, radius, degree, rings);
        if (std::stoi(max_iterations) < 1) {
            fmt::print(stderr, "--max-iterations {}: expected a positive count\n", max_iterations);
            return 2;
        }
    } catch (const std::logic_error&) {  // std::stoi, std::stod
        fmt::print(stderr,
                   "--levels {} --radius {} --degree {} --deflation-rings {} --max-iterations "
                   "{}: expected numbers (--deflation-rings: or off)\n",
                   levels, radius, degree, rings, max_iterations);
        return 2;
    } catch (const Error& e) {
        fmt::print(stderr, "{}\n", e.what());
        return 2;
    }
    const int limit = std::stoi(max_iterations);
    std::vector<std::string> rows = {
        "| cube | field | contrast | DOFs | backend | set-up s | solve s | total s | 2nd rhs s | "
        "iterations | residual | peak GB |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|"};
    for (const std::string& n : split(sizes))
        for (const std::string& field : split(fields))
            for (const std::string& contrast : split(contrasts))
                for (const std::string& backend : split(backends)) {
                    const std::string cmd =
                        fmt::format("{} --one {} {} {} {} {} {} {} {} {}", argv[0], backend, n,
                                    field, contrast, levels, radius, degree, rings, max_iterations);
                    std::FILE* pipe = popen(cmd.c_str(), "r");
                    std::string text;
                    char buffer[4096];
                    while (pipe && std::fgets(buffer, sizeof buffer, pipe)) text += buffer;
                    if (!pipe || pclose(pipe) != 0 || text.empty()) {
                        fmt::print(stderr, "{} failed\n", cmd);
                        continue;
                    }
                    const nlohmann::json r = nlohmann::json::parse(text);
                    if (r.contains("error")) {
                        rows.push_back(fmt::format(
                            "| {}^3 | {} | {} | - | {} | failed after {:.2f} GB peak: {} |||||||",
                            n, field, contrast, backend, r["peak_gb"].get<double>(),
                            r["error"].get<std::string>()));
                        fmt::print("{}\n", rows.back());
                        continue;
                    }
                    const bool pcg = backend != "cholmod";
                    const auto count = [&](const char* key) {
                        const int k = r[key].get<int>();
                        return k == limit ? fmt::format("{} (limit)", k) : std::to_string(k);
                    };
                    const std::string its =
                        pcg ? fmt::format("{} / {}", count("iterations"), count("iterations2"))
                            : "-";
                    const std::string setup =
                        backend == "mra-pcg"
                            ? fmt::format("{:.2f} (build {:.2f}, {} levels, coarsest {})",
                                          r["setup_s"].get<double>(), r["build_s"].get<double>(),
                                          r["levels"].get<int>(), r["coarsest_dofs"].get<long>())
                            : fmt::format("{:.2f}", r["setup_s"].get<double>());
                    rows.push_back(
                        fmt::format("| {}^3 | {} | {} | {} | {} | {} | {:.2f} | {:.2f} | {:.2f} | "
                                    "{} | {:.1e} | "
                                    "{:.2f} |",
                                    n, field, contrast, r["dofs"].get<long>(), backend, setup,
                                    r["solve_s"].get<double>(),
                                    r["setup_s"].get<double>() + r["solve_s"].get<double>(),
                                    r["solve2_s"].get<double>(), its, r["residual"].get<double>(),
                                    r["peak_gb"].get<double>()));
                    fmt::print("{}\n", rows.back());
                    std::fflush(stdout);
                }
    std::ofstream file(out);
    file << "# Exact fine solves: CHOLMOD, mra-pcg and BoomerAMG\n\n"
         << "N^3 hex cubes clamped at z = 0 under gravity, materials a checkerboard of cubes of "
            "side 1/8 or a 4^3 lattice of stiff spheres (radius 0.09) in a soft matrix, at the "
            "stiffness contrast given; every iterative solve to a 1e-8 relative residual. "
            "Set-up: CHOLMOD's analysis and factorization; mra-pcg's hierarchy build and "
            "V-cycle set-up; BoomerAMG's set-up. Solve: the gravity load; 2nd rhs: gravity "
            "along x with the factorization or preconditioner kept. Iterations: first / second "
            "right-hand side. Residual: ||f - K u|| / ||f|| of the first answer, computed apart. "
            "Peak GB: the process's peak resident memory (each configuration runs in its own "
            "process). Regenerate with\n\n"
            "    OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2 build/release/bench/bench_fine_pcg "
            "--sizes "
         << sizes << " --fields " << fields << " --contrasts " << contrasts << " --backends "
         << backends << " --levels " << levels << " --radius " << radius << " --degree " << degree
         << " --deflation-rings " << rings << " --max-iterations " << max_iterations << "\n\n";
    for (const std::string& row : rows) file << row << "\n";
    fmt::print(stderr, "wrote {}\n", out);
    return 0;
}
