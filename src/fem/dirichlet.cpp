#include "coarsegrain/fem/dirichlet.hpp"

#include <algorithm>

#include "coarsegrain/common/error.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

/// Merges (dof, value) pairs into bc; new values override existing ones for the same DOF.
void merge(Dirichlet& bc, std::vector<std::pair<Index, double>> added) {
    std::stable_sort(added.begin(), added.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<std::pair<Index, double>> out;
    out.reserve(bc.dofs.size() + added.size());
    std::size_t i = 0, j = 0;
    while (i < bc.dofs.size() || j < added.size()) {
        if (j == added.size() || (i < bc.dofs.size() && bc.dofs[i] < added[j].first)) {
            out.emplace_back(bc.dofs[i], bc.values[static_cast<Index>(i)]);
            ++i;
        } else {
            if (i < bc.dofs.size() && bc.dofs[i] == added[j].first) ++i;  // overridden
            // Within `added` the last entry for a DOF wins.
            while (j + 1 < added.size() && added[j + 1].first == added[j].first) ++j;
            out.push_back(added[j]);
            ++j;
        }
    }
    bc.dofs.resize(out.size());
    bc.values.resize(static_cast<Index>(out.size()));
    for (std::size_t k = 0; k < out.size(); ++k) {
        bc.dofs[k] = out[k].first;
        bc.values[static_cast<Index>(k)] = out[k].second;
    }
}

}  // namespace

void Dirichlet::fix_nodes(const std::vector<Index>& nodes, const Eigen::VectorXd& value) {
    const int dim = static_cast<int>(value.size());
    CG_VERIFY(dim == 2 || dim == 3,
              "Dirichlet::fix_nodes: value has {} components, expected 2 or 3", dim);
    std::vector<std::pair<Index, double>> added;
    added.reserve(nodes.size() * static_cast<std::size_t>(dim));
    for (const Index v : nodes) {
        CG_VERIFY(v >= 0, "Dirichlet::fix_nodes: node {} is negative", v);
        for (int d = 0; d < dim; ++d) added.emplace_back(dim * v + d, value[d]);
    }
    merge(*this, std::move(added));
}

void Dirichlet::fix_component(const std::vector<Index>& nodes, int dim, int component,
                              double value) {
    CG_VERIFY(dim == 2 || dim == 3, "Dirichlet::fix_component: dim = {} must be 2 or 3", dim);
    CG_VERIFY(component >= 0 && component < dim,
              "Dirichlet::fix_component: component = {} must be in 0..{}", component, dim - 1);
    std::vector<std::pair<Index, double>> added;
    added.reserve(nodes.size());
    for (const Index v : nodes) {
        CG_VERIFY(v >= 0, "Dirichlet::fix_component: node {} is negative", v);
        added.emplace_back(dim * v + component, value);
    }
    merge(*this, std::move(added));
}

IndexVector free_dofs(Index n, const std::vector<Index>& fixed_dofs) {
    for (std::size_t k = 0; k < fixed_dofs.size(); ++k) {
        const Index d = fixed_dofs[k];
        CG_VERIFY(d >= 0 && d < n, "Dirichlet DOF {} out of range 0..{}", d, n - 1);
        CG_VERIFY(k == 0 || fixed_dofs[k - 1] < d,
                  "Dirichlet DOFs must be sorted and unique, got {} after {}", d,
                  fixed_dofs[k - 1]);
    }
    IndexVector free(n - static_cast<Index>(fixed_dofs.size()));
    auto fixed = fixed_dofs.begin();
    for (Index i = 0, next = 0; i < n; ++i) {
        if (fixed != fixed_dofs.end() && *fixed == i)
            ++fixed;
        else
            free[next++] = i;
    }
    return free;
}

IndexVector free_dofs(Index n, const Dirichlet& bc) { return free_dofs(n, bc.dofs); }

ReducedSystem reduce(const SparseMatrix& K, const Vector& f, const Dirichlet& bc) {
    const Index n = static_cast<Index>(K.rows());
    CG_VERIFY(K.cols() == n, "reduce: K is {}x{}, not square", K.rows(), K.cols());
    CG_VERIFY(f.size() == n, "reduce: f has {} entries, K has {} rows", f.size(), n);
    CG_VERIFY(static_cast<std::size_t>(bc.values.size()) == bc.dofs.size(),
              "reduce: {} Dirichlet DOFs but {} values", bc.dofs.size(), bc.values.size());
    CG_VERIFY(K.isCompressed(), "reduce: K must be in compressed storage (call makeCompressed)");
    ReducedSystem sys;
    sys.free_dofs = free_dofs(n, bc);
    const Index nf = sys.free_dofs.size();
    // map[i] = reduced index of DOF i, or -1 if DOF i is prescribed.
    std::vector<Index> map(static_cast<std::size_t>(n), -1);
    for (Index r = 0; r < nf; ++r) map[sys.free_dofs[r]] = r;
    const Index* outer = K.outerIndexPtr();
    const Index* inner = K.innerIndexPtr();
    const double* values = K.valuePtr();

    // K_ff: count the free rows of each free column, then copy (the renumbering is monotone, so
    // rows stay sorted).
    sys.K.resize(nf, nf);
    Index* rout = sys.K.outerIndexPtr();
    rout[0] = 0;
#pragma omp parallel for schedule(static) if (nf >= detail::kMinParallel)
    for (Index c = 0; c < nf; ++c) {
        const Index j = sys.free_dofs[c];
        Index count = 0;
        for (Index p = outer[j]; p < outer[j + 1]; ++p) count += map[inner[p]] >= 0;
        rout[c + 1] = count;
    }
    for (Index c = 0; c < nf; ++c) rout[c + 1] += rout[c];
    sys.K.resizeNonZeros(rout[nf]);
    Index* rin = sys.K.innerIndexPtr();
    double* rval = sys.K.valuePtr();
#pragma omp parallel for schedule(static) if (nf >= detail::kMinParallel)
    for (Index c = 0; c < nf; ++c) {
        const Index j = sys.free_dofs[c];
        Index k = rout[c];
        for (Index p = outer[j]; p < outer[j + 1]; ++p) {
            const Index r = map[inner[p]];
            if (r >= 0) {
                rin[k] = r;
                rval[k++] = values[p];
            }
        }
    }

    // rhs = f_f - K_fd u_d, reading only the prescribed columns.
    sys.rhs.resize(nf);
    for (Index c = 0; c < nf; ++c) sys.rhs[c] = f[sys.free_dofs[c]];
    for (std::size_t k = 0; k < bc.dofs.size(); ++k) {
        const Index j = bc.dofs[k];
        const double u = bc.values[static_cast<Index>(k)];
        if (u == 0.0) continue;
        for (Index p = outer[j]; p < outer[j + 1]; ++p) {
            const Index r = map[inner[p]];
            if (r >= 0) sys.rhs[r] -= values[p] * u;
        }
    }
    return sys;
}

Vector expand(const ReducedSystem& sys, const Vector& u_free, const Dirichlet& bc, Index num_dofs) {
    CG_VERIFY(u_free.size() == sys.free_dofs.size(), "expand: {} free values for {} free DOFs",
              u_free.size(), sys.free_dofs.size());
    CG_VERIFY(sys.free_dofs.size() + static_cast<Index>(bc.dofs.size()) == num_dofs,
              "expand: {} free + {} prescribed DOFs do not make {}", sys.free_dofs.size(),
              bc.dofs.size(), num_dofs);
    Vector u(num_dofs);
    for (Index c = 0; c < sys.free_dofs.size(); ++c) u[sys.free_dofs[c]] = u_free[c];
    for (std::size_t k = 0; k < bc.dofs.size(); ++k)
        u[bc.dofs[k]] = bc.values[static_cast<Index>(k)];
    return u;
}

Vector solve_static(const SparseMatrix& K, const Vector& f, const Dirichlet& bc,
                    const solve::SolverOptions& options, Timings* timings) {
    solve::SpdSolver solver(options);
    return solve_static(K, f, bc, solver, timings);
}

Vector solve_static(const SparseMatrix& K, const Vector& f, const Dirichlet& bc,
                    solve::SpdSolver& solver, Timings* timings) {
    const ReducedSystem sys = reduce(K, f, bc);
    {
        const Phase phase("factorize", timings);
        solver.compute(sys.K);
    }
    const Phase phase("solve", timings);
    return expand(sys, solver.solve(sys.rhs), bc, K.rows());
}

}  // namespace coarsegrain::fem
