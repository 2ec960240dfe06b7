#include "coarsegrain/mra/refinement.hpp"

#include <algorithm>
#include <cmath>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra {

namespace {

using Triplet = Eigen::Triplet<double, Index>;

}  // namespace

Eigen::Vector3i node_counts(const Eigen::Vector3i& cells, int dim) {
    return {cells[0] + 1, cells[1] + 1, dim == 3 ? cells[2] + 1 : 1};
}

Index grid_nodes(const Eigen::Vector3i& cells, int dim) {
    const Eigen::Vector3i n = node_counts(cells, dim);
    return static_cast<Index>(n[0]) * n[1] * n[2];
}

Eigen::Vector3i node_coordinates(Index v, const Eigen::Vector3i& cells, int dim) {
    const Eigen::Vector3i n = node_counts(cells, dim);
    return {v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
}

std::vector<Index> coincident_nodes(const Eigen::Vector3i& coarse_cells, int dim) {
    const Eigen::Vector3i fine_cells = 2 * coarse_cells;
    const Eigen::Vector3i nf = node_counts(fine_cells, dim);
    const Index n = grid_nodes(coarse_cells, dim);
    std::vector<Index> out(static_cast<std::size_t>(n));
    for (Index v = 0; v < n; ++v) {
        const Eigen::Vector3i c = 2 * node_coordinates(v, coarse_cells, dim);
        out[static_cast<std::size_t>(v)] = c[0] + nf[0] * (c[1] + nf[1] * c[2]);
    }
    return out;
}

SparseMatrix canonical_refinement(const Eigen::Vector3i& coarse_cells, int dim,
                                  Refinement refinement) {
    const Eigen::Vector3i fine_cells = 2 * coarse_cells;
    const Eigen::Vector3i nf = node_counts(fine_cells, dim);
    const Index nc = grid_nodes(coarse_cells, dim);
    const int reach = refinement == Refinement::Linear ? 1 : 0;
    std::vector<Triplet> t;
    t.reserve(static_cast<std::size_t>(nc) * (refinement == Refinement::Linear ? 27 : 1));
    for (Index v = 0; v < nc; ++v) {
        const Eigen::Vector3i c = 2 * node_coordinates(v, coarse_cells, dim);
        const int rz = dim == 3 ? reach : 0;
        for (int dz = -rz; dz <= rz; ++dz)
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dx = -reach; dx <= reach; ++dx) {
                    const Eigen::Vector3i f = c + Eigen::Vector3i(dx, dy, dz);
                    if ((f.array() < 0).any() || (f.array() >= nf.array()).any()) continue;
                    const double w = std::ldexp(1.0, -(std::abs(dx) + std::abs(dy) + std::abs(dz)));
                    t.emplace_back(v, f[0] + nf[0] * (f[1] + nf[1] * f[2]), w);
                }
    }
    SparseMatrix C(nc, grid_nodes(fine_cells, dim));
    C.setFromTriplets(t.begin(), t.end());
    return C;
}

SparseMatrix expand_to_dofs(const SparseMatrix& S, int dim) {
    std::vector<Triplet> t;
    t.reserve(static_cast<std::size_t>(S.nonZeros()) * dim);
    for (Index j = 0; j < S.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(S, j); it; ++it)
            for (int d = 0; d < dim; ++d)
                t.emplace_back(dim * static_cast<Index>(it.row()) + d, dim * j + d, it.value());
    SparseMatrix out(dim * S.rows(), dim * S.cols());
    out.setFromTriplets(t.begin(), t.end());
    return out;
}

Vector stiffness_weights(const SparseMatrix& K, const IndexMatrix& elements, int dim) {
    const Index nodes = K.rows() / dim;
    CG_VERIFY(K.rows() == dim * nodes && K.cols() == K.rows(),
              "mra: stiffness weights need a square stiffness of dim * #nodes rows, got {}x{}",
              K.rows(), K.cols());
    Vector count = Vector::Zero(nodes);
    for (Index e = 0; e < elements.rows(); ++e)
        for (Index a = 0; a < elements.cols(); ++a) count[elements(e, a)] += 1;
    const Vector diagonal = K.diagonal();
    Vector w(nodes);
    for (Index j = 0; j < nodes; ++j) {
        w[j] = diagonal.segment(dim * j, dim).sum() / (dim * count[j]);
        CG_VERIFY(std::isfinite(w[j]) && w[j] > 0,
                  "mra: node {} has no positive stiffness weight ({}; an unused node?)", j, w[j]);
    }
    return w;
}

SparseMatrix weighted_refinement(SparseMatrix C_node, const std::vector<Index>& coincident,
                                 const Vector& w) {
    CG_VERIFY(C_node.cols() == w.size() && C_node.rows() == static_cast<Index>(coincident.size()),
              "mra: weighted refinement of a {}x{} refinement with {} weights and {} coincident "
              "nodes",
              C_node.rows(), C_node.cols(), w.size(), coincident.size());
    for (Index j = 0; j < C_node.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(C_node, j); it; ++it)
            it.valueRef() *= w[j] / w[coincident[static_cast<std::size_t>(it.row())]];
    return C_node;
}

RefinementOperators refinement_operators(const SparseMatrix& C_node,
                                         const std::vector<Index>& coincident, int dim,
                                         const IndexVector& fine_dofs, bool keep_boundary_rows) {
    const Index nc = static_cast<Index>(C_node.rows());
    const Index nf_all = dim * static_cast<Index>(C_node.cols());
    CG_VERIFY(static_cast<Index>(coincident.size()) == nc,
              "refinement_operators: {} coincident nodes for {} coarse nodes", coincident.size(),
              nc);
    // Local index of each present fine DOF, -1 if absent.
    std::vector<Index> fine_local(static_cast<std::size_t>(nf_all), -1);
    for (Index k = 0; k < fine_dofs.size(); ++k) {
        const Index d = fine_dofs[k];
        CG_VERIFY(d >= 0 && d < nf_all && (k == 0 || fine_dofs[k - 1] < d),
                  "refinement_operators: fine DOFs must be sorted, unique and in 0..{}",
                  nf_all - 1);
        fine_local[static_cast<std::size_t>(d)] = k;
    }
    const Eigen::SparseMatrix<double, Eigen::RowMajor, Index> rows = C_node;
    std::vector<char> is_coincident(static_cast<std::size_t>(C_node.cols()), 0);
    for (const Index j : coincident) is_coincident[static_cast<std::size_t>(j)] = 1;

    // Rows without their coincident DOF: count, per fine DOF, how many of them weight it.
    std::vector<int> boundary_weight_count(static_cast<std::size_t>(fine_dofs.size()), 0);
    const auto present = [&](Index node, int d) {
        return fine_local[static_cast<std::size_t>(dim * node + d)];
    };
    if (keep_boundary_rows)
        for (Index i = 0; i < nc; ++i)
            for (int d = 0; d < dim; ++d) {
                if (present(coincident[static_cast<std::size_t>(i)], d) >= 0) continue;
                for (decltype(rows)::InnerIterator it(rows, i); it; ++it) {
                    const Index l = present(static_cast<Index>(it.col()), d);
                    if (l >= 0) ++boundary_weight_count[static_cast<std::size_t>(l)];
                }
            }

    // Pivot of every kept coarse DOF.
    RefinementOperators ops;
    std::vector<Index> kept, dropped, pivot;
    std::vector<char> from_coincident;
    for (Index i = 0; i < nc; ++i)
        for (int d = 0; d < dim; ++d) {
            const Index own = present(coincident[static_cast<std::size_t>(i)], d);
            Index p = own;
            if (p < 0 && keep_boundary_rows) {
                double best = 0;
                for (decltype(rows)::InnerIterator it(rows, i); it; ++it) {
                    const Index j = static_cast<Index>(it.col());
                    const Index l = present(j, d);
                    if (l < 0 || is_coincident[static_cast<std::size_t>(j)] ||
                        boundary_weight_count[static_cast<std::size_t>(l)] != 1)
                        continue;
                    if (it.value() > best) {  // columns ascend: ties keep the smallest index
                        best = it.value();
                        p = l;
                    }
                }
            }
            if (p < 0) {
                dropped.push_back(dim * i + d);
                continue;
            }
            kept.push_back(dim * i + d);
            pivot.push_back(p);
            from_coincident.push_back(own >= 0);
        }
    const Index nk = static_cast<Index>(kept.size());
    ops.coarse_dofs = Eigen::Map<const IndexVector>(kept.data(), nk);
    ops.dropped_dofs =
        Eigen::Map<const IndexVector>(dropped.data(), static_cast<Index>(dropped.size()));

    // C restricted to kept rows and present columns.
    std::vector<Triplet> t;
    for (Index r = 0; r < nk; ++r) {
        const Index i = kept[static_cast<std::size_t>(r)] / dim;
        const int d = kept[static_cast<std::size_t>(r)] % dim;
        for (decltype(rows)::InnerIterator it(rows, i); it; ++it) {
            const Index l = present(static_cast<Index>(it.col()), d);
            if (l >= 0) t.emplace_back(r, l, it.value());
        }
    }
    const Index nf = static_cast<Index>(fine_dofs.size());
    ops.C.resize(nk, nf);
    ops.C.setFromTriplets(t.begin(), t.end());

    // C_dagger: injection on rows with a coincident pivot; row r without one is
    // (e_{p_r} - sum_s E_{s,r} e_{p_s}) / F_r over the coincident-pivot rows s, with
    // F_r = C(r, p_r) and E_{s,r} = C(s, p_r) (the rows weighting the pivot column p_r).
    std::vector<Index> row_of_pivot(static_cast<std::size_t>(nf), -1);
    for (Index r = 0; r < nk; ++r) row_of_pivot[static_cast<std::size_t>(pivot[r])] = r;
    t.clear();
    for (Index r = 0; r < nk; ++r) {
        if (from_coincident[static_cast<std::size_t>(r)]) {
            t.emplace_back(r, pivot[static_cast<std::size_t>(r)], 1.0);
            continue;
        }
        const Index p = pivot[static_cast<std::size_t>(r)];
        double F = 0;
        std::vector<std::pair<Index, double>> E;
        for (SparseMatrix::InnerIterator it(ops.C, p); it; ++it) {
            const Index s = static_cast<Index>(it.row());
            if (s == r)
                F = it.value();
            else {
                CG_ASSERT(from_coincident[static_cast<std::size_t>(s)], "pivot not exclusive");
                E.emplace_back(s, it.value());
            }
        }
        t.emplace_back(r, p, 1.0 / F);
        for (const auto& [s, e] : E) t.emplace_back(r, pivot[static_cast<std::size_t>(s)], -e / F);
    }
    ops.C_dagger.resize(nk, nf);
    ops.C_dagger.setFromTriplets(t.begin(), t.end());

    // W = S (I - C^T C_dagger) over the non-pivot fine DOFs.
    std::vector<Index> non_pivot;
    for (Index l = 0; l < nf; ++l)
        if (row_of_pivot[static_cast<std::size_t>(l)] < 0) non_pivot.push_back(l);
    const Index nw = static_cast<Index>(non_pivot.size());
    SparseMatrix S(nw, nf);
    t.clear();
    for (Index w = 0; w < nw; ++w) t.emplace_back(w, non_pivot[static_cast<std::size_t>(w)], 1.0);
    S.setFromTriplets(t.begin(), t.end());
    const SparseMatrix SCt = S * SparseMatrix(ops.C.transpose());
    ops.W = S - SparseMatrix(SCt * ops.C_dagger);
    ops.W.prune(0.0);
    ops.W.makeCompressed();
    return ops;
}

}  // namespace coarsegrain::mra
