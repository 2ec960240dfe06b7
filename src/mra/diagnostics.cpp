#include "coarsegrain/mra/diagnostics.hpp"

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <span>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

/// y = A^{-1} x by a factorization of A: the operator of Lanczos for the smallest eigenvalue.
class InverseOp {
  public:
    using Scalar = double;
    explicit InverseOp(const solve::SpdSolver& solver) : m_solver(solver) {}
    Index rows() const { return m_solver.rows(); }
    Index cols() const { return m_solver.rows(); }
    void perform_op(const double* x_in, double* y_out) const {
        const Vector y = m_solver.solve(Vector(Eigen::Map<const Vector>(x_in, rows())));
        Eigen::Map<Vector>(y_out, rows()) = y;
    }

  private:
    const solve::SpdSolver& m_solver;
};

/// Largest eigenvalue of the operator by Lanczos. Tolerance 1e-12 relative (Spectra's
/// convergence test on the Ritz value), well under the 1e-8 the tests ask for.
template <class Op>
double largest_eigenvalue(Op& op, const char* what) {
    const Index n = op.rows();
    // 40 Lanczos vectors: 20 left the largest eigenvalue of a 15000-row B^1 (100x100 grid)
    // unconverged after 1000 restarts.
    const Index ncv = std::min<Index>(n, 40);
    Spectra::SymEigsSolver<Op> eigs(op, 1, ncv);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestAlge, 1000, 1e-12);
    CG_VERIFY(eigs.info() == Spectra::CompInfo::Successful,
              "mra diagnostics: Lanczos for the {} eigenvalue of a {}x{} matrix did not converge",
              what, n, n);
    return eigs.eigenvalues()[0];
}

double energy_norm(const SparseMatrix& A, const Vector& v) { return std::sqrt(v.dot(A * v)); }

Vector restrict_to(const Vector& v, const IndexVector& dofs) {
    Vector r(dofs.size());
    for (Index i = 0; i < dofs.size(); ++i) r[i] = v[dofs[i]];
    return r;
}

/// A factorization of the matrix whose spectrum is asked for, made when first needed.
using Factorization = std::function<const solve::SpdSolver&()>;

/// Extreme eigenvalues of M (its lower triangle if `lower`), or NaN with L.spectrum_skipped set
/// and the reason appended to L.spectrum_note if M has more than `limit` rows or Lanczos fails.
/// The smallest uses `factorization` of M if given, else factorizes M.
Spectrum level_spectrum(const SparseMatrix& M, bool lower, const char* name, Index limit,
                        LevelDiagnostics& L, const Factorization& factorization = {}) {
    std::string reason;
    if (M.rows() > limit) {
        reason = fmt::format("{}: {} rows > coarse.spectrum_max_dofs = {}", name, M.rows(), limit);
    } else {
        try {
            const SparseMatrix A = lower ? symmetric_from_lower(M) : M;
            return factorization ? extreme_eigenvalues(A, factorization()) : extreme_eigenvalues(A);
        } catch (const Error& e) {
            reason = fmt::format("{}: {}", name, e.what());
        }
    }
    L.spectrum_skipped = true;
    L.spectrum_note += (L.spectrum_note.empty() ? "" : "; ") + reason;
    return {nan, nan};
}

/// Fraction of zeros of a rows x cols matrix whose stored values are `values`.
double zero_fraction(Index rows, Index cols, std::span<const double> values) {
    const double size = static_cast<double>(rows) * static_cast<double>(cols);
    if (size == 0) return 0;
    const auto nonzero =
        std::count_if(values.begin(), values.end(), [](double v) { return v != 0; });
    return 1.0 - static_cast<double>(nonzero) / size;
}

/// sparsity() of the symmetric matrix whose lower triangle `lower` holds.
double symmetric_sparsity(const SparseMatrix& lower) {
    const double size = static_cast<double>(lower.rows()) * static_cast<double>(lower.cols());
    return size > 0 ? 1.0 - static_cast<double>(symmetric_nonzeros(lower)) / size : 0.0;
}

/// u^k of level k < q by `solver`, or, for k > 1 whose factorization is refused for its size, an
/// empty vector with the reason in L.solve_note.
Vector level_solution(MultilevelSolver& solver, const Vector& g_fine, int k, LevelDiagnostics& L) {
    try {
        return solver.solve_level(g_fine, k);
    } catch (const solve::FactorTooLarge& e) {
        if (k == 1) throw;
        L.solve_note = fmt::format("level {} not solved: {}", k, e.what());
        return {};
    }
}

}  // namespace

Spectrum extreme_eigenvalues(const SparseMatrix& A) {
    CG_VERIFY(A.rows() > 0 && A.rows() == A.cols(),
              "mra diagnostics: eigenvalues of a {}x{} matrix", A.rows(), A.cols());
    solve::SpdSolver factorization;
    if (A.rows() > 1) factorization.compute(A);
    return extreme_eigenvalues(A, factorization);
}

Spectrum extreme_eigenvalues(const SparseMatrix& A, const solve::SpdSolver& factorization) {
    CG_VERIFY(A.rows() > 0 && A.rows() == A.cols(),
              "mra diagnostics: eigenvalues of a {}x{} matrix", A.rows(), A.cols());
    if (A.rows() == 1) {
        const double a = A.coeff(0, 0);
        CG_VERIFY(a > 0, "mra diagnostics: 1x1 matrix {} is not positive definite", a);
        return {a, a};
    }
    CG_VERIFY(factorization.rows() == A.rows(),
              "mra diagnostics: a factorization of {} rows for a {}x{} matrix",
              factorization.rows(), A.rows(), A.cols());
    // Both triangles are stored; the product uses the lower one.
    Spectra::SparseSymMatProd<double, Eigen::Lower, Eigen::ColMajor, Index> prod(A);
    InverseOp inv(factorization);
    Spectrum s;
    s.lambda_max = largest_eigenvalue(prod, "largest");
    s.lambda_min = 1.0 / largest_eigenvalue(inv, "smallest");
    return s;
}

double sparsity(const SparseMatrix& M) {
    return zero_fraction(M.rows(), M.cols(),
                         {M.valuePtr(), static_cast<std::size_t>(M.nonZeros())});
}

double sparsity(const RunMatrix& M) { return zero_fraction(M.rows(), M.cols(), M.values()); }

Diagnostics diagnose(const Hierarchy& h, const Vector& g_fine, const DiagnoseOptions& options) {
    CG_VERIFY(g_fine.size() == h.fine_grid_dofs(),
              "mra diagnostics: load has {} entries, the fine grid {} DOFs", g_fine.size(),
              h.fine_grid_dofs());
    const int q = h.num_levels();
    const double g_norm = restrict_to(g_fine, h.fine_dofs).norm();
    CG_VERIFY(g_norm > 0, "mra diagnostics: the load is zero on the hierarchy's DOFs");
    MultilevelSolver solver(h, options.max_factor_bytes);
    const bool penalized = h.options.dirichlet == DirichletTreatment::Penalty ||
                           h.options.dirichlet == DirichletTreatment::DiagonalPenalty;
    CG_VERIFY(!options.fine_solution || !penalized,
              "mra diagnostics: the {} treatment solves its own fine problem; give no fine "
              "solution",
              dirichlet_name(h.options.dirichlet));
    CG_VERIFY(!options.fine_solution || options.fine_solution->size() == h.fine_grid_dofs(),
              "mra diagnostics: the fine solution has {} entries, the fine grid {} DOFs",
              options.fine_solution ? options.fine_solution->size() : 0, h.fine_grid_dofs());
    CG_VERIFY(!options.fine_factorization || !penalized,
              "mra diagnostics: the {} treatment factorizes its own fine operator; give no fine "
              "factorization",
              dirichlet_name(h.options.dirichlet));
    const Vector u_grid =
        options.fine_solution ? *options.fine_solution : solver.solve_level(g_fine, q);
    const Vector u = restrict_to(u_grid, h.fine_dofs);
    const double u_norm = energy_norm(h.A_fine, u);
    Diagnostics d;
    d.levels.resize(static_cast<std::size_t>(q));
    for (int k = 1; k <= q; ++k) {
        LevelDiagnostics& L = d.levels[static_cast<std::size_t>(k - 1)];
        L.k = k;
        const SparseMatrix& A = k == q ? h.A_fine : h.level(k).A;
        L.dofs = A.rows();
        Vector u_k = k == q ? u_grid : level_solution(solver, g_fine, k, L);
        if (u_k.size() > 0) {
            const Vector e = restrict_to(u_k, h.fine_dofs) - u;
            L.error_over_g = energy_norm(h.A_fine, e) / g_norm;
            L.error_over_u = energy_norm(h.A_fine, e) / u_norm;
        } else {
            L.error_over_g = L.error_over_u = nan;
        }
        if (options.keep_solutions) d.solutions.push_back(std::move(u_k));
        const bool lower = k < q;  // Level::A is stored as its lower triangle, A_fine whole
        // The spectrum of the operator the level's solves factorize (boundary-blind levels:
        // without their fixed DOFs, whose A^k is singular), with their factorization: the
        // caller's of the fine operator, or the solver's.
        const bool held = fixed_positions(h, k).size() > 0;
        const Factorization factorization = [&]() -> const solve::SpdSolver& {
            if (k == q && options.fine_factorization) return *options.fine_factorization;
            return solver.factorization(k);
        };
        const Spectrum sa = level_spectrum(held ? free_operator(h, k) : A, lower, "A",
                                           options.max_spectrum_dofs, L, factorization);
        L.lambda_min_A = sa.lambda_min;
        L.lambda_max_A = sa.lambda_max;
        L.cond_A = sa.condition();
        L.sparsity_A = lower ? symmetric_sparsity(A) : sparsity(A);
        L.bytes_A = storage_bytes(A);
        if (k == q) {
            L.lambda_min_B = L.lambda_max_B = L.cond_B = nan;
            L.sparsity_B = L.sparsity_C = nan;
            continue;
        }
        const Level& lev = h.level(k);
        L.wavelets = lev.B.rows();
        const Spectrum sb = L.wavelets > 0
                                ? level_spectrum(lev.B, true, "B", options.max_spectrum_dofs, L)
                                : Spectrum{nan, nan};
        L.lambda_min_B = sb.lambda_min;
        L.lambda_max_B = sb.lambda_max;
        L.cond_B = sb.condition();
        L.sparsity_B = symmetric_sparsity(lev.B);
        L.sparsity_C = sparsity(lev.C_adapted);
        L.bytes_Phi = storage_bytes(lev.Phi);
        L.bytes_Psi = storage_bytes(lev.Psi);
        L.bytes_C = storage_bytes(lev.C_adapted);
        L.bytes_B = storage_bytes(lev.B);
        L.build_seconds = lev.build_seconds;
    }
    return d;
}

io::Table levels_table(const Diagnostics& d) {
    io::Table t{"mra_levels",
                {"level",           "dofs",         "wavelets",   "error_over_g", "error_over_u",
                 "lambda_min_A",    "lambda_max_A", "cond_A",     "lambda_min_B", "lambda_max_B",
                 "cond_B",          "sparsity_A",   "sparsity_B", "sparsity_C",   "bytes_Phi",
                 "bytes_Psi",       "bytes_C",      "bytes_A",    "bytes_B",      "build_seconds",
                 "spectrum_skipped"},
                Matrix(static_cast<Index>(d.levels.size()), 21)};
    for (std::size_t i = 0; i < d.levels.size(); ++i) {
        const LevelDiagnostics& L = d.levels[i];
        t.values.row(static_cast<Index>(i)) << L.k, L.dofs, L.wavelets, L.error_over_g,
            L.error_over_u, L.lambda_min_A, L.lambda_max_A, L.cond_A, L.lambda_min_B,
            L.lambda_max_B, L.cond_B, L.sparsity_A, L.sparsity_B, L.sparsity_C,
            static_cast<double>(L.bytes_Phi), static_cast<double>(L.bytes_Psi),
            static_cast<double>(L.bytes_C), static_cast<double>(L.bytes_A),
            static_cast<double>(L.bytes_B), L.build_seconds, L.spectrum_skipped ? 1.0 : 0.0;
    }
    return t;
}

}  // namespace coarsegrain::mra
