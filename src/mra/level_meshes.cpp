#include "coarsegrain/mra/level_meshes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "detail.hpp"

namespace coarsegrain::mra {

namespace detail {

NodeGraph::NodeGraph(const IndexMatrix& elements, Index nodes) {
    std::vector<std::vector<Index>> lists(static_cast<std::size_t>(nodes));
    for (Index e = 0; e < elements.rows(); ++e)
        for (Index a = 0; a < elements.cols(); ++a)
            for (Index b = 0; b < elements.cols(); ++b)
                if (a != b) lists[elements(e, a)].push_back(elements(e, b));
    first.push_back(0);
    for (std::vector<Index>& l : lists) {
        std::sort(l.begin(), l.end());
        l.erase(std::unique(l.begin(), l.end()), l.end());
        neighbours.insert(neighbours.end(), l.begin(), l.end());
        first.push_back(static_cast<Index>(neighbours.size()));
    }
}

std::vector<Index> nodes_within(const NodeGraph& graph, Index centre, int rings,
                                std::vector<char>& mark) {
    std::vector<Index> out{centre};
    mark[static_cast<std::size_t>(centre)] = 1;
    for (std::size_t begin = 0; rings > 0 && begin < out.size(); --rings) {
        const std::size_t end = out.size();
        for (std::size_t a = begin; a < end; ++a)
            for (Index k = graph.first[out[a]]; k < graph.first[out[a] + 1]; ++k) {
                const Index n = graph.neighbours[k];
                if (!mark[static_cast<std::size_t>(n)]) {
                    mark[static_cast<std::size_t>(n)] = 1;
                    out.push_back(n);
                }
            }
        begin = end;
    }
    for (const Index n : out) mark[static_cast<std::size_t>(n)] = 0;
    return out;
}

}  // namespace detail

namespace {

using detail::NodeGraph;

using Triplet = Eigen::Triplet<double, Index>;
using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// Uniform buckets over a point set (about one point per bucket) for nearest-point queries that
/// skip taken points.
class PointBuckets {
  public:
    explicit PointBuckets(const Matrix& points) : m_points(points), m_dim(points.cols()) {
        m_lo = points.colwise().minCoeff().transpose();
        const Eigen::VectorXd extent = points.colwise().maxCoeff().transpose() - m_lo;
        const double volume = std::max(extent.prod(), std::pow(extent.maxCoeff(), m_dim) * 1e-12);
        m_size = std::pow(volume / static_cast<double>(points.rows()), 1.0 / m_dim);
        if (!(m_size > 0)) m_size = 1;
        for (int d = 0; d < m_dim; ++d)
            m_count[d] = std::max(1, static_cast<int>(std::ceil(extent[d] / m_size)));
        m_first.assign(static_cast<std::size_t>(m_count[0]) * m_count[1] * m_count[2] + 1, 0);
        std::vector<Index> bucket(static_cast<std::size_t>(points.rows()));
        for (Index p = 0; p < points.rows(); ++p) {
            bucket[p] = flat(cell_of(points.row(p).transpose()));
            ++m_first[bucket[p] + 1];
        }
        std::partial_sum(m_first.begin(), m_first.end(), m_first.begin());
        m_items.resize(bucket.size());
        std::vector<Index> fill(m_first.begin(), m_first.end() - 1);
        for (Index p = 0; p < points.rows(); ++p) m_items[fill[bucket[p]]++] = p;
    }

    /// The nearest point to x with taken[point] == 0 (ties: the smallest index), -1 if none.
    Index nearest(const Eigen::VectorXd& x, const std::vector<char>& taken) const {
        const std::array<int, 3> c = cell_of(x);
        Index best = -1;
        double best_d2 = std::numeric_limits<double>::infinity();
        const int max_ring = *std::max_element(m_count.begin(), m_count.end());
        for (int r = 0; r <= max_ring; ++r) {
            visit_ring(c, r, [&](Index bucket) {
                for (Index k = m_first[bucket]; k < m_first[bucket + 1]; ++k) {
                    const Index p = m_items[k];
                    if (taken[p]) continue;
                    const double d2 = (m_points.row(p).transpose() - x).squaredNorm();
                    if (d2 < best_d2 || (d2 == best_d2 && p < best)) {
                        best_d2 = d2;
                        best = p;
                    }
                }
            });
            // Points of ring r + 1 are at least r bucket sizes away along some axis.
            if (best >= 0 && std::sqrt(best_d2) <= r * m_size) break;
        }
        return best;
    }

  private:
    std::array<int, 3> cell_of(const Eigen::VectorXd& x) const {
        std::array<int, 3> c{0, 0, 0};
        for (int d = 0; d < m_dim; ++d)
            c[d] = std::clamp(static_cast<int>(std::floor((x[d] - m_lo[d]) / m_size)), 0,
                              m_count[d] - 1);
        return c;
    }
    Index flat(const std::array<int, 3>& c) const {
        return c[0] + m_count[0] * (c[1] + m_count[1] * c[2]);
    }
    template <class F>
    void visit_ring(const std::array<int, 3>& c, int r, F&& f) const {
        std::array<int, 3> lo{}, hi{};
        for (int d = 0; d < 3; ++d) {
            lo[d] = std::max(0, c[d] - r);
            hi[d] = std::min(m_count[d] - 1, c[d] + r);
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) == r)
                        f(flat({x, y, z}));
    }

    const Matrix& m_points;
    int m_dim;
    Eigen::VectorXd m_lo;
    double m_size = 1;
    std::array<int, 3> m_count{1, 1, 1};
    std::vector<Index> m_first, m_items;
};

/// Row r of C^†: see local_refinement_operators. Returns (present fine DOF, value) pairs.
class LeftInverseRow {
  public:
    LeftInverseRow(const SparseMatrix& cols, const RowMajor& rows, const NodeGraph& graph,
                   const std::vector<Index>& fine_local, const std::vector<Index>& coarse_local,
                   int dim)
        : m_cols(cols),
          m_rows(rows),
          m_graph(graph),
          m_fine(fine_local),
          m_coarse(coarse_local),
          m_dim(dim) {}

    /// Largest number of rings of the finer level's graph around the pivot.
    static constexpr int kMaxRings = 8;
    /// Smallest reciprocal condition number (singular values) of a cell's system.
    static constexpr double kMinCellRcond = 1e-3;

    /// Empty if the row has no local left inverse.
    std::vector<std::pair<Index, double>> operator()(Index i, int d, Index pivot) const {
        std::vector<std::pair<Index, double>> out = cell_row(i, d);
        return out.empty() ? ring_row(i, d, pivot) : out;
    }

  private:
    /// Kept coarse nodes (component d) whose refinement is nonzero at fine node j, sorted.
    std::vector<Index> support(Index j, int d) const {
        std::vector<Index> K;
        for (SparseMatrix::InnerIterator it(m_cols, j); it; ++it)
            if (m_coarse[m_dim * it.row() + d] >= 0) K.push_back(static_cast<Index>(it.row()));
        std::sort(K.begin(), K.end());
        return K;
    }

    /// The row on the fewest fine nodes whose refinement columns share one support Σ ∋ i (the
    /// kept vertices of a coarse element, or of one of its faces or edges: the fine nodes in
    /// it): the |Σ| best conditioned (column-pivoted QR of C[Σ, group]), with c solving
    /// C[Σ, nodes] c = e_i; every other row of C vanishes there, so C c = e_i. Among the
    /// supports with a system of reciprocal condition at least kMinCellRcond, the smallest,
    /// then the best conditioned. Empty if none.
    std::vector<std::pair<Index, double>> cell_row(Index i, int d) const {
        std::map<std::vector<Index>, std::vector<Index>> groups;  // Σ -> its fine nodes
        for (RowMajor::InnerIterator it(m_rows, i); it; ++it)
            if (present(static_cast<Index>(it.col()), d))
                groups[support(static_cast<Index>(it.col()), d)].push_back(
                    static_cast<Index>(it.col()));
        std::vector<std::pair<Index, double>> best;
        std::size_t best_size = 0;
        double best_rcond = 0;
        for (const auto& [sigma, nodes] : groups) {
            if (nodes.size() < sigma.size() || (!best.empty() && sigma.size() > best_size))
                continue;
            // The |Σ| best conditioned of the group's columns C[Σ, nodes] (column-pivoted QR).
            const Index n = static_cast<Index>(sigma.size());
            Matrix G(n, static_cast<Index>(nodes.size()));
            for (Index a = 0; a < n; ++a)
                for (Index b = 0; b < G.cols(); ++b) G(a, b) = m_cols.coeff(sigma[a], nodes[b]);
            const Eigen::ColPivHouseholderQR<Matrix> qr(G);
            std::vector<Index> chosen;
            Matrix M(n, n);
            for (Index b = 0; b < n; ++b) {
                chosen.push_back(nodes[qr.colsPermutation().indices()[b]]);
                M.col(b) = G.col(qr.colsPermutation().indices()[b]);
            }
            const Vector sv = Eigen::JacobiSVD<Matrix>(M).singularValues();
            const double rcond = sv[n - 1] / sv[0];
            if (rcond < kMinCellRcond ||
                (!best.empty() && sigma.size() == best_size && rcond <= best_rcond))
                continue;
            Vector target = Vector::Zero(n);
            target[std::lower_bound(sigma.begin(), sigma.end(), i) - sigma.begin()] = 1;
            const Vector c = M.partialPivLu().solve(target);
            if ((M * c - target).lpNorm<Eigen::Infinity>() > 1e-12) continue;
            best.clear();
            for (Index b = 0; b < n; ++b)
                if (c[b] != 0) best.emplace_back(m_fine[m_dim * chosen[b] + d], c[b]);
            best_size = sigma.size();
            best_rcond = rcond;
        }
        return best;
    }

    /// The row as the smallest change of the injection at the pivot on the fewest rings around
    /// it that admit an exact solution; empty if none within kMaxRings.
    std::vector<std::pair<Index, double>> ring_row(Index i, int d, Index pivot) const {
        std::vector<Index> S{pivot}, ring{pivot};  // fine nodes: the region and its last ring
        for (int rings = 0;; ++rings) {
            std::sort(S.begin(), S.end());
            std::vector<Index> K;  // kept coarse nodes (component d) whose rows touch S
            for (const Index j : S)
                for (SparseMatrix::InnerIterator it(m_cols, j); it; ++it)
                    if (m_coarse[m_dim * it.row() + d] >= 0)
                        K.push_back(static_cast<Index>(it.row()));
            std::sort(K.begin(), K.end());
            K.erase(std::unique(K.begin(), K.end()), K.end());
            Matrix M = Matrix::Zero(static_cast<Index>(K.size()), static_cast<Index>(S.size()));
            for (Index b = 0; b < static_cast<Index>(S.size()); ++b)
                for (SparseMatrix::InnerIterator it(m_cols, S[b]); it; ++it) {
                    const auto a = std::lower_bound(K.begin(), K.end(), it.row());
                    if (a != K.end() && *a == it.row()) M(a - K.begin(), b) = it.value();
                }
            const auto own = std::lower_bound(K.begin(), K.end(), i);
            if (own != K.end() && *own == i) {
                const Index p = std::lower_bound(S.begin(), S.end(), pivot) - S.begin();
                Vector target = Vector::Zero(M.rows());
                target[own - K.begin()] = 1;
                Vector c = Vector::Zero(M.cols());
                c[p] = 1;
                const Vector defect = target - M * c;
                if (defect.lpNorm<Eigen::Infinity>() > 0)
                    c += Eigen::CompleteOrthogonalDecomposition<Matrix>(M).solve(defect);
                // An exact solution leaves the round-off of a dense solve with O(1) entries.
                if ((M * c - target).lpNorm<Eigen::Infinity>() <= 1e-12) {
                    std::vector<std::pair<Index, double>> out;
                    for (Index b = 0; b < c.size(); ++b)
                        if (c[b] != 0) out.emplace_back(m_fine[m_dim * S[b] + d], c[b]);
                    return out;
                }
            }
            // The next ring: present neighbours of the last one not yet in S.
            std::vector<Index> next;
            for (const Index j : ring)
                for (Index k = m_graph.first[j]; k < m_graph.first[j + 1]; ++k) {
                    const Index n = m_graph.neighbours[k];
                    if (present(n, d) && !std::binary_search(S.begin(), S.end(), n))
                        next.push_back(n);
                }
            std::sort(next.begin(), next.end());
            next.erase(std::unique(next.begin(), next.end()), next.end());
            if (rings >= kMaxRings || next.empty()) return {};
            S.insert(S.end(), next.begin(), next.end());
            ring = std::move(next);
        }
    }

    bool present(Index node, int d) const { return m_fine[m_dim * node + d] >= 0; }

    const SparseMatrix& m_cols;
    const RowMajor& m_rows;
    const NodeGraph& m_graph;
    const std::vector<Index>& m_fine;
    const std::vector<Index>& m_coarse;
    int m_dim;
};

/// Kernel pivots P, one fine DOF per row of C^† (rows: its (DOF, value) entries), such that
/// C^†[:, P] is nonsingular, which is what makes W = S_N (I - C^T C^†) a basis of ker C (a
/// y != 0 with C^†[:, P]^T y = 0 would give the kernel vector C^{†,T} y, zero on P, that the
/// rows of W miss). Rows are served in the order of their largest |C^†(r, j) C(r, j)|
/// (candidates[r]: (-|product|, j), sorted) and eliminated against the rows served before, as
/// an LU factorization with threshold partial pivoting: a row takes its first candidate not yet
/// taken whose reduced entry is at least kPreferred of its largest, else its largest. On
/// nested meshes (C^† the injection) this gives P = the pivots; elsewhere the candidates keep
/// C^†[:, P] C[:, P]^T diagonally dominant where the rows are near injections. The elimination
/// only selects (W is formed exactly from P), so reduced entries below kDrop of the row's
/// largest are dropped to bound the fill.
/// Returns each row's pivot DOF, -1 where its reduced row vanished (a row dependent on others).
std::vector<Index> kernel_pivots(
    const std::vector<std::vector<std::pair<Index, double>>>& rows,
    const std::vector<std::vector<std::pair<double, Index>>>& candidates, Index nf) {
    constexpr double kPreferred = 0.1, kDrop = 1e-10;
    const Index nk = static_cast<Index>(rows.size());
    std::vector<Index> order(static_cast<std::size_t>(nk));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
        const double sa = candidates[a].empty() ? 0 : candidates[a][0].first;
        const double sb = candidates[b].empty() ? 0 : candidates[b][0].first;
        return sa < sb;
    });
    std::vector<Index> pivot(static_cast<std::size_t>(nk), -1);
    std::vector<Index> served(static_cast<std::size_t>(nf), -1);  // column -> serving step
    std::vector<std::vector<std::pair<Index, double>>> reduced;   // per step, its pivot first
    std::vector<double> work(static_cast<std::size_t>(nf), 0.0);
    std::vector<char> touched(static_cast<std::size_t>(nf), 0);
    for (const Index r : order) {
        std::vector<Index> cols;
        std::priority_queue<Index, std::vector<Index>, std::greater<>> steps;
        const auto add = [&](Index c, double v) {
            if (!touched[c]) {
                touched[c] = 1;
                cols.push_back(c);
                if (served[c] >= 0) steps.push(served[c]);
            }
            work[c] += v;
        };
        for (const auto& [c, v] : rows[r]) add(c, v);
        double scale = 0;
        for (const auto& [c, v] : rows[r]) scale = std::max(scale, std::abs(v));
        // Steps in increasing order: a reduced row vanishes at the pivots of earlier steps.
        while (!steps.empty()) {
            const Index step = steps.top();
            steps.pop();
            const auto& u = reduced[static_cast<std::size_t>(step)];
            const double factor = work[u[0].first] / u[0].second;
            if (factor == 0) continue;
            for (const auto& [c, v] : u) add(c, -factor * v);
            work[u[0].first] = 0;
        }
        double largest = 0;
        for (const Index c : cols)
            if (served[c] < 0) largest = std::max(largest, std::abs(work[c]));
        Index chosen = -1;
        if (largest > kDrop * scale) {
            for (const auto& [product, j] : candidates[r])
                if (served[j] < 0 && std::abs(work[j]) >= kPreferred * largest) {
                    chosen = j;
                    break;
                }
            for (const Index c : cols)
                if (chosen < 0 && served[c] < 0 && std::abs(work[c]) == largest) chosen = c;
        }
        if (chosen >= 0) {
            std::vector<std::pair<Index, double>> u{{chosen, work[chosen]}};
            for (const Index c : cols)
                if (c != chosen && served[c] < 0 && std::abs(work[c]) > kDrop * largest)
                    u.emplace_back(c, work[c]);
            served[chosen] = static_cast<Index>(reduced.size());
            reduced.push_back(std::move(u));
            pivot[r] = chosen;
        }
        for (const Index c : cols) {
            work[c] = 0;
            touched[c] = 0;
        }
    }
    return pivot;
}

}  // namespace

SparseMatrix linear_refinement(const mesh::Mesh& coarse, const Matrix& fine_positions) {
    const int dim = coarse.dim();
    CG_VERIFY(mesh::is_simplex(coarse.type),
              "mra: level meshes must be simplicial (triangles or tetrahedra), got {}",
              mesh::element_name(coarse.type));
    CG_VERIFY(fine_positions.cols() == dim, "mra: fine positions in {}D for a {}D level mesh",
              fine_positions.cols(), dim);
    const mesh::PointLocator locator(coarse);
    const Index nf = static_cast<Index>(fine_positions.rows());
    std::vector<Index> element(static_cast<std::size_t>(nf));
    Matrix lambda(nf, dim + 1);
#pragma omp parallel for schedule(static) if (nf >= 4096)
    for (Index j = 0; j < nf; ++j) {
        const Eigen::VectorXd x = fine_positions.row(j).transpose();
        element[j] = locator.locate_nearest(x).element;
        lambda.row(j) = mesh::barycentric_coordinates(coarse, element[j], x).transpose();
    }
    std::vector<Triplet> t;
    t.reserve(static_cast<std::size_t>(nf) * (dim + 1));
    for (Index j = 0; j < nf; ++j)
        for (int a = 0; a <= dim; ++a)
            if (lambda(j, a) != 0) t.emplace_back(coarse.elements(element[j], a), j, lambda(j, a));
    SparseMatrix C(coarse.num_nodes(), nf);
    C.setFromTriplets(t.begin(), t.end());
    return C;
}

SparseMatrix selection_refinement(const std::vector<Index>& pivots, Index fine_nodes) {
    std::vector<Triplet> t;
    for (std::size_t i = 0; i < pivots.size(); ++i)
        t.emplace_back(static_cast<Index>(i), pivots[i], 1.0);
    SparseMatrix C(static_cast<Index>(pivots.size()), fine_nodes);
    C.setFromTriplets(t.begin(), t.end());
    return C;
}

std::vector<Index> pivot_nodes(const Matrix& coarse_positions, const Matrix& fine_positions) {
    const Index nc = static_cast<Index>(coarse_positions.rows());
    const Index nf = static_cast<Index>(fine_positions.rows());
    CG_VERIFY(coarse_positions.cols() == fine_positions.cols(),
              "mra: level meshes of different dimensions ({} and {})", coarse_positions.cols(),
              fine_positions.cols());
    CG_VERIFY(nf >= nc, "mra: a coarser level has more nodes ({}) than the finer one ({})", nc, nf);
    const PointBuckets buckets(fine_positions);
    const std::vector<char> none(static_cast<std::size_t>(nf), 0);
    std::vector<Index> nearest(static_cast<std::size_t>(nc));
    std::vector<double> distance(static_cast<std::size_t>(nc));
#pragma omp parallel for schedule(static) if (nc >= 4096)
    for (Index i = 0; i < nc; ++i) {
        const Eigen::VectorXd x = coarse_positions.row(i).transpose();
        nearest[i] = buckets.nearest(x, none);
        distance[i] = (fine_positions.row(nearest[i]).transpose() - x).norm();
    }
    std::vector<Index> order(static_cast<std::size_t>(nc));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](Index a, Index b) { return distance[a] < distance[b]; });
    std::vector<char> taken(static_cast<std::size_t>(nf), 0);
    std::vector<Index> pivots(static_cast<std::size_t>(nc));
    for (const Index i : order) {
        Index p = nearest[i];
        if (taken[p]) p = buckets.nearest(coarse_positions.row(i).transpose(), taken);
        taken[p] = 1;
        pivots[i] = p;
    }
    return pivots;
}

RefinementOperators local_refinement_operators(const SparseMatrix& C_node,
                                               const std::vector<Index>& pivots,
                                               const IndexMatrix& fine_elements, int dim,
                                               const IndexVector& fine_dofs,
                                               bool keep_boundary_rows) {
    const Index nc = C_node.rows();
    const Index nf_all = dim * C_node.cols();
    CG_VERIFY(static_cast<Index>(pivots.size()) == nc,
              "local_refinement_operators: {} pivots for {} coarse nodes", pivots.size(), nc);
    std::vector<Index> fine_local(static_cast<std::size_t>(nf_all), -1);
    for (Index k = 0; k < fine_dofs.size(); ++k) {
        const Index d = fine_dofs[k];
        CG_VERIFY(d >= 0 && d < nf_all && (k == 0 || fine_dofs[k - 1] < d),
                  "local_refinement_operators: fine DOFs must be sorted, unique and in 0..{}",
                  nf_all - 1);
        fine_local[d] = k;
    }
    std::vector<char> is_pivot(static_cast<std::size_t>(C_node.cols()), 0);
    for (const Index p : pivots) {
        CG_VERIFY(p >= 0 && p < C_node.cols() && !is_pivot[p],
                  "local_refinement_operators: pivot {} repeated or out of 0..{}", p,
                  C_node.cols() - 1);
        is_pivot[p] = 1;
    }

    const RowMajor rows = C_node;
    // Boundary rows (kept ones): per present fine DOF, how many rows without their pivot DOF
    // weight it (positively, at a node that is no pivot).
    const auto own_pivot = [&](Index i, int d) { return fine_local[dim * pivots[i] + d]; };
    std::vector<int> boundary_weights(static_cast<std::size_t>(fine_dofs.size()), 0);
    for (Index i = 0; keep_boundary_rows && i < nc; ++i)
        for (int d = 0; d < dim; ++d) {
            if (own_pivot(i, d) >= 0) continue;
            for (RowMajor::InnerIterator it(rows, i); it; ++it) {
                const Index l = fine_local[dim * it.col() + d];
                if (l >= 0 && it.value() > 0 && !is_pivot[it.col()]) ++boundary_weights[l];
            }
        }
    // Kept coarse DOFs and their pivot DOFs (indices into fine_dofs).
    RefinementOperators ops;
    std::vector<Index> kept, dropped, pivot, coarse_local(static_cast<std::size_t>(dim * nc), -1);
    // A row that vanishes on the present DOFs (its hat function reaches only fixed fine nodes)
    // measures nothing: it is dropped whatever its pivot.
    const auto measures = [&](Index i, int d) {
        for (RowMajor::InnerIterator it(rows, i); it; ++it)
            if (fine_local[dim * it.col() + d] >= 0) return true;
        return false;
    };
    for (Index i = 0; i < nc; ++i)
        for (int d = 0; d < dim; ++d) {
            Index p = measures(i, d) ? own_pivot(i, d) : -1;
            double best = 0;
            for (RowMajor::InnerIterator it(rows, i); p < 0 && keep_boundary_rows && it; ++it) {
                const Index l = fine_local[dim * it.col() + d];
                if (l >= 0 && !is_pivot[it.col()] && boundary_weights[l] == 1 &&
                    it.value() > best) {
                    best = it.value();  // columns ascend: ties keep the smallest index
                    p = l;
                }
            }
            if (p < 0) {
                dropped.push_back(dim * i + d);
                continue;
            }
            coarse_local[dim * i + d] = static_cast<Index>(kept.size());
            kept.push_back(dim * i + d);
            pivot.push_back(p);
        }
    const Index nf = static_cast<Index>(fine_dofs.size());
    const NodeGraph graph(fine_elements, C_node.cols());
    const LeftInverseRow left_inverse(C_node, rows, graph, fine_local, coarse_local, dim);
    const auto dagger_row = [&](std::size_t r) {
        return left_inverse(kept[r] / dim, static_cast<int>(kept[r] % dim),
                            fine_dofs[pivot[r]] / dim);
    };
    std::vector<std::vector<std::pair<Index, double>>> dagger(kept.size());
#pragma omp parallel for schedule(dynamic, 64) if (kept.size() >= 4096)
    for (std::size_t r = 0; r < kept.size(); ++r) dagger[r] = dagger_row(r);
    // A row without a local left inverse depends, near its pivot, on the other rows (two coarse
    // nodes whose hat functions reach the same single fine node, or levels too different there):
    // such rows are dropped one at a time, the weakest (smallest norm on the present DOFs) first,
    // and the others without one solved again. The rows solved with a dropped row's constraint
    // stay left-inverse rows of the remaining ones.
    const auto weight = [&](std::size_t r) {
        double w = 0;
        for (RowMajor::InnerIterator it(rows, kept[r] / dim); it; ++it)
            if (fine_local[dim * it.col() + kept[r] % dim] >= 0) w += it.value() * it.value();
        return w;
    };
    std::vector<std::size_t> unsolved;
    for (std::size_t r = 0; r < kept.size(); ++r)
        if (dagger[r].empty()) unsolved.push_back(r);
    std::vector<char> drop(kept.size(), 0);
    while (!unsolved.empty()) {
        const auto weakest =
            std::min_element(unsolved.begin(), unsolved.end(),
                             [&](std::size_t a, std::size_t b) { return weight(a) < weight(b); });
        drop[*weakest] = 1;
        coarse_local[static_cast<std::size_t>(kept[*weakest])] = -1;
        unsolved.erase(weakest);
        std::vector<std::size_t> still;
        for (const std::size_t r : unsolved)
            if ((dagger[r] = dagger_row(r)).empty()) still.push_back(r);
        unsolved = std::move(still);
    }
    {
        std::size_t n = 0;
        for (std::size_t r = 0; r < kept.size(); ++r) {
            if (drop[r]) {
                dropped.push_back(kept[r]);
                continue;
            }
            if (n != r) {
                kept[n] = kept[r];
                pivot[n] = pivot[r];
                dagger[n] = std::move(dagger[r]);
            }
            coarse_local[static_cast<std::size_t>(kept[n])] = static_cast<Index>(n);
            ++n;
        }
        kept.resize(n);
        pivot.resize(n);
        dagger.resize(n);
        std::sort(dropped.begin(), dropped.end());
    }
    const Index nk = static_cast<Index>(kept.size());
    CG_VERIFY(nk > 0,
              "mra: no DOF of the coarser level has a local left inverse of the refinement");
    ops.coarse_dofs = Eigen::Map<const IndexVector>(kept.data(), nk);
    ops.dropped_dofs =
        Eigen::Map<const IndexVector>(dropped.data(), static_cast<Index>(dropped.size()));

    std::vector<Triplet> t;
    for (Index r = 0; r < nk; ++r) {
        const Index i = kept[r] / dim;
        const int d = kept[r] % dim;
        for (RowMajor::InnerIterator it(rows, i); it; ++it) {
            const Index l = fine_local[dim * it.col() + d];
            if (l >= 0) t.emplace_back(r, l, it.value());
        }
    }
    ops.C.resize(nk, nf);
    ops.C.setFromTriplets(t.begin(), t.end());
    t.clear();
    for (Index r = 0; r < nk; ++r)
        for (const auto& [l, v] : dagger[r]) t.emplace_back(r, l, v);
    ops.C_dagger.resize(nk, nf);
    ops.C_dagger.setFromTriplets(t.begin(), t.end());

    // W = S_N (I - C^T C^†) on the fine DOFs N outside a set P of one DOF per row (the kernel
    // pivots, kernel_pivots).
    std::vector<std::vector<std::pair<double, Index>>> candidates(static_cast<std::size_t>(nk));
    {
        const RowMajor C_rows = ops.C;
        for (Index r = 0; r < nk; ++r) {
            for (RowMajor::InnerIterator it(C_rows, r); it; ++it) {
                const auto at = std::find_if(dagger[r].begin(), dagger[r].end(),
                                             [&](const auto& e) { return e.first == it.col(); });
                if (at != dagger[r].end())
                    candidates[r].emplace_back(-std::abs(at->second * it.value()),
                                               static_cast<Index>(it.col()));
            }
            std::sort(candidates[r].begin(), candidates[r].end());
        }
    }
    const std::vector<Index> kernel_pivot = kernel_pivots(dagger, candidates, nf);
    std::vector<char> is_kernel_pivot(static_cast<std::size_t>(nf), 0);
    for (Index r = 0; r < nk; ++r) {
        CG_VERIFY(kernel_pivot[r] >= 0,
                  "mra: no kernel pivot for DOF {} of the coarser level: the level meshes are too "
                  "different near it",
                  kept[r]);
        is_kernel_pivot[kernel_pivot[r]] = 1;
    }
    t.clear();
    Index wavelets = 0;
    for (Index l = 0; l < nf; ++l)
        if (!is_kernel_pivot[l]) t.emplace_back(wavelets++, l, 1.0);
    SparseMatrix S_N(wavelets, nf);
    S_N.setFromTriplets(t.begin(), t.end());
    const SparseMatrix SCt = S_N * SparseMatrix(ops.C.transpose());
    ops.W = S_N - SparseMatrix(SCt * ops.C_dagger);
    ops.W.prune(0.0);
    ops.W.makeCompressed();
    return ops;
}

mesh::Mesh subdivide(const mesh::Mesh& coarse) {
    CG_VERIFY(mesh::is_simplex(coarse.type),
              "mra: subdivision needs a simplicial mesh (triangles or tetrahedra), got {}",
              mesh::element_name(coarse.type));
    const int dim = coarse.dim();
    const int corners = dim + 1;
    // One new node per edge, numbered after the coarse nodes in order of first appearance.
    std::map<std::pair<Index, Index>, Index> edge_node;
    std::vector<std::pair<Index, Index>> edges;
    const auto midpoint = [&](Index a, Index b) {
        const auto key = std::minmax(a, b);
        const auto [it, added] =
            edge_node.emplace(key, coarse.num_nodes() + static_cast<Index>(edges.size()));
        if (added) edges.push_back(key);
        return it->second;
    };
    const auto position = [&](Index node) -> Eigen::RowVectorXd {
        if (node < coarse.num_nodes()) return coarse.rest_positions.row(node);
        const auto& [a, b] = edges[static_cast<std::size_t>(node - coarse.num_nodes())];
        return 0.5 * (coarse.rest_positions.row(a) + coarse.rest_positions.row(b));
    };
    std::vector<std::array<Index, 4>> children;
    std::vector<Index> parent;
    for (Index e = 0; e < coarse.num_elements(); ++e) {
        std::array<Index, 4> v{};
        for (int a = 0; a < corners; ++a) v[a] = coarse.elements(e, a);
        std::array<std::array<Index, 4>, 4> m{};  // m[a][b]: midpoint of edge (a, b)
        for (int a = 0; a < corners; ++a)
            for (int b = a + 1; b < corners; ++b) m[a][b] = m[b][a] = midpoint(v[a], v[b]);
        if (dim == 2) {
            children.push_back({v[0], m[0][1], m[0][2], 0});
            children.push_back({m[0][1], v[1], m[1][2], 0});
            children.push_back({m[0][2], m[1][2], v[2], 0});
            children.push_back({m[0][1], m[1][2], m[0][2], 0});
            parent.insert(parent.end(), 4, e);
            continue;
        }
        for (int a = 0; a < 4; ++a) {  // the corner tetrahedra
            std::array<Index, 4> c{};
            for (int b = 0; b < 4; ++b) c[b] = a == b ? v[a] : m[a][b];
            children.push_back(c);
        }
        // The octahedron of the six midpoints, cut along its shortest diagonal: the midpoints of
        // opposite edges (0,1)-(2,3), (0,2)-(1,3), (0,3)-(1,2).
        const std::array<std::array<int, 4>, 3> diagonals{
            {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}}};
        double shortest = std::numeric_limits<double>::infinity();
        int best = 0;
        for (int k = 0; k < 3; ++k) {
            const auto& g = diagonals[k];
            const double length = (position(m[g[0]][g[1]]) - position(m[g[2]][g[3]])).squaredNorm();
            if (length < shortest) {
                shortest = length;
                best = k;
            }
        }
        const auto& g = diagonals[best];
        const Index top = m[g[0]][g[1]], bottom = m[g[2]][g[3]];
        // The four other midpoints in cyclic order: consecutive ones share a corner.
        const std::array<Index, 4> ring{m[g[0]][g[2]], m[g[0]][g[3]], m[g[1]][g[3]], m[g[1]][g[2]]};
        for (int a = 0; a < 4; ++a) children.push_back({top, bottom, ring[a], ring[(a + 1) % 4]});
        parent.insert(parent.end(), 8, e);
    }
    mesh::Mesh fine;
    fine.type = coarse.type;
    fine.rest_positions.resize(coarse.num_nodes() + static_cast<Index>(edges.size()), dim);
    for (Index v = 0; v < fine.num_nodes(); ++v) fine.rest_positions.row(v) = position(v);
    fine.elements.resize(static_cast<Index>(children.size()), corners);
    fine.material_ids.resize(static_cast<Index>(children.size()));
    for (Index e = 0; e < fine.num_elements(); ++e) {
        for (int a = 0; a < corners; ++a) fine.elements(e, a) = children[e][a];
        fine.material_ids[e] = coarse.material_ids.size() > 0 ? coarse.material_ids[parent[e]] : 0;
        if (mesh::element_measure(fine, e) < 0) std::swap(fine.elements(e, 0), fine.elements(e, 1));
    }
    return fine;
}

}  // namespace coarsegrain::mra
