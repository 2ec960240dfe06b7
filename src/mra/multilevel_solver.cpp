#include "coarsegrain/mra/multilevel_solver.hpp"

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra {

MultilevelSolver::MultilevelSolver(const Hierarchy& h, double max_factor_bytes)
    : m_h(h),
      m_max_factor_bytes(max_factor_bytes),
      m_A(static_cast<std::size_t>(h.num_levels())),
      m_B(static_cast<std::size_t>(h.num_levels() - 1)) {}

MultilevelSolver::~MultilevelSolver() = default;
MultilevelSolver::MultilevelSolver(MultilevelSolver&&) noexcept = default;

void MultilevelSolver::factorize_level(int k) {
    CG_VERIFY(k >= 1 && k <= m_h.num_levels(), "mra: level {} out of range 1..{}", k,
              m_h.num_levels());
    auto& s = m_A[static_cast<std::size_t>(k - 1)];
    if (s) return;
    const bool fine = k == m_h.num_levels();
    solve::SolverOptions options;
    options.max_factor_bytes = m_max_factor_bytes;
    options.lower_triangle = !fine;  // Level::A holds the lower triangle of A^k
    // Kept only once factorized: a refused or failed factorization is tried again on next use.
    auto solver = std::make_unique<solve::SpdSolver>(options);
    if (fixed_positions(m_h, k).size() > 0)
        solver->compute(free_operator(m_h, k));
    else
        solver->compute(fine ? m_h.A_fine : m_h.level(k).A);
    s = std::move(solver);
}

const solve::SpdSolver& MultilevelSolver::factorization(int k) {
    factorize_level(k);
    return *m_A[static_cast<std::size_t>(k - 1)];
}

Vector MultilevelSolver::solve_on_level(const Vector& g, int k) {
    const solve::SpdSolver& s = factorization(k);
    if (fixed_positions(m_h, k).size() == 0) return s.solve(g);
    const IndexVector free = free_positions(m_h, k);
    Vector u = Vector::Zero(g.size());
    u(free) = s.solve(Vector(g(free)));
    return u;
}

void MultilevelSolver::factorize_wavelets(int k) {
    const Level& L = m_h.level(k);
    auto& s = m_B[static_cast<std::size_t>(k - 1)];
    if (s) return;
    solve::SolverOptions options;
    options.max_factor_bytes = m_max_factor_bytes;
    options.lower_triangle = true;  // Level::B holds the lower triangle of B^k
    auto solver = std::make_unique<solve::SpdSolver>(options);
    solver->compute(L.B);
    s = std::move(solver);
}

Vector MultilevelSolver::solve_levels(const Vector& g_fine, int m) {
    const int q = m_h.num_levels();
    CG_VERIFY(m >= 1 && m <= q, "mra: number of levels {} out of range 1..{}", m, q);
    CG_VERIFY(m == 1 || m_h.options.dirichlet != DirichletTreatment::Ignore,
              "mra: the boundary-blind hierarchy (dirichlet \"ignore\") has no wavelet solves: "
              "its wavelets do not vanish at the fixed DOFs; solve one level at a time");
    // Coarse-graining g^k = C̃^k g^{k+1}, keeping W^k g^{k+1} for the wavelet solves.
    std::vector<Vector> Wg(static_cast<std::size_t>(q - 1));
    Vector g = coarse_grain(m_h, g_fine, q);
    for (int k = q - 1; k >= 1; --k) {
        const Level& L = m_h.level(k);
        if (k < m) Wg[static_cast<std::size_t>(k - 1)] = L.W * g;
        g = L.C_adapted * g;
    }
    // u = Φ^{1,T} v^1 + sum_{k<m} Ψ^{k,T} w^k, accumulated from the coarsest level:
    // u^{k+1} = C̃^{k,T} u^k + W^{k,T} w^k, since Φ^k = C̃^k Φ^{k+1} and Ψ^k = W^k Φ^{k+1}.
    Vector u = solve_on_level(g, 1);
    for (int k = 1; k < q; ++k) {
        const Level& L = m_h.level(k);
        u = L.C_adapted.transpose_times(u);
        if (k < m) {
            factorize_wavelets(k);
            u += L.W.transpose() *
                 m_B[static_cast<std::size_t>(k - 1)]->solve(Wg[static_cast<std::size_t>(k - 1)]);
        }
    }
    return expand_fine(m_h, u);
}

Vector MultilevelSolver::solve_level(const Vector& g_fine, int k) {
    return reconstruct(m_h, solve_on_level(coarse_grain(m_h, g_fine, k), k), k);
}

Vector expand_fine(const Hierarchy& h, const Vector& u_present) {
    CG_VERIFY(u_present.size() == h.fine_dofs.size(), "mra: {} values for {} fine DOFs",
              u_present.size(), h.fine_dofs.size());
    Vector u = Vector::Zero(h.fine_grid_dofs());
    for (Index i = 0; i < h.fine_dofs.size(); ++i) u[h.fine_dofs[i]] = u_present[i];
    return u;
}

}  // namespace coarsegrain::mra
