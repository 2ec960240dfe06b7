#pragma once
/// @file Per-level figures of a material-adapted hierarchy that reproduce Chen et al. 2019,
/// Sec. 5 as data: homogenization error (Fig. 9, Table 1), extreme eigenvalues and condition
/// numbers of A^k and B^k (Figs. 7 and 8), sparsity and storage (Table 1), build time.
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "coarsegrain/io/table.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra {

/// Figures of one level k (1 = coarsest, q = finest). Quantities a level does not have (B^q,
/// C̃^q, Ψ^q at the finest level) are NaN or 0 bytes.
struct LevelDiagnostics {
    int k = 0;
    Index dofs = 0;      ///< rows of A^k
    Index wavelets = 0;  ///< rows of B^k (0 at level q)
    /// Homogenization error of the single-level solve (Sec. 4.1): ||u^k - u||_A / ||g||_2 with
    /// u^k = Φ^{k,T} (A^k)^{-1} g^k, u the fine solution and A = A^q (the paper's Fig. 9 metric).
    double error_over_g = 0;
    double error_over_u = 0;  ///< ||u^k - u||_A / ||u||_A
    /// Why the level was not solved, if it was not (its errors are then NaN; not in the CSV):
    /// an intermediate level 1 < k < q whose factorization would not fit
    /// (DiagnoseOptions::max_factor_bytes).
    std::string solve_note;
    /// Extreme eigenvalues and condition numbers of A^k (Figs. 7, 8) and B^k (NaN at level q);
    /// NaN also where skipped (spectrum_skipped).
    double lambda_min_A = 0, lambda_max_A = 0, cond_A = 0;
    double lambda_min_B = 0, lambda_max_B = 0, cond_B = 0;
    /// Fraction of zero entries (1 - nonzeros / (rows * cols)) of the whole matrices (both
    /// triangles of A^k and B^k); explicitly stored zeros count as zeros. sparsity_C is of C̃^k
    /// (NaN at level q).
    double sparsity_A = 0, sparsity_B = 0, sparsity_C = 0;
    /// Storage (storage_bytes) as kept: A^k and B^k as their lower triangles (A^q whole), C̃^k
    /// as a RunMatrix; Φ^k and Ψ^k only where kept (Options::store_bases), else the few bytes
    /// of an empty matrix.
    std::size_t bytes_Phi = 0, bytes_Psi = 0, bytes_C = 0, bytes_A = 0, bytes_B = 0;
    double build_seconds = 0;  ///< Level::build_seconds (0 at level q, which is not built)
    /// The spectrum of A^k or B^k was not computed: more rows than max_spectrum_dofs, or
    /// Lanczos did not converge (an optional figure never fails the diagnostics).
    bool spectrum_skipped = false;
    std::string spectrum_note;  ///< why, if skipped (not in the CSV)
};

struct Diagnostics {
    std::vector<LevelDiagnostics> levels;  ///< levels[k-1] is level k, k = 1..q
    /// u^k = Φ^{k,T} (A^k)^{-1} g^k over all fine grid DOFs, solutions[k-1] for level k (u^q is
    /// the fine solution, empty for a level not solved); none unless
    /// DiagnoseOptions::keep_solutions.
    std::vector<Vector> solutions;
};

struct DiagnoseOptions {
    /// Spectra of matrices with more rows are skipped (NaN): the smallest eigenvalue costs a
    /// sparse factorization and tens of Lanczos solves with it.
    Index max_spectrum_dofs = std::numeric_limits<Index>::max();
    bool keep_solutions = false;  ///< fill Diagnostics::solutions
    /// The fine solution u^q over all fine grid DOFs, if the caller has it (the runtime's fine
    /// solve): the fine level is then not factorized and solved again. It must solve the
    /// hierarchy's own fine problem: the eliminate, constrain or ignore treatment (the penalty
    /// treatments solve a penalized one).
    const Vector* fine_solution = nullptr;
    /// A factorization of the fine operator that a level-q solve factorizes, free_operator(h, q)
    /// (the fine stiffness without the fixed DOFs, as fem::solve_static factorizes it), if the
    /// caller has one (the runtime's fine solve): the smallest eigenvalue of A^q then uses it
    /// instead of factorizing A^q again. Not with the penalty treatments, whose fine operator
    /// is their own.
    const solve::SpdSolver* fine_factorization = nullptr;
    /// The most bytes a level's factorization may take (solve::SolverOptions::max_factor_bytes;
    /// 0: the memory available when it is made). An intermediate level 1 < k < q whose
    /// factorization would take more is not solved (LevelDiagnostics::solve_note): its A^k can
    /// be far denser than the fine operator, and its solve is a figure, not the coarse model.
    double max_factor_bytes = 0;
};

/// Extreme eigenvalues of a symmetric positive-definite sparse matrix.
struct Spectrum {
    double lambda_min = 0, lambda_max = 0;
    double condition() const { return lambda_max / lambda_min; }
};

/// Largest eigenvalue by Lanczos on A (Spectra), smallest by Lanczos on A^{-1} (shift-invert
/// with shift 0, one CHOLMOD factorization). Never forms a dense matrix.
/// @throws Error if A is empty, not positive definite, or Lanczos does not converge
Spectrum extreme_eigenvalues(const SparseMatrix& A);
/// The same with a factorization of A made beforehand (`factorization` solves with A).
/// @throws Error as above, or if the factorization's size is not A's
Spectrum extreme_eigenvalues(const SparseMatrix& A, const solve::SpdSolver& factorization);

/// Fraction of zero entries of M (explicitly stored zeros count as zeros); 0 for an empty M.
double sparsity(const SparseMatrix& M);
double sparsity(const RunMatrix& M);

/// All figures of all levels for the load `g_fine` (over all fine grid DOFs, as
/// MultilevelSolver::solve_level takes it). Each A^k is factorized once, for the level's solve
/// and the smallest eigenvalue (A^q not at all with DiagnoseOptions::fine_factorization).
/// @throws Error if g_fine has the wrong size or is zero on the hierarchy's fine DOFs, or a
///         fine solution or factorization is given for a penalty treatment or has the wrong size
/// @throws solve::FactorTooLarge if the factorization of A^1, or of A^q without a fine
///         solution, would exceed DiagnoseOptions::max_factor_bytes
Diagnostics diagnose(const Hierarchy& h, const Vector& g_fine, const DiagnoseOptions& options = {});

/// The table "mra_levels": one row per level, columns as the LevelDiagnostics fields in their
/// order (spectrum_skipped last, as 0 / 1; NaN where a level has no such figure).
io::Table levels_table(const Diagnostics& d);

}  // namespace coarsegrain::mra
