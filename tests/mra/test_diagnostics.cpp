// Per-level diagnostics of the hierarchy: eigenvalues against a dense solver, error, sparsity,
// storage, CSV round trip and the plotting script.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/diagnostics.hpp"
#include "mra_test_util.hpp"
#include "test_util.hpp"

namespace coarsegrain::mra {
namespace {

/// Horizontal layers, 8 over the height, alternating soft (0) and stiff (1).
int layered(const Eigen::VectorXd& x) { return static_cast<int>(std::floor(8 * x[1])) % 2; }

double dense_zero_fraction(const SparseMatrix& M) {
    const Matrix D(M);
    return static_cast<double>((D.array() == 0).count()) / static_cast<double>(D.size());
}

void expect_spectrum(const SparseMatrix& M, double lmin, double lmax, double cond,
                     const std::string& what) {
    const Eigen::SelfAdjointEigenSolver<Matrix> eig{Matrix(M)};
    const double dmin = eig.eigenvalues().minCoeff(), dmax = eig.eigenvalues().maxCoeff();
    // Lanczos converged to 1e-12 relative; the dense solver is backward stable (error
    // ~ n eps lambda_max on each eigenvalue, here with cond <= 1e7 at most ~1e-8 relative on
    // lambda_min for the worst level). 1e-8 relative.
    EXPECT_NEAR(lmax, dmax, 1e-8 * dmax) << what;
    EXPECT_NEAR(lmin, dmin, 1e-8 * dmin) << what;
    EXPECT_NEAR(cond, dmax / dmin, 1e-8 * dmax / dmin) << what;
}

TEST(MraDiagnostics, SpectraAgreesWithDenseEigenvalues) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(8, 8, 1), 1.0, 1e3, test::checker_pattern);
    for (const Refinement r : {Refinement::Linear, Refinement::Dirac}) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(3, r));
        const Diagnostics d = diagnose(h, p.f);
        ASSERT_EQ(d.levels.size(), 3u);
        for (const LevelDiagnostics& L : d.levels) {
            const std::string what = fmt::format("{} level {}", refinement_name(r), L.k);
            const bool fine = L.k == h.num_levels();
            expect_spectrum(fine ? h.A_fine : symmetric_from_lower(h.level(L.k).A), L.lambda_min_A,
                            L.lambda_max_A, L.cond_A, what + " A");
            if (!fine)
                expect_spectrum(symmetric_from_lower(h.level(L.k).B), L.lambda_min_B,
                                L.lambda_max_B, L.cond_B, what + " B");
        }
    }
}

TEST(MraDiagnostics, ErrorSparsityAndStorage) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(8, 8, 1), 1.0, 1e3, test::checker_pattern);
    Options o;
    o.levels = 3;
    o.radius = {1};
    o.truncation = 1e-3;
    o.store_bases = true;
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
    const Diagnostics d = diagnose(h, p.f);
    const LevelDiagnostics& fine = d.levels.back();
    // The finest single-level solve is the very fine solve: bitwise the same vector.
    EXPECT_EQ(fine.error_over_g, 0.0);
    EXPECT_EQ(fine.error_over_u, 0.0);
    EXPECT_TRUE(std::isnan(fine.cond_B));
    EXPECT_EQ(fine.bytes_Phi, 0u);
    EXPECT_DOUBLE_EQ(fine.sparsity_A, dense_zero_fraction(h.A_fine));
    for (int k = 1; k < h.num_levels(); ++k) {
        const Level& lev = h.level(k);
        const LevelDiagnostics& L = d.levels[static_cast<std::size_t>(k - 1)];
        // The coarse spaces are strict subspaces: a positive error.
        EXPECT_GT(L.error_over_g, 0.0);
        // Counts are integers divided by the same size: equal to round-off (1 - x of a
        // fraction x near 1 keeps ~1e-15 absolute).
        EXPECT_NEAR(L.sparsity_A, dense_zero_fraction(symmetric_from_lower(lev.A)), 1e-14);
        EXPECT_NEAR(L.sparsity_B, dense_zero_fraction(symmetric_from_lower(lev.B)), 1e-14);
        EXPECT_NEAR(L.sparsity_C, dense_zero_fraction(lev.C_adapted.sparse()), 1e-14);
        // Compressed column storage: a double and an int index per stored entry, cols+1
        // column pointers.
        const auto bytes = [](const SparseMatrix& M) {
            return static_cast<std::size_t>(M.nonZeros()) * 12 +
                   static_cast<std::size_t>(M.cols() + 1) * 4;
        };
        EXPECT_EQ(L.bytes_A, bytes(lev.A));
        EXPECT_EQ(L.bytes_B, bytes(lev.B));
        EXPECT_EQ(L.bytes_C, lev.C_adapted.bytes());  // kept by runs (test_run_matrix.cpp)
        EXPECT_EQ(L.bytes_Phi, bytes(lev.Phi));
        EXPECT_EQ(L.bytes_Psi, bytes(lev.Psi));
        EXPECT_EQ(L.dofs, lev.A.rows());
        EXPECT_EQ(L.wavelets, lev.B.rows());
        EXPECT_EQ(L.build_seconds, lev.build_seconds);
    }
    test::expect_error([&] { diagnose(h, Vector::Zero(3)); }, "load has 3 entries");

    // Given the fine solution of another solve of the same fine problem (the runtime's,
    // conditions eliminated), every level's error is the same up to the two solves' round-off
    // (1e-10 relative: the fine problem's condition number here is about 1e5).
    const Vector u = fem::solve_static(p.K, p.f, p.bc, {});
    DiagnoseOptions given;
    given.fine_solution = &u;
    const Diagnostics d2 = diagnose(h, p.f, given);
    for (std::size_t k = 0; k + 1 < d.levels.size(); ++k)
        EXPECT_NEAR(d2.levels[k].error_over_u, d.levels[k].error_over_u,
                    1e-10 * d.levels[k].error_over_u);
    const Vector short_u = Vector::Zero(3);
    given.fine_solution = &short_u;
    test::expect_error([&] { diagnose(h, p.f, given); }, "the fine solution has 3 entries");
}

// An intermediate level whose factorization would exceed max_factor_bytes is not solved: its
// errors are NaN, its note names the level and the refused size, it has no solution; level 1 and
// the fine level are as without the limit. Four levels of a 16x16 grid: A^1 has 18 rows, A^2 50
// and A^3 162, each factorized nearly dense (8 n^2 bytes: 2.6 KB, 20 KB, 210 KB, up to CHOLMOD's
// supernodal overhead), so a 12 KB limit passes level 1 alone; the test checks that first.
TEST(MraDiagnostics, IntermediateLevelTooLargeToFactorizeIsNotSolved) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(16, 16, 1), 1.0, 1e3, test::checker_pattern);
    const Hierarchy h =
        build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(4, Refinement::Linear));
    constexpr double limit = 12e3;
    solve::SolverOptions limited;
    limited.max_factor_bytes = limit;
    limited.lower_triangle = true;
    ASSERT_NO_THROW(solve::SpdSolver(limited).analyze(h.level(1).A));
    for (int k = 2; k <= 3; ++k)
        ASSERT_THROW(solve::SpdSolver(limited).analyze(h.level(k).A), solve::FactorTooLarge) << k;

    const Vector u = fem::solve_static(p.K, p.f, p.bc, {});
    DiagnoseOptions o;
    o.fine_solution = &u;
    o.keep_solutions = true;
    const Diagnostics full = diagnose(h, p.f, o);
    o.max_factor_bytes = limit;
    const Diagnostics d = diagnose(h, p.f, o);
    ASSERT_EQ(d.levels.size(), 4u);
    ASSERT_EQ(d.solutions.size(), 4u);
    for (const int i : {0, 3}) {  // levels 1 and 4: the same solves
        EXPECT_EQ(d.levels[i].error_over_u, full.levels[i].error_over_u) << i;
        EXPECT_EQ(d.solutions[i], full.solutions[i]) << i;
        EXPECT_TRUE(d.levels[i].solve_note.empty()) << i;
    }
    for (const int i : {1, 2}) {
        const LevelDiagnostics& L = d.levels[static_cast<std::size_t>(i)];
        EXPECT_TRUE(std::isnan(L.error_over_g) && std::isnan(L.error_over_u)) << i;
        EXPECT_EQ(d.solutions[static_cast<std::size_t>(i)].size(), 0) << i;
        EXPECT_NE(L.solve_note.find(fmt::format("level {} not solved", i + 1)), std::string::npos)
            << L.solve_note;
        EXPECT_NE(L.solve_note.find("allowed (max_factor_bytes)"), std::string::npos)
            << L.solve_note;
        EXPECT_GT(full.levels[static_cast<std::size_t>(i)].error_over_u, 0.0) << i;
        EXPECT_TRUE(full.levels[static_cast<std::size_t>(i)].solve_note.empty()) << i;
    }
    // The coarse model's level is not skipped: a limit it exceeds is an error.
    o.max_factor_bytes = 100;
    EXPECT_THROW(diagnose(h, p.f, o), solve::FactorTooLarge);
}

// A factorization of the fine operator from the caller (the runtime's of K_ff) is the one the
// fine level's smallest eigenvalue uses, so A^q is not factorized again: given that of 2 K_ff,
// Lanczos on its inverse finds 2 lambda_min, while lambda_max (products with A^q itself) and the
// coarse levels are unchanged. With and without the conditions in the hierarchy (constrain,
// ignore), whose level-q solves both factorize K_ff.
TEST(MraDiagnostics, FineSpectrumUsesTheGivenFactorization) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(8, 8, 1), 1.0, 1e3, test::checker_pattern);
    const fem::ReducedSystem sys = fem::reduce(p.K, p.f, p.bc);
    solve::SpdSolver twice;
    twice.compute(SparseMatrix(2.0 * sys.K));
    for (const DirichletTreatment t : {DirichletTreatment::Constrain, DirichletTreatment::Ignore}) {
        Options o = test::exact_options(3, Refinement::Linear);
        o.dirichlet = t;
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        const Diagnostics d = diagnose(h, p.f);
        DiagnoseOptions given;
        given.fine_factorization = &twice;
        const Diagnostics d2 = diagnose(h, p.f, given);
        const std::string what = dirichlet_name(t);
        // Lanczos converges to 1e-12 relative on both; 1e-10.
        const LevelDiagnostics &fine = d.levels.back(), &fine2 = d2.levels.back();
        EXPECT_NEAR(fine2.lambda_min_A, 2 * fine.lambda_min_A, 1e-10 * fine.lambda_min_A) << what;
        EXPECT_NEAR(fine2.lambda_max_A, fine.lambda_max_A, 1e-10 * fine.lambda_max_A) << what;
        for (std::size_t k = 0; k + 1 < d.levels.size(); ++k)
            EXPECT_EQ(d2.levels[k].lambda_min_A, d.levels[k].lambda_min_A) << what;
    }
    // A factorization of another size is not used: the fine spectrum is skipped and says why.
    const Hierarchy h =
        build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(3, Refinement::Linear));
    solve::SpdSolver other;
    other.compute(symmetric_from_lower(h.level(1).A));
    DiagnoseOptions wrong;
    wrong.fine_factorization = &other;
    const LevelDiagnostics fine = diagnose(h, p.f, wrong).levels.back();
    EXPECT_TRUE(fine.spectrum_skipped);
    EXPECT_NE(fine.spectrum_note.find("a factorization of"), std::string::npos)
        << fine.spectrum_note;
    // The penalty treatments factorize their own fine operator.
    Options penalty = test::exact_options(3, Refinement::Linear);
    penalty.dirichlet = DirichletTreatment::Penalty;
    const Hierarchy hp = build_hierarchy(p.mesh, p.K, p.bc.dofs, penalty);
    DiagnoseOptions given;
    given.fine_factorization = &twice;
    test::expect_error([&] { diagnose(hp, p.f, given); }, "factorizes its own fine operator");
}

/// Writes the CSV of each refinement of `p` (exact hierarchy, `levels` levels) into `dir`,
/// checks that it parses back and that the error of nested Galerkin spaces never grows with k,
/// and returns the file names separated by spaces. Prints the figures if `print`.
std::string check_csvs(const test::GridProblem& p, int levels, const std::string& dir, bool print) {
    std::string csvs;
    for (const Refinement r : {Refinement::Linear, Refinement::Dirac}) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(levels, r));
        const Diagnostics d = diagnose(h, p.f);
        const std::string file = dir + "/" + refinement_name(r) + ".csv";
        io::write_csv(levels_table(d), file);
        csvs += " " + file;
        for (std::size_t i = 0; i < d.levels.size(); ++i) {
            const LevelDiagnostics& L = d.levels[i];
            if (print)
                std::printf(
                    "%s k=%d dofs=%d wavelets=%d err/g=%.4e err/u=%.4e condA=%.4e "
                    "condB=%.4e spA=%.4f spB=%.4f spC=%.4f Phi=%zu Psi=%zu C=%zu A=%zu "
                    "B=%zu t=%.3f\n",
                    refinement_name(r).c_str(), L.k, L.dofs, L.wavelets, L.error_over_g,
                    L.error_over_u, L.cond_A, L.cond_B, L.sparsity_A, L.sparsity_B, L.sparsity_C,
                    L.bytes_Phi, L.bytes_Psi, L.bytes_C, L.bytes_A, L.bytes_B, L.build_seconds);
            // span Φ^k is contained in span Φ^{k+1} (Φ^k = C̃^k Φ^{k+1}), and u^k is the
            // A-projection of u: the error cannot grow with k. 1e-10 relative allows the
            // round-off of the solves.
            if (i > 0) {
                EXPECT_LE(L.error_over_u, d.levels[i - 1].error_over_u * (1 + 1e-10) + 1e-12)
                    << refinement_name(r) << " level " << L.k;
            }
        }
        // Parse back: header plus one row per level, level numbers 1..q in order.
        std::ifstream in(file);
        std::string line;
        EXPECT_TRUE(std::getline(in, line));
        EXPECT_EQ(line.rfind("level,dofs,wavelets,error_over_g,", 0), 0u);
        int rows = 0;
        while (std::getline(in, line)) {
            std::istringstream fields(line);
            std::string cell;
            int columns = 0, level = 0;
            double error = 0;
            while (std::getline(fields, cell, ',')) {
                if (columns == 0) level = std::stoi(cell);
                if (columns == 3) error = std::stod(cell);
                ++columns;
            }
            EXPECT_EQ(columns, 21);
            ++rows;
            EXPECT_EQ(level, rows);
            if (rows <= static_cast<int>(d.levels.size())) {
                // Written with 17 significant digits: reads back exactly.
                EXPECT_EQ(error, d.levels[static_cast<std::size_t>(rows - 1)].error_over_g);
            }
        }
        EXPECT_EQ(rows, h.num_levels());
    }
    return csvs;
}

/// The CSVs of linear and Dirac hierarchies of one scene parse back; the script plots them and
/// rejects a bad CSV with a clear message.
TEST(MraDiagnostics, CsvParsesBackAndPlots) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(8, 8, 1), 100.0, 5e6, layered);
    const std::string dir = test::temp_dir("mra_diagnostics_plot");
    const std::string csvs = check_csvs(p, 3, dir, false);
    const std::string script = COARSEGRAIN_TEST_DATA "/../../scripts/plot_mra.py";
    std::string out;
    ASSERT_EQ(test::run("/usr/bin/python3 " + script + " " + dir + "/error.png" + csvs +
                            " --cond " + dir + "/cond.png",
                        &out),
              0)
        << out;
    for (const char* png : {"/error.png", "/cond.png"}) {
        std::ifstream f(dir + png, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(f)),
                                std::istreambuf_iterator<char>());
        EXPECT_GT(bytes.size(), 1000u) << png;
        EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << png;
    }
    {
        std::ofstream bad(dir + "/bad.csv");
        bad << "level,dofs\n1,2\n";
    }
    EXPECT_NE(
        test::run("/usr/bin/python3 " + script + " " + dir + "/x.png " + dir + "/bad.csv", &out),
        0);
    EXPECT_NE(out.find("missing column(s) error_over_g"), std::string::npos) << out;
}

/// The 32x32 layered square (E 100 vs 5e6), 5 levels, linear and Dirac refinement (the figures
/// quoted in the report); writes the CSVs and plots into the test's temporary folder.
TEST(MraDiagnosticsSlow, Layered32) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(32, 32, 1), 100.0, 5e6, layered);
    const std::string dir = test::temp_dir("mra_diagnostics_layered32");
    check_csvs(p, 5, dir, true);
}

}  // namespace
}  // namespace coarsegrain::mra
