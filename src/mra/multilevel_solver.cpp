#include "coarsegrain/mra/multilevel_solver.hpp"

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra {

MultilevelSolver::MultilevelSolver(const Hierarchy& h)
    : m_h(h),
      m_A(static_cast<std::size_t>(h.num_levels())),
      m_B(static_cast<std::size_t>(h.num_levels() - 1)) {}

MultilevelSolver::~MultilevelSolver() = default;
MultilevelSolver::MultilevelSolver(MultilevelSolver&&) noexcept = default;

void MultilevelSolver::factorize_level(int k) {
    CG_VERIFY(k >= 1 && k <= m_h.num_levels(), "mra: level {} out of range 1..{}", k,
              m_h.num_levels());
    auto& s = m_A[static_cast<std::size_t>(k - 1)];
    if (s) return;
    s = std::make_unique<solve::SpdSolver>();
    s->compute(k == m_h.num_levels() ? m_h.A_fine : m_h.level(k).A);
}

void MultilevelSolver::factorize_wavelets(int k) {
    const Level& L = m_h.level(k);
    auto& s = m_B[static_cast<std::size_t>(k - 1)];
    if (s) return;
    s = std::make_unique<solve::SpdSolver>();
    s->compute(L.B);
}

Vector MultilevelSolver::solve_levels(const Vector& g_fine, int m) {
    const int q = m_h.num_levels();
    CG_VERIFY(m >= 1 && m <= q, "mra: number of levels {} out of range 1..{}", m, q);
    Vector g = coarse_grain(m_h, g_fine, q);
    Vector u = Vector::Zero(m_h.fine_grid_dofs());
    for (int k = q - 1; k >= 1; --k) {
        const Level& L = m_h.level(k);
        if (k < m) {
            factorize_wavelets(k);
            const Vector w = m_B[static_cast<std::size_t>(k - 1)]->solve(Vector(L.W * g));
            u += L.Psi.transpose() * w;
        }
        g = L.C_adapted * g;
    }
    factorize_level(1);
    u += m_h.level(1).Phi.transpose() * m_A[0]->solve(g);
    return u;
}

Vector MultilevelSolver::solve_level(const Vector& g_fine, int k) {
    factorize_level(k);
    const Vector g = coarse_grain(m_h, g_fine, k);
    const Vector v = m_A[static_cast<std::size_t>(k - 1)]->solve(g);
    if (k == m_h.num_levels()) return expand_fine(m_h, v);
    return m_h.level(k).Phi.transpose() * v;
}

Vector expand_fine(const Hierarchy& h, const Vector& u_present) {
    CG_VERIFY(u_present.size() == h.fine_dofs.size(),
              "mra: {} values for {} fine DOFs", u_present.size(), h.fine_dofs.size());
    Vector u = Vector::Zero(h.fine_grid_dofs());
    for (Index i = 0; i < h.fine_dofs.size(); ++i) u[h.fine_dofs[i]] = u_present[i];
    return u;
}

}  // namespace coarsegrain::mra
