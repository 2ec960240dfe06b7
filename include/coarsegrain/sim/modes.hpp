#pragma once
/// @file Natural frequencies and modes: the lowest eigenpairs of K φ = ω² M φ on the free DOFs,
/// and the modal assurance criterion that pairs the modes of two models.
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::sim {

/// The lowest eigenpairs of a model.
struct Modes {
    Vector eigenvalues;     ///< ω² (1/time²), ascending
    Vector frequencies_hz;  ///< ω / 2π (cycles per time unit), ascending
    /// n x k mode shapes over all DOFs, zero on the Dirichlet DOFs, mass-normalized
    /// (φ_iᵀ M φ_i = 1) and signed so that their largest-magnitude entry is positive.
    Matrix vectors;
};

/// The min(count, free DOFs) lowest eigenpairs of K φ = ω² M φ with the Dirichlet DOFs of `bc`
/// removed (their values are ignored). Shift-invert Lanczos (Spectra's SymGEigsShiftSolver,
/// shift 0) on one factorization of the free stiffness K_ff; models of at most 600 free DOFs
/// are solved densely (LAPACK). Eigenvalues converge to 1e-10 relative.
/// @param K  n x n stiffness, both triangles stored; K_ff positive definite (the conditions
///           hold the body)
/// @param M  n x n mass, M_ff positive definite
/// @throws Error if sizes disagree, count < 1 or Lanczos does not converge;
///         NotPositiveDefinite if K_ff is singular
Modes modes(const SparseMatrix& K, const SparseMatrix& M, const fem::Dirichlet& bc, int count,
            const solve::SolverOptions& solver = {});

/// Modal assurance criterion (aᵀb)² / (aᵀa · bᵀb): 1 for parallel shapes, 0 for orthogonal.
/// @throws Error if sizes disagree or a vector is zero
double mac(const Vector& a, const Vector& b);

/// One fine mode and the coarse mode paired with it.
struct ModePair {
    Index coarse = 0;  ///< column of the coarse modes
    double mac = 0;    ///< MAC of the pair
};

/// Pairs each column of `reference` with the column of `candidates` (same rows) of largest MAC.
/// Several reference modes may pair with one candidate (when the candidate model lacks a mode).
/// @throws Error if the row counts disagree or `candidates` has no column
std::vector<ModePair> pair_modes(const Matrix& reference, const Matrix& candidates);

}  // namespace coarsegrain::sim
