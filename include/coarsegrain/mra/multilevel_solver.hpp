#pragma once
/// @file Solves with the material-adapted hierarchy (Chen et al. 2019, Sec. 3.6 and 4.1).
#include <memory>
#include <vector>

#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra {

/// Static solves on a hierarchy. Factorizations of A^k and B^k are computed on first use and
/// kept, so further right-hand sides cost only coarse-graining, back-substitutions and the
/// products with Φ and Ψ. Vectors in and out are over all fine grid DOFs (interleaved); entries
/// of eliminated Dirichlet DOFs are ignored on input and zero on output. Not thread-safe.
class MultilevelSolver {
  public:
    /// Keeps a reference to `h`, which must outlive the solver. `max_factor_bytes` is the
    /// solve::SolverOptions::max_factor_bytes of every factorization (0: the memory available).
    explicit MultilevelSolver(const Hierarchy& h, double max_factor_bytes = 0);
    ~MultilevelSolver();
    MultilevelSolver(MultilevelSolver&&) noexcept;

    /// Multilevel solve (Sec. 3.6) with the wavelets of levels 1..m-1: g^k = C̃^k g^{k+1},
    /// B^k w^k = W^k g^{k+1}, A^1 v^1 = g^1, u = Φ^{1,T} v^1 + sum_{k<m} Ψ^{k,T} w^k. With
    /// m = q (all levels) this reproduces the fine solution A^q u = g^q when the wavelets are
    /// exactly A-orthogonal to the basis (global solves, no truncation or correction: Eq. 12);
    /// with m = 1 it is the coarsest solve.
    /// @throws Error if m is not in 1..q, g has the wrong size, or m > 1 on a boundary-blind
    ///         hierarchy (DirichletTreatment::Ignore)
    Vector solve_levels(const Vector& g_fine, int m);
    Vector solve(const Vector& g_fine) { return solve_levels(g_fine, m_h.num_levels()); }

    /// Single coarse level k (Sec. 4.1): A^k u^k = g^k, u = Φ^{k,T} u^k (k = q: the fine solve),
    /// with u^k = 0 at fixed_positions(h, k).
    Vector solve_level(const Vector& g_fine, int k);

    /// Factorizes A^k / B^k now (otherwise on first use). Every solve and factorization throws
    /// solve::FactorTooLarge, before any numeric work, if a factorization it needs would exceed
    /// max_factor_bytes.
    void factorize_level(int k);
    void factorize_wavelets(int k);
    /// The factorization of the operator a level-k solve factorizes (free_operator(h, k)),
    /// made now if not yet: for further solves with it, e.g. the smallest eigenvalue of A^k.
    const solve::SpdSolver& factorization(int k);

  private:
    /// u^k with A^k u^k = g^k on the free DOFs of level k and u^k = 0 at its fixed_positions.
    Vector solve_on_level(const Vector& g, int k);

    const Hierarchy& m_h;
    double m_max_factor_bytes;
    std::vector<std::unique_ptr<solve::SpdSolver>> m_A;  ///< index k-1, k = 1..q
    std::vector<std::unique_ptr<solve::SpdSolver>> m_B;  ///< index k-1, k = 1..q-1
};

/// Fine vector over all grid DOFs from one over the hierarchy's fine DOFs (zeros elsewhere).
Vector expand_fine(const Hierarchy& h, const Vector& u_present);

}  // namespace coarsegrain::mra
