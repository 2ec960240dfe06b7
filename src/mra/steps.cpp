#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <utility>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/hash.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/mra/refinement.hpp"
#include "coarsegrain/solve/spd_solver.hpp"
#include "detail.hpp"
#include "products.hpp"

namespace coarsegrain::mra::detail {

namespace {

using Triplet = Eigen::Triplet<double, Index>;
using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// Columns of R solved per block in global_adapted_refinement: a block of the dense right-hand side
/// is #wavelets x 64 doubles.
constexpr Index kGlobalBlock = 64;

/// Loops shorter than these run on one thread: waking a second thread costs ~20 ms on a loaded
/// machine (measured: an 18x18 factorization took 24 ms with 2 threads, 0.1 ms with one).
/// kMinParallelNodes counts regions of localized solves.
constexpr Index kMinParallelNodes = 64;
constexpr Index kMinParallelColumns = 4096;

/// Local systems up to kDenseLocalLimit unknowns, or up to kDenseLocalMax with more than
/// kDenseLocalDensity of their entries nonzero, are factorized densely (LAPACK), others by
/// CHOLMOD's supernodal Cholesky (one BLAS thread per OpenMP thread), in a fill-reducing order
/// of the node graph (solve::fill_reducing_order) the region builds its system in (no permuted
/// copies inside CHOLMOD), order and symbolic analysis reused across regions of the same pattern
/// (solve_region). The localized solves of 24^3 cells at rho = 2 fine rings (regions of 400-1000
/// unknowns) take 3.8 s against 10.5 s with Eigen's simplicial LLT from 400 unknowns; the
/// dense bounds' measurements are in docs/performance.md.
constexpr Index kDenseLocalLimit = 100;
constexpr Index kDenseLocalMax = 4000;
constexpr double kDenseLocalDensity = 0.25;

/// Options of the local CHOLMOD factorizations: in the order the caller applied (keep_order),
/// without input checks: the systems are principal submatrices of the symmetrized B^k, made of
/// the fine stiffness that build_hierarchy checked.
solve::SolverOptions local_options() {
    solve::SolverOptions options;
    options.keep_order = true;
    options.check_input = false;
    return options;
}

/// A fill-reducing order of a region's local system B[S, S] (postordered), kept for the
/// next regions of the same pattern: n, nnz and hash of its (row, column) pairs in S's order.
struct LocalOrder {
    Index n = -1;
    Index nnz = -1;
    std::uint64_t hash = 0;
    std::vector<Index> perm;      ///< position k of the ordered system holds S[perm[k]]
    std::vector<Index> position;  ///< inverse of perm
};

/// Orders kept per thread and growth step, the oldest replaced first: regions of a few patterns
/// taken in turn reuse theirs. On the 80x20x20 accordion's finest step at 10 rings, 180 boxes
/// in 81 patterns (9 per position along the beam, boxes of one shape in up to 4: mirror images,
/// with coarse nodes at other offsets from their faces) take 90 orders (METIS and AMD each),
/// against 180 keeping the last order alone (the step: 75 s -> 62 s).
constexpr std::size_t kOrdersKept = 16;

/// Per-thread scratch of the localized solves: `local`, the wavelet -> region row map (-1 for
/// wavelets outside the region; whoever fills it restores it), the region's wavelets S and its
/// B[S, S], a zero vector over the wavelets, a -1 map over the fine DOFs (adapted_rows), and per
/// growth step of the region (Eq. 12 defect-driven radius) a sparse solver and the last
/// kOrdersKept orders (`next_order`: the one replaced next), kept across regions for their
/// symbolic analyses.
struct RegionScratch {
    explicit RegionScratch(Index wavelets)
        : local(static_cast<std::size_t>(wavelets), -1),
          work(static_cast<std::size_t>(wavelets), 0.0) {}
    std::vector<Index> local;
    std::vector<Index> S;
    std::vector<Index> own;  ///< clipped_rows' wavelets of one node
    SparseMatrix b;
    std::vector<double> work;
    std::vector<Index> fine_position;  ///< adapted_rows' positions, sized on first use
    std::vector<char> mark;            ///< nodes_within's marks on level meshes, sized on first use
    std::vector<Index> measurement;    ///< solve_penalized_region's -1 map, sized on first use
    std::vector<solve::SpdSolver> solvers;
    std::vector<std::vector<LocalOrder>> orders;
    std::vector<std::size_t> next_order;
};

/// One past the last position from j on of `dofs` (grid DOF indices, sorted) on the node of
/// dofs[j]: the columns of C̃ at one level-(k+1) node are [j, node_end(dofs, dim, j)).
Index node_end(const IndexVector& dofs, int dim, Index j) {
    const Index node = dofs[j] / dim;
    while (j < dofs.size() && dofs[j] / dim == node) ++j;
    return j;
}

}  // namespace

Index StepGeometry::fine_nodes() const {
    return on_grid() ? grid_nodes(fine_cells, dim) : fine_graph->nodes();
}

Index StepGeometry::coarse_nodes() const {
    return on_grid() ? grid_nodes(coarse_cells, dim) : static_cast<Index>(pivots.size());
}

SparseMatrix global_adapted_refinement(const SparseMatrix& B, const SparseMatrix& R,
                                       const SparseMatrix& C_dagger, const SparseMatrix& W,
                                       double tau, const StepGeometry& g) {
    solve::SpdSolver solver;
    solver.compute(B);
    const Index nc = static_cast<Index>(R.cols()), nf = static_cast<Index>(W.cols());
    const SparseMatrix Wt = W.transpose();
    const RowSparse Cd = C_dagger;
    std::vector<Triplet> t;
    for (Index c0 = 0; c0 < nc; c0 += kGlobalBlock) {
        const Index nb = std::min(kGlobalBlock, nc - c0);
        // Rows c0.. of C̃ = C^† + Z W with Z^T = -B^{-1} R, as columns: C^{†,T} - W^T B^{-1} R.
        Matrix rows = -(Wt * solver.solve(Matrix(R.middleCols(c0, nb))));
        for (Index c = 0; c < nb; ++c)
            for (RowSparse::InnerIterator it(Cd, c0 + c); it; ++it) rows(it.col(), c) += it.value();
        for (Index c = 0; c < nb; ++c) {
            // As truncate_rows: a node's entries are kept or dropped together.
            const double cut = tau * rows.col(c).cwiseAbs().maxCoeff();
            for (Index f0 = 0, f1 = 0; f0 < nf; f0 = f1) {
                f1 = node_end(g.fine_dofs, g.dim, f0);
                const double node_max = rows.col(c).segment(f0, f1 - f0).cwiseAbs().maxCoeff();
                if (node_max > 0.0 && node_max >= cut)
                    for (Index f = f0; f < f1; ++f)
                        if (rows(f, c) != 0.0) t.emplace_back(c0 + c, f, rows(f, c));
            }
        }
    }
    SparseMatrix Ct(nc, nf);
    Ct.setFromTriplets(t.begin(), t.end());
    return Ct;
}

namespace {

/// A patch of coarse nodes (indices into the node list of localized_refinement) whose rows of Z are
/// solved on one box of level-(k+1) nodes: those within `rings` of the patch's nodes, whose
/// positions on level k+1 span [first, last] (grid coordinates).
struct Region {
    Eigen::Vector3i first, last;
    std::vector<Index> members;

    /// The box's corners (inclusive), clipped to a grid of nf nodes per axis.
    std::pair<Eigen::Vector3i, Eigen::Vector3i> box(int rings, const Eigen::Vector3i& nf) const {
        return {(first.array() - rings).max(0), (last.array() + rings).min(nf.array() - 1)};
    }
    /// Offsets of the box's corners from `first`: regions with equal keys have the same local
    /// pattern (but near a Dirichlet boundary).
    std::array<int, 6> shape(int rings, const Eigen::Vector3i& nf) const {
        const auto [lo, hi] = box(rings, nf);
        const Eigen::Vector3i a = lo - first, b = hi - first;
        return {a[0], a[1], a[2], b[0], b[1], b[2]};
    }
};

/// Regions of the localized solves: one per patch of coarse nodes, patches whose boxes of
/// `rings` coincide merged, sorted by shape so that consecutive regions reuse the solver's
/// symbolic analysis.
std::vector<Region> patch_regions(const std::vector<Index>& nodes, const StepGeometry& g, int rings,
                                  int patch) {
    const int dim = g.dim;
    const Eigen::Vector3i nf = node_counts(g.fine_cells, dim);
    const Eigen::Vector3i nc = node_counts(g.coarse_cells, dim);
    std::map<std::array<int, 6>, std::size_t> index;
    std::vector<Region> regions;
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        const Eigen::Vector3i c = node_coordinates(nodes[n], g.coarse_cells, dim);
        const Eigen::Vector3i first = (c.array() / patch) * patch;
        const Eigen::Vector3i last = (first.array() + patch - 1).min(nc.array() - 1);
        const Region candidate{2 * first, 2 * last, {}};
        const auto [lo, hi] = candidate.box(rings, nf);
        const std::array<int, 6> key{lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
        const auto [it, added] = index.emplace(key, regions.size());
        if (added) regions.push_back(candidate);
        Region& r = regions[it->second];
        r.first = r.first.cwiseMin(2 * first);
        r.last = r.last.cwiseMax(2 * last);
        r.members.push_back(static_cast<Index>(n));
    }
    std::stable_sort(regions.begin(), regions.end(), [&](const Region& a, const Region& b) {
        return a.shape(rings, nf) < b.shape(rings, nf);
    });
    return regions;
}

/// Regions of the localized solves on level meshes: one per node (patch 1).
std::vector<Region> node_regions(std::size_t count) {
    std::vector<Region> regions(count);
    for (std::size_t n = 0; n < count; ++n) regions[n].members = {static_cast<Index>(n)};
    return regions;
}

/// Per level-(k+1) DOF, its index among the present DOFs g.fine_dofs (-1: absent).
std::vector<Index> fine_local_index(const StepGeometry& g) {
    std::vector<Index> fine_local(static_cast<std::size_t>(g.dim * g.fine_nodes()), -1);
    for (Index l = 0; l < g.fine_dofs.size(); ++l)
        fine_local[static_cast<std::size_t>(g.fine_dofs[l])] = l;
    return fine_local;
}

/// Appends to S the wavelets (rows of W) with a nonzero on level-(k+1) node v not yet in it,
/// marking them in local (0).
void node_wavelets(const SparseMatrix& W, const std::vector<Index>& fine_local, int dim, Index v,
                   std::vector<Index>& local, std::vector<Index>& S) {
    for (int d = 0; d < dim; ++d) {
        const Index l = fine_local[static_cast<std::size_t>(dim * v + d)];
        if (l < 0) continue;
        for (SparseMatrix::InnerIterator it(W, l); it; ++it) {
            const Index w = static_cast<Index>(it.row());
            if (local[static_cast<std::size_t>(w)] < 0) {
                local[static_cast<std::size_t>(w)] = 0;
                S.push_back(w);
            }
        }
    }
}

/// Sorts S and sets local[w] to the position of w in S.
void index_wavelets(std::vector<Index>& local, std::vector<Index>& S) {
    std::sort(S.begin(), S.end());
    for (std::size_t s = 0; s < S.size(); ++s)
        local[static_cast<std::size_t>(S[s])] = static_cast<Index>(s);
}

/// S: the wavelets (rows of W) with a nonzero on a level-(k+1) node of the box [lo, hi], sorted,
/// and local[w] = the position of w in S (local must hold -1 for every wavelet on entry).
void box_wavelets(const SparseMatrix& W, const std::vector<Index>& fine_local,
                  const Eigen::Vector3i& nf, int dim, const Eigen::Vector3i& lo,
                  const Eigen::Vector3i& hi, std::vector<Index>& local, std::vector<Index>& S) {
    S.clear();
    for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
            for (int x = lo[0]; x <= hi[0]; ++x)
                node_wavelets(W, fine_local, dim, x + nf[0] * (y + nf[1] * z), local, S);
    index_wavelets(local, S);
}

/// nnz and a hash of the pattern of B[S, S] in S's order (local[w]: the position of wavelet w
/// in S, or -1): the sum of mix64 over its (column, row) pairs, as in SpdSolver.
std::pair<Index, std::uint64_t> block_pattern(const SparseMatrix& B, const std::vector<Index>& S,
                                              const std::vector<Index>& local) {
    Index nnz = 0;
    std::uint64_t hash = 0;
    for (std::size_t c = 0; c < S.size(); ++c) {
        const std::uint64_t column = static_cast<std::uint64_t>(c) << 32;
        for (SparseMatrix::InnerIterator it(B, S[c]); it; ++it) {
            const Index r = local[static_cast<std::size_t>(it.row())];
            if (r < 0) continue;
            ++nnz;
            hash += mix64(column | static_cast<std::uint32_t>(r));
        }
    }
    return {nnz, hash};
}

/// b = B[S, S] (both triangles, nnz entries), local[w] the position of wavelet w in S or -1,
/// reusing b's storage. Without `order`, in S's order: S is sorted, so local is increasing on S
/// and B's sorted columns give sorted local columns. With it, in the order's: column k is S's
/// order->perm[k], row positions through order->position, unsorted within a column.
void principal_block(const SparseMatrix& B, const std::vector<Index>& S,
                     const std::vector<Index>& local, Index nnz, const LocalOrder* order,
                     SparseMatrix& b) {
    const Index ns = static_cast<Index>(S.size());
    b.resize(ns, ns);
    b.resizeNonZeros(nnz);
    Index* outer = b.outerIndexPtr();
    Index* inner = b.innerIndexPtr();
    double* value = b.valuePtr();
    Index k = 0;
    for (Index c = 0; c < ns; ++c) {
        outer[c] = k;
        const Index from = order ? order->perm[static_cast<std::size_t>(c)] : c;
        for (SparseMatrix::InnerIterator it(B, S[static_cast<std::size_t>(from)]); it; ++it) {
            const Index r = local[static_cast<std::size_t>(it.row())];
            if (r >= 0) {
                inner[k] = order ? order->position[static_cast<std::size_t>(r)] : r;
                value[k++] = it.value();
            }
        }
    }
    outer[ns] = k;
}

/// Solves B[S, S] x = rhs (rhs in S's order) with the calling thread's scratch: densely
/// (LAPACK) when small or dense, else by CHOLMOD in the fill-reducing order of a recent region
/// of the same pattern at this growth step (`attempt`), or a new order of its node graph (the
/// wavelets of a level-(k+1) node, up to dim of them, are consecutive in S and share their
/// pattern). local[w] is the position of wavelet w in S or -1. New orders try METIS beside AMD
/// only where `patterns_repeat` (grids): on level meshes every region has its own pattern, and
/// METIS costs more than it saves on a system factorized once (fibre block of 24,688 nodes, 2
/// automatic levels, Dirac, rho 5: localized solves 22.4 s against 20.3 s with AMD alone; on the
/// 40x20x20 hex checker, where an order serves many regions, 14.4 s against 24.1 s).
Matrix solve_region(const SparseMatrix& B, const std::vector<Index>& S,
                    const std::vector<Index>& local, const Matrix& rhs, int dim,
                    RegionScratch& scratch, std::size_t attempt, bool patterns_repeat) {
    const Index ns = static_cast<Index>(S.size());
    // Named, not bound: clang 14 cannot capture structured bindings (the order lookup below).
    const std::pair<Index, std::uint64_t> pattern = block_pattern(B, S, local);
    const Index nnz = pattern.first;
    const std::uint64_t hash = pattern.second;
    const double n = static_cast<double>(ns);
    if (ns <= kDenseLocalLimit ||
        (ns <= kDenseLocalMax && static_cast<double>(nnz) > kDenseLocalDensity * n * n)) {
        principal_block(B, S, local, nnz, nullptr, scratch.b);
        solve::DenseCholesky llt;
        CG_VERIFY(llt.compute(Matrix(scratch.b)) == 0,
                  "mra: a local system (n = {}) is not positive definite", ns);
        return llt.solve(rhs);
    }
    while (scratch.solvers.size() <= attempt) {
        scratch.solvers.emplace_back(local_options());
        scratch.orders.emplace_back();
        scratch.next_order.push_back(0);
    }
    std::vector<LocalOrder>& kept = scratch.orders[attempt];
    auto order = std::find_if(kept.begin(), kept.end(), [&](const LocalOrder& o) {
        return o.n == ns && o.nnz == nnz && o.hash == hash;
    });
    if (order == kept.end()) {
        principal_block(B, S, local, nnz, nullptr, scratch.b);
        const IndexVector perm = solve::fill_reducing_order(scratch.b, dim, patterns_repeat);
        LocalOrder fresh{ns, nnz, hash, std::vector<Index>(perm.begin(), perm.end()),
                         std::vector<Index>(static_cast<std::size_t>(ns))};
        for (Index k = 0; k < ns; ++k) fresh.position[static_cast<std::size_t>(perm[k])] = k;
        std::size_t& next = scratch.next_order[attempt];
        if (kept.size() < kOrdersKept) {
            kept.push_back(std::move(fresh));
            order = kept.end() - 1;
        } else {
            kept[next] = std::move(fresh);
            order = kept.begin() + static_cast<std::ptrdiff_t>(next);
            next = (next + 1) % kOrdersKept;
        }
    }
    principal_block(B, S, local, nnz, &*order, scratch.b);
    Matrix ordered(ns, rhs.cols());
    for (Index k = 0; k < ns; ++k)
        ordered.row(k) = rhs.row(order->perm[static_cast<std::size_t>(k)]);
    solve::SpdSolver& solver = scratch.solvers[attempt];
    solver.factorize(scratch.b);
    ordered = solver.solve(ordered);
    Matrix x(ns, rhs.cols());
    for (Index k = 0; k < ns; ++k) x.row(order->perm[static_cast<std::size_t>(k)]) = ordered.row(k);
    return x;
}

/// Rows of M with a nonzero in the columns `cols`, sorted.
std::vector<Index> touching_rows(const SparseMatrix& M, const IndexVector& cols) {
    std::vector<Index> r;
    for (const Index c : cols)
        for (SparseMatrix::InnerIterator it(M, c); it; ++it)
            r.push_back(static_cast<Index>(it.row()));
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
}

/// The columns `cols` of M as a dense block over the rows where they have a nonzero (`rows`,
/// sorted).
Matrix column_block(const SparseMatrix& M, const IndexVector& cols, IndexVector& rows) {
    const std::vector<Index> r = touching_rows(M, cols);
    rows = Eigen::Map<const IndexVector>(r.data(), static_cast<Index>(r.size()));
    Matrix block = Matrix::Zero(rows.size(), cols.size());
    for (Index q = 0; q < cols.size(); ++q)
        for (SparseMatrix::InnerIterator it(M, cols[q]); it; ++it)
            block(std::lower_bound(r.begin(), r.end(), static_cast<Index>(it.row())) - r.begin(),
                  q) = it.value();
    return block;
}

/// The A-orthogonality defect of Eq. 12 of the rows `rows` of C̃ = C^† + Z W whose Z rows are
/// -x on the wavelets S (zero elsewhere): row r of C̃ A W^T is R[:, r]^T - x[:, q]^T B[S, :],
/// zero on S (the local solve) and not outside it. Returns the largest relative defect
/// ||R[:, r] - B[:, S] x[:, q]|| / ||R[:, r]|| over the rows (0 for rows with R[:, r] = 0).
/// `work` (#wavelets, zero) is used and left zero.
double orthogonality_defect(const SparseMatrix& B, const SparseMatrix& R, const Matrix& x,
                            const std::vector<Index>& rows, const std::vector<Index>& S,
                            std::vector<double>& work) {
    double worst = 0;
    std::vector<Index> touched;
    for (Index q = 0; q < x.cols(); ++q) {
        touched.clear();
        double r2 = 0;
        for (SparseMatrix::InnerIterator it(R, rows[static_cast<std::size_t>(q)]); it; ++it) {
            work[static_cast<std::size_t>(it.row())] += it.value();
            touched.push_back(static_cast<Index>(it.row()));
            r2 += it.value() * it.value();
        }
        for (std::size_t s = 0; s < S.size(); ++s) {
            const double xs = x(static_cast<Index>(s), q);
            for (SparseMatrix::InnerIterator it(B, S[s]); it; ++it) {
                work[static_cast<std::size_t>(it.row())] -= it.value() * xs;
                touched.push_back(static_cast<Index>(it.row()));
            }
        }
        double d2 = 0;
        for (const Index w : touched) {
            double& v = work[static_cast<std::size_t>(w)];
            d2 += v * v;
            v = 0;
        }
        if (r2 > 0) worst = std::max(worst, std::sqrt(d2 / r2));
    }
    return worst;
}

/// One region's rows of a matrix: row rows[q] holds x(:, q) at the columns cols.
struct RegionSolution {
    std::vector<Index> rows;
    std::vector<Index> cols;
    Matrix x;
};

/// The rows `rows` of C̃ = C^† + Z W whose Z rows are -x on the wavelets S (zero elsewhere), over
/// the columns (fine DOFs, sorted) that C^† and W[S, :] touch. Wt = W^T, Cd = C^† by rows;
/// position (#fine DOFs, -1) is used and left -1.
RegionSolution adapted_rows(const Matrix& x, const std::vector<Index>& S, std::vector<Index> rows,
                            const SparseMatrix& Wt, const RowSparse& Cd,
                            std::vector<Index>& position) {
    RegionSolution out{std::move(rows), {}, {}};
    const auto touch = [&](Index f) {
        if (position[static_cast<std::size_t>(f)] < 0) {
            position[static_cast<std::size_t>(f)] = 0;
            out.cols.push_back(f);
        }
    };
    for (const Index w : S)
        for (SparseMatrix::InnerIterator it(Wt, w); it; ++it) touch(static_cast<Index>(it.row()));
    for (const Index r : out.rows)
        for (RowSparse::InnerIterator it(Cd, r); it; ++it) touch(static_cast<Index>(it.col()));
    std::sort(out.cols.begin(), out.cols.end());
    for (std::size_t c = 0; c < out.cols.size(); ++c)
        position[static_cast<std::size_t>(out.cols[c])] = static_cast<Index>(c);
    out.x = Matrix::Zero(static_cast<Index>(out.cols.size()), x.cols());
    for (std::size_t s = 0; s < S.size(); ++s)
        for (SparseMatrix::InnerIterator it(Wt, S[s]); it; ++it)
            out.x.row(position[static_cast<std::size_t>(it.row())]) -=
                it.value() * x.row(static_cast<Index>(s));
    for (std::size_t q = 0; q < out.rows.size(); ++q)
        for (RowSparse::InnerIterator it(Cd, out.rows[q]); it; ++it)
            out.x(position[static_cast<std::size_t>(it.col())], static_cast<Index>(q)) +=
                it.value();
    for (const Index f : out.cols) position[static_cast<std::size_t>(f)] = -1;
    return out;
}

/// Patch clipping (Options::patch_clip): the rows of C̃ of each member node of a region from the
/// region's solution x on its wavelets S, restricted to the node's own wavelets (those with a
/// nonzero on a level-(k+1) node within `rings` of it), so that the node's row of C̃ has the
/// support of patch 1. Member m owns first[m+1] - first[m] consecutive columns of x and rows of
/// `rows`, members in order; its rows go to solutions[m]. scratch.local (-1 everywhere) is used
/// and left so.
void clipped_rows(const Region& region, const std::vector<Index>& first,
                  const std::vector<Index>& rows, const std::vector<Index>& nodes, int rings,
                  const SparseMatrix& W, const SparseMatrix& Wt, const RowSparse& Cd,
                  const std::vector<Index>& fine_local, const StepGeometry& g,
                  const std::vector<Index>& S, const Matrix& x, RegionScratch& scratch,
                  std::vector<RegionSolution>& solutions) {
    const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
    std::vector<Index>& own = scratch.own;
    Index q = 0;
    for (const Index m : region.members) {
        const std::size_t mm = static_cast<std::size_t>(m);
        const Eigen::Vector3i c = 2 * node_coordinates(nodes[mm], g.coarse_cells, g.dim);
        const auto [lo, hi] = Region{c, c, {}}.box(rings, nf);
        box_wavelets(W, fine_local, nf, g.dim, lo, hi, scratch.local, own);
        for (const Index w : own) scratch.local[static_cast<std::size_t>(w)] = -1;
        const Index count = first[mm + 1] - first[mm];
        // own is a sorted subset of the sorted S.
        Matrix xo(static_cast<Index>(own.size()), count);
        for (std::size_t o = 0, s = 0; o < own.size(); ++o) {
            while (S[s] != own[o]) ++s;
            xo.row(static_cast<Index>(o)) = x.block(static_cast<Index>(s), q, 1, count);
        }
        solutions[mm] = adapted_rows(xo, own, {rows.begin() + q, rows.begin() + q + count}, Wt, Cd,
                                     scratch.fine_position);
        q += count;
    }
}

/// A #rows by #cols matrix from region solutions that each own their rows (no row in two
/// regions), built row by row and converted, freeing the solutions on the way: about 20 bytes
/// per entry at the peak, against 56 through triplets. Exact zeros are left out.
SparseMatrix from_region_solutions(std::vector<RegionSolution>& solutions, Index rows, Index cols) {
    std::vector<Index> count(static_cast<std::size_t>(rows), 0);
    for (const RegionSolution& s : solutions)
        for (std::size_t q = 0; q < s.rows.size(); ++q)
            count[static_cast<std::size_t>(s.rows[q])] =
                static_cast<Index>((s.x.col(static_cast<Index>(q)).array() != 0.0).count());
    RowSparse M(rows, cols);
    Index* outer = M.outerIndexPtr();
    outer[0] = 0;
    for (Index r = 0; r < rows; ++r) outer[r + 1] = outer[r] + count[static_cast<std::size_t>(r)];
    M.resizeNonZeros(outer[rows]);
    for (RegionSolution& s : solutions) {
        for (std::size_t q = 0; q < s.rows.size(); ++q) {
            Index k = outer[s.rows[q]];
            for (std::size_t e = 0; e < s.cols.size(); ++e) {
                const double v = s.x(static_cast<Index>(e), static_cast<Index>(q));
                if (v == 0.0) continue;
                M.innerIndexPtr()[k] = s.cols[e];
                M.valuePtr()[k++] = v;
            }
        }
        s = RegionSolution();
    }
    return SparseMatrix(M);
}

/// Runs solve(n, scratch) for every region n in [0, count) on all OpenMP threads (dynamic
/// schedule: regions differ in size; serially below min_parallel regions), each thread with its
/// own RegionScratch for nw wavelets.
/// The first exception thrown is rethrown after the loop; no region starts after it, as the
/// throwing thread's scratch is left mid-region (its wavelet indices not reset).
template <class F>
void for_each_region(Index count, Index nw, F&& solve, Index min_parallel = kMinParallelNodes) {
    std::exception_ptr error;
    std::atomic<bool> failed = false;
    std::mutex mutex;
#pragma omp parallel if (count >= min_parallel)
    {
        RegionScratch scratch(nw);
#pragma omp for schedule(dynamic, 1)
        for (Index n = 0; n < count; ++n) {
            if (failed.load(std::memory_order_relaxed)) continue;
            try {
                solve(n, scratch);
            } catch (...) {
                const std::lock_guard<std::mutex> lock(mutex);
                if (!error) error = std::current_exception();
                failed = true;
            }
        }
    }
    if (error) std::rethrow_exception(error);
}

}  // namespace

LocalizedRefinement localized_refinement(const SparseMatrix& B, const SparseMatrix& R,
                                         const SparseMatrix& C_dagger, const SparseMatrix& W,
                                         const StepGeometry& g, const LocalizationRings& rings,
                                         int patch, bool clip) {
    const int dim = g.dim;
    CG_VERIFY(g.on_grid() || (patch == 1 && !clip),
              "mra: patch-wise localization needs grids (patch {} on level meshes)", patch);
    const Index nw = static_cast<Index>(W.rows());
    const Eigen::Vector3i nf =
        g.on_grid() ? node_counts(g.fine_cells, dim) : Eigen::Vector3i::Ones().eval();
    const std::vector<Index> fine_local = fine_local_index(g);
    const bool adaptive = rings.defect_tolerance > 0 && rings.max > rings.start;

    // Kept coarse DOFs grouped by node: rows [first[n], first[n+1]) of Z belong to node nodes[n].
    std::vector<Index> nodes, first;
    for (Index r = 0; r < g.coarse_dofs.size(); ++r) {
        const Index v = g.coarse_dofs[r] / dim;
        if (nodes.empty() || nodes.back() != v) {
            nodes.push_back(v);
            first.push_back(r);
        }
    }
    first.push_back(static_cast<Index>(g.coarse_dofs.size()));
    const std::vector<Region> regions =
        g.on_grid() ? patch_regions(nodes, g, rings.start, patch) : node_regions(nodes.size());
    const Index num_regions = static_cast<Index>(regions.size());
    // S: the wavelets on the nodes within r rings of the region's (sorted, indexed in local);
    // returns whether those are all nodes of level k+1.
    const auto region_wavelets = [&](const Region& region, int r, RegionScratch& scratch) {
        if (g.on_grid()) {
            const auto [lo, hi] = region.box(r, nf);
            box_wavelets(W, fine_local, nf, dim, lo, hi, scratch.local, scratch.S);
            return (lo.array() == 0).all() && (hi.array() == nf.array() - 1).all();
        }
        if (scratch.mark.empty()) scratch.mark.assign(static_cast<std::size_t>(g.fine_nodes()), 0);
        const Index centre = g.pivots[static_cast<std::size_t>(
            nodes[static_cast<std::size_t>(region.members.front())])];
        const std::vector<Index> ball = nodes_within(*g.fine_graph, centre, r, scratch.mark);
        scratch.S.clear();
        for (const Index v : ball) node_wavelets(W, fine_local, dim, v, scratch.local, scratch.S);
        index_wavelets(scratch.local, scratch.S);
        return static_cast<Index>(ball.size()) == g.fine_nodes();
    };

    const SparseMatrix Wt = W.transpose();
    const RowSparse Cd = C_dagger;
    const Index num_fine = static_cast<Index>(W.cols());
    LocalizedRefinement out;
    out.rings.assign(static_cast<std::size_t>(g.coarse_nodes()), 0);
    // Per node (an index into `nodes`), the rows of C̃ it holds: a region's rows at its first
    // member, or each member's own rows when clipped.
    std::vector<RegionSolution> solutions(nodes.size());
    for_each_region(num_regions, nw, [&](Index n, RegionScratch& scratch) {
        std::vector<Index>& local = scratch.local;
        std::vector<Index>& S = scratch.S;
        const Region& region = regions[static_cast<std::size_t>(n)];
        // The rows (of Z and C̃) of the region's nodes.
        std::vector<Index> rows;
        for (const Index m : region.members)
            for (Index r = first[static_cast<std::size_t>(m)];
                 r < first[static_cast<std::size_t>(m) + 1]; ++r)
                rows.push_back(r);
        const Index nr = static_cast<Index>(rows.size());
        Matrix x;
        int r = rings.start;
        for (std::size_t attempt = 0;; ++attempt) {
            const bool whole = region_wavelets(region, r, scratch);
            const Index ns = static_cast<Index>(S.size());
            // The right-hand sides R[S, rows].
            Matrix rhs = Matrix::Zero(ns, nr);
            for (Index q = 0; q < nr; ++q)
                for (SparseMatrix::InnerIterator it(R, rows[static_cast<std::size_t>(q)]); it;
                     ++it) {
                    const Index l = local[static_cast<std::size_t>(it.row())];
                    if (l >= 0) rhs(l, q) = it.value();
                }
            x = ns > 0 ? solve_region(B, S, local, rhs, dim, scratch, attempt, g.on_grid())
                       : Matrix(0, nr);
            for (const Index w : S) local[static_cast<std::size_t>(w)] = -1;
            if (ns == 0) break;  // no wavelet near: the rows are C^†'s
            if (!adaptive || r >= rings.max || whole ||
                orthogonality_defect(B, R, x, rows, S, scratch.work) <= rings.defect_tolerance)
                break;
            r = std::min(2 * r, rings.max);
        }
        for (const Index m : region.members)
            out.rings[static_cast<std::size_t>(nodes[static_cast<std::size_t>(m)])] = r;
        if (scratch.fine_position.empty())
            scratch.fine_position.assign(static_cast<std::size_t>(num_fine), -1);
        if (clip && region.members.size() > 1)
            clipped_rows(region, first, rows, nodes, r, W, Wt, Cd, fine_local, g, S, x, scratch,
                         solutions);
        else
            solutions[static_cast<std::size_t>(region.members.front())] =
                adapted_rows(x, S, std::move(rows), Wt, Cd, scratch.fine_position);
    });
    out.Ct = from_region_solutions(solutions, static_cast<Index>(g.coarse_dofs.size()), num_fine);
    return out;
}

std::vector<CellStiffness> cell_stiffness(const mesh::Mesh& mesh,
                                          const material::ElementMaterials& materials,
                                          const IndexVector& fine_dofs,
                                          const Eigen::Vector3i& cells, int patch,
                                          fem::Formulation formulation) {
    const int dim = mesh.dim();
    CG_VERIFY(materials.size() == mesh.num_elements(),
              "mra: cell localization got {} element materials for {} elements", materials.size(),
              mesh.num_elements());
    std::vector<Index> present(static_cast<std::size_t>(mesh.num_dofs()), -1);
    for (Index l = 0; l < fine_dofs.size(); ++l)
        present[static_cast<std::size_t>(fine_dofs[l])] = l;
    const Eigen::Vector3d spacing =
        (mesh.grid->max - mesh.grid->min).cwiseQuotient(cells.cast<double>());
    Eigen::Vector3i blocks = Eigen::Vector3i::Ones();
    for (int d = 0; d < dim; ++d) blocks[d] = (cells[d] + patch - 1) / patch;
    const Index num_blocks = cell_count(blocks, dim);
    std::vector<std::vector<Index>> members(static_cast<std::size_t>(num_blocks));
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        const Eigen::VectorXd centre = mesh.element_positions(e).colwise().mean().transpose();
        Index t = 0;
        for (int d = dim - 1; d >= 0; --d) {
            const int c = std::clamp(
                static_cast<int>(std::floor((centre[d] - mesh.grid->min[d]) / spacing[d])), 0,
                cells[d] - 1);
            t = t * blocks[d] + c / patch;
        }
        members[static_cast<std::size_t>(t)].push_back(e);
    }
    std::vector<CellStiffness> parts;
    for (Index t = 0; t < num_blocks; ++t) {
        const auto& elems = members[static_cast<std::size_t>(t)];
        if (elems.empty()) continue;
        std::vector<Index> dofs;
        for (const Index e : elems)
            for (Index a = 0; a < mesh.elements.cols(); ++a)
                for (int d = 0; d < dim; ++d) {
                    const Index l =
                        present[static_cast<std::size_t>(dim * mesh.elements(e, a) + d)];
                    if (l >= 0) dofs.push_back(l);
                }
        std::sort(dofs.begin(), dofs.end());
        dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
        CellStiffness part;
        part.cell = Eigen::Vector3i::Zero();
        for (Index rest = t, d = 0; d < dim; rest /= blocks[d], ++d)
            part.cell[d] = static_cast<int>(rest % blocks[d]) * patch;
        part.span = patch;
        part.dofs = Eigen::Map<const IndexVector>(dofs.data(), static_cast<Index>(dofs.size()));
        std::vector<Eigen::Triplet<double, Index>> entries;
        for (const Index e : elems) {
            const Matrix Ke =
                fem::element_stiffness(mesh.type, mesh.element_positions(e),
                                       material::tensor(materials.of(e), dim), formulation);
            std::vector<Index> pos(static_cast<std::size_t>(Ke.rows()), -1);
            for (Index a = 0; a < mesh.elements.cols(); ++a)
                for (int d = 0; d < dim; ++d) {
                    const Index l =
                        present[static_cast<std::size_t>(dim * mesh.elements(e, a) + d)];
                    if (l >= 0)
                        pos[static_cast<std::size_t>(dim * a + d)] = static_cast<Index>(
                            std::lower_bound(dofs.begin(), dofs.end(), l) - dofs.begin());
                }
            for (Index i = 0; i < Ke.rows(); ++i)
                for (Index j = 0; j < Ke.cols(); ++j)
                    if (pos[static_cast<std::size_t>(i)] >= 0 &&
                        pos[static_cast<std::size_t>(j)] >= 0)
                        entries.emplace_back(pos[static_cast<std::size_t>(i)],
                                             pos[static_cast<std::size_t>(j)], Ke(i, j));
        }
        part.A.resize(part.dofs.size(), part.dofs.size());
        part.A.setFromTriplets(entries.begin(), entries.end());
        parts.push_back(std::move(part));
    }
    return parts;
}

namespace {

/// The region of part T: the level-(k+1) nodes within `rings` of T (its nodes 2c .. 2c + 2 span,
/// c its first cell), as a box [lo, hi] of the grid of nf nodes, extended to the grid's boundary
/// where it would leave at most rings / kRegionSnap node layers out. Boxes then coincide
/// across a model thinner than about three radii, and share their factorization
/// (cell_corrections): on the 64x16x16 accordion's finest step at 11 rings, 16 boxes instead of
/// 144, each across the whole section.
std::pair<Eigen::Vector3i, Eigen::Vector3i> cell_region(const CellStiffness& part, int rings,
                                                        const Eigen::Vector3i& nf) {
    Eigen::Vector3i lo = (2 * part.cell.array() - rings).max(0);
    Eigen::Vector3i hi = (2 * part.cell.array() + 2 * part.span + rings).min(nf.array() - 1);
    const int snap = rings / kRegionSnap;
    for (int a = 0; a < 3; ++a) {
        if (lo[a] <= snap) lo[a] = 0;
        if (nf[a] - 1 - hi[a] <= snap) hi[a] = nf[a] - 1;
    }
    return {lo, hi};
}

/// Unknowns of a cell-wise localized solve on a box [lo, hi] of level-(k+1) nodes: fills S
/// (sorted) and sets local[u] to the position of unknown u in S (local holds -1 for every unknown
/// on entry). Monotone: a larger box holds the unknowns of a smaller one.
using BoxUnknowns = std::function<void(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi,
                                       std::vector<Index>& local, std::vector<Index>& S)>;

/// Start + sum_T X^T, summed in place in its final column-major storage, so that one copy of it
/// is alive while it is built. Row r's pattern is the unknowns of the bounding box of the regions
/// of the cells whose start row G[r, :] (C^† Φ or C Φ) reaches (a superset of the union of their
/// S_T: the regions of a block of cells overlap, so each cell's solution is added where it falls),
/// plus the start's entries. Holding the cells' solutions as triplets instead took ~10 per entry
/// of Z (a peak of 10.8 GB at 16^3 hexes, rho = 5); a row-wise accumulator copied into the
/// matrix, and the matrix added to the start, kept 3 copies alive.
class CellSum {
  public:
    /// `start`: #rows by `unknowns`, or empty (0 by 0) for none.
    CellSum(Index unknowns, const BoxUnknowns& in_box, const SparseMatrix& G,
            const SparseMatrix& start, const std::vector<CellStiffness>& parts,
            const StepGeometry& g, int rings) {
        const auto rows = static_cast<std::size_t>(G.rows());
        const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
        std::vector<Eigen::Vector3i> lo(rows, nf), hi(rows, Eigen::Vector3i(-1, -1, -1));
        for (const CellStiffness& part : parts) {
            const auto [a, b] = cell_region(part, rings, nf);
            for (const Index r : touching_rows(G, part.dofs)) {
                lo[static_cast<std::size_t>(r)] = lo[static_cast<std::size_t>(r)].cwiseMin(a);
                hi[static_cast<std::size_t>(r)] = hi[static_cast<std::size_t>(r)].cwiseMax(b);
            }
        }
        const RowSparse start_rows =
            start.size() > 0 ? RowSparse(start) : RowSparse(G.rows(), unknowns);
        // Row r's pattern, sorted, into `pattern`.
        const auto row_pattern = [&](Index r, RegionScratch& scratch, std::vector<Index>& pattern) {
            const auto q = static_cast<std::size_t>(r);
            std::vector<Index>& box = scratch.S;
            box.clear();
            if ((hi[q].array() >= lo[q].array()).all()) {
                in_box(lo[q], hi[q], scratch.local, box);
                for (const Index u : box) scratch.local[static_cast<std::size_t>(u)] = -1;
            }
            pattern.clear();
            auto p = box.begin();
            for (RowSparse::InnerIterator it(start_rows, r); it; ++it) {
                for (; p != box.end() && *p < it.col(); ++p) pattern.push_back(*p);
                if (p != box.end() && *p == it.col()) ++p;
                pattern.push_back(it.col());
            }
            pattern.insert(pattern.end(), p, box.end());
        };
        // Column counts, then each column's rows (in any order, sorted after).
        std::vector<Index> cursor(static_cast<std::size_t>(unknowns) + 1, 0);
        const auto each_row_pattern = [&](auto&& use) {
            for_each_region(G.rows(), unknowns, [&](Index r, RegionScratch& scratch) {
                std::vector<Index>& pattern = scratch.own;
                row_pattern(r, scratch, pattern);
                for (const Index u : pattern) use(r, u);
            });
        };
        each_row_pattern([&](Index, Index u) {
#pragma omp atomic
            ++cursor[static_cast<std::size_t>(u) + 1];
        });
        for (std::size_t u = 1; u < cursor.size(); ++u) cursor[u] += cursor[u - 1];
        X_.resize(G.rows(), unknowns);
        X_.resizeNonZeros(cursor.back());
        std::copy(cursor.begin(), cursor.end(), X_.outerIndexPtr());
        Index* inner = X_.innerIndexPtr();
        each_row_pattern([&](Index r, Index u) {
            Index position;
#pragma omp atomic capture
            position = cursor[static_cast<std::size_t>(u)]++;
            inner[position] = r;
        });
        const Index* outer = X_.outerIndexPtr();
#pragma omp parallel for schedule(dynamic, 256)
        for (Index u = 0; u < unknowns; ++u) std::sort(inner + outer[u], inner + outer[u + 1]);
        std::fill(X_.valuePtr(), X_.valuePtr() + X_.nonZeros(), 0.0);
        for (Index u = 0; u < start.outerSize(); ++u)
            for (SparseMatrix::InnerIterator it(start, u); it; ++it)
                entry(it.row(), u) = it.value();
    }

    /// X[rows[q], S] -= x[:, q] for every q (S sorted, within each row's pattern). Threads may
    /// call it at once.
    void subtract(const Eigen::Ref<const Matrix>& x, const IndexVector& rows,
                  const std::vector<Index>& S) {
        for (std::size_t s = 0; s < S.size(); ++s)
            for (Index q = 0; q < rows.size(); ++q) {
                double& value = entry(rows[q], S[s]);
#pragma omp atomic
                value -= x(static_cast<Index>(s), q);
            }
    }

    /// The sum, its exact zeros dropped.
    SparseMatrix take() {
        X_.prune(0.0);
        return std::move(X_);
    }

  private:
    double& entry(Index r, Index u) {
        const Index* begin = X_.innerIndexPtr() + X_.outerIndexPtr()[u];
        const Index* end = X_.innerIndexPtr() + X_.outerIndexPtr()[u + 1];
        const Index* p = std::lower_bound(begin, end, r);
        CG_ASSERT(p != end && *p == r, "mra: unknown outside its row's box");
        return X_.valuePtr()[p - X_.innerIndexPtr()];
    }

    SparseMatrix X_;
};

/// The operator of cell-wise localized solves: A (both triangles, or with G its lower one), plus
/// penalty G^T G if G is given (G: measurements by A's unknowns, compressed), whose principal
/// blocks are formed region by region (solve_operator_region), never whole. The relaxed coarser
/// steps need that: their G measures the fine functions of level k+1, reaching about 7 of its nodes
/// from a coarse node, so G^T G over a whole level is denser than A^{k+1} (the 24^3 checker's
/// coarse step: 43M entries against A's 27M; at 40^3 the whole sum did not fit in 21 GB).
struct RegionOperator {
    const SparseMatrix& A;
    const SparseMatrix* G = nullptr;
    double penalty = 0;
    Stored stored = Stored::Both;
};

/// Solves (A[S, S] + penalty G[:, S]^T G[:, S]) x = rhs (rhs in S's order; local[u]: the position
/// of unknown u in S, or -1) with the calling thread's scratch. G[:, S] is gathered over the rows
/// it touches; the block is formed densely and its Gram part by BLAS dsyrk when it is small or
/// A[S, S] or G[:, S] is dense (solve_region's bounds, at any size: a sparse product of dense
/// blocks costs more than the dense factorization), else sparse and solved by solve_region.
Matrix solve_penalized_region(const RegionOperator& op, const std::vector<Index>& S,
                              const std::vector<Index>& local, const Matrix& rhs, int dim,
                              RegionScratch& scratch) {
    const SparseMatrix& G = *op.G;
    const Index ns = static_cast<Index>(S.size());
    std::vector<Index>& position = scratch.measurement;
    if (position.empty()) position.assign(static_cast<std::size_t>(G.rows()), -1);
    std::vector<Index> rows;
    std::vector<Eigen::Triplet<double, Index>> g;
    for (Index s = 0; s < ns; ++s)
        for (SparseMatrix::InnerIterator it(G, S[static_cast<std::size_t>(s)]); it; ++it) {
            Index& p = position[static_cast<std::size_t>(it.row())];
            if (p < 0) {
                p = static_cast<Index>(rows.size());
                rows.push_back(it.row());
            }
            g.emplace_back(p, s, it.value());
        }
    for (const Index r : rows) position[static_cast<std::size_t>(r)] = -1;
    const Index nr = static_cast<Index>(rows.size());
    // A lower A[S, S] (S sorted: its local order is the global one) holds the block's lower
    // triangle, whose entries off its (full) diagonal stand for two.
    const bool lower = op.stored == Stored::Lower;
    const Index stored_nnz = block_pattern(op.A, S, local).first;
    const Index nnz = lower ? 2 * stored_nnz - ns : stored_nnz;
    const double n = static_cast<double>(ns);
    const bool dense =
        ns <= kDenseLocalLimit || static_cast<double>(nnz) > kDenseLocalDensity * n * n ||
        static_cast<double>(g.size()) > kDenseLocalDensity * n * static_cast<double>(nr);
    if (dense) {  // the lower triangle is all that syrk_lower and DenseCholesky read
        Matrix m = Matrix::Zero(ns, ns);
        for (Index c = 0; c < ns; ++c)
            for (SparseMatrix::InnerIterator it(op.A, S[static_cast<std::size_t>(c)]); it; ++it)
                if (const Index r = local[static_cast<std::size_t>(it.row())]; r >= 0)
                    m(r, c) = it.value();
        Matrix gs = Matrix::Zero(nr, ns);
        for (const auto& t : g) gs(t.row(), t.col()) = t.value();
        solve::syrk_lower(gs, op.penalty, m);
        solve::DenseCholesky llt;
        CG_VERIFY(llt.compute(std::move(m)) == 0,
                  "mra: a local penalized system (n = {}) is not positive definite", ns);
        return llt.solve(rhs);
    }
    principal_block(op.A, S, local, stored_nnz, nullptr, scratch.b);
    if (lower) scratch.b = SparseMatrix(scratch.b.selfadjointView<Eigen::Lower>());
    SparseMatrix gs(nr, ns);
    gs.setFromTriplets(g.begin(), g.end());
    const SparseMatrix m = scratch.b + op.penalty * SparseMatrix(SparseMatrix(gs.transpose()) * gs);
    std::vector<Index> all(static_cast<std::size_t>(ns));
    std::iota(all.begin(), all.end(), Index{0});
    return solve_region(m, all, all, rhs, dim, scratch, 0, true);
}

/// Solves op[S, S] x = rhs: by solve_region without G, else by solve_penalized_region.
Matrix solve_operator_region(const RegionOperator& op, const std::vector<Index>& S,
                             const std::vector<Index>& local, const Matrix& rhs, int dim,
                             RegionScratch& scratch) {
    return op.G ? solve_penalized_region(op, S, local, rhs, dim, scratch)
                : solve_region(op.A, S, local, rhs, dim, scratch, 0, true);
}

/// start + sum_T X^T with X^T[:, S_T] = -x^T and op[S_T, S_T] x = F[S_T, T] A_T G[:, T]^T: the
/// cell-wise localized solves of both constructions (G the start rows over the present fine DOFs:
/// C^† Φ or C Φ; `start` #rows of G by `unknowns`, or empty for none). `op` is symmetric (both
/// triangles) on `unknowns` unknowns, whose functions over the present fine DOFs are the rows of F;
/// S_T are the unknowns `in_box` gives for the box of `rings` rings around part T. One
/// factorization per distinct box, boxes in parallel (OpenMP); parts whose boxes coincide share
/// it, and their right-hand sides of one row are summed (the solve is linear), so a box solves as
/// many columns as rows touch its parts.
SparseMatrix cell_corrections(const RegionOperator& op, Index unknowns, const BoxUnknowns& in_box,
                              const SparseMatrix& F, const SparseMatrix& G,
                              const SparseMatrix& start, const std::vector<CellStiffness>& parts,
                              const StepGeometry& g, int rings) {
    const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
    CellSum X(unknowns, in_box, G, start, parts, g, rings);
    // Parts whose boxes coincide (clipped by the grid: on a coarse level a box may span it, and a
    // thin model's cross-section) share one factorization and one right-hand side per row.
    std::map<std::array<int, 6>, std::vector<std::size_t>> by_box;
    for (std::size_t n = 0; n < parts.size(); ++n) {
        const auto [lo, hi] = cell_region(parts[n], rings, nf);
        by_box[{lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]}].push_back(n);
    }
    std::vector<std::vector<std::size_t>> groups;
    for (auto& [box, members] : by_box) groups.push_back(std::move(members));
    // F[S, T] A_T G[rows, T]^T of part T added to rhs (ns by #rows; rows: sorted, a superset of
    // those touching T).
    const auto add_part = [&](const CellStiffness& part, const std::vector<Index>& local,
                              const std::vector<Index>& rows, Matrix& rhs) {
        IndexVector frows, crows;
        const Matrix ft = column_block(F, part.dofs, frows);
        const Matrix ct = column_block(G, part.dofs, crows);
        if (frows.size() == 0 || crows.size() == 0) return;
        // By BLAS: the library's own dense products are compiled for x86-64-v2 (solve::gemm).
        const Matrix act = part.A * ct.transpose();
        Matrix rt(ft.rows(), act.cols());
        solve::gemm(ft, false, act, false, 0.0, rt);
        for (Index c = 0; c < crows.size(); ++c) {
            const Index column =
                std::lower_bound(rows.begin(), rows.end(), crows[c]) - rows.begin();
            for (Index r = 0; r < frows.size(); ++r)
                if (const Index s = local[static_cast<std::size_t>(frows[r])]; s >= 0)
                    rhs(s, column) += rt(r, c);
        }
    };
    // Boxes in parallel; with fewer boxes than threads (a coarse level spanned by a few boxes)
    // the boxes in turn and each box's parts in parallel.
    const int threads = omp_get_max_threads();
    const bool by_part = static_cast<int>(groups.size()) < threads;
    // The sum of add_part over a group's parts (ns by #rows).
    const auto parts_rhs = [&](const std::vector<std::size_t>& group,
                               const std::vector<Index>& local, const std::vector<Index>& rows,
                               Index ns) {
        Matrix rhs = Matrix::Zero(ns, static_cast<Index>(rows.size()));
        if (!by_part || group.size() == 1) {
            for (const std::size_t n : group) add_part(parts[n], local, rows, rhs);
            return rhs;
        }
        std::exception_ptr error;
        std::mutex mutex;
#pragma omp parallel
        {
            Matrix own = Matrix::Zero(ns, rhs.cols());
#pragma omp for schedule(dynamic, 1)
            for (std::size_t t = 0; t < group.size(); ++t) {
                try {
                    add_part(parts[group[t]], local, rows, own);
                } catch (...) {
                    const std::lock_guard<std::mutex> lock(mutex);
                    if (!error) error = std::current_exception();
                }
            }
            const std::lock_guard<std::mutex> lock(mutex);
            rhs += own;
        }
        if (error) std::rethrow_exception(error);
        return rhs;
    };
    for_each_region(
        static_cast<Index>(groups.size()), unknowns,
        [&](Index q, RegionScratch& scratch) {
            const std::vector<std::size_t>& group = groups[static_cast<std::size_t>(q)];
            std::vector<Index>& local = scratch.local;
            std::vector<Index>& S = scratch.S;
            const auto [lo, hi] = cell_region(parts[group.front()], rings, nf);
            in_box(lo, hi, local, S);
            const Index ns = static_cast<Index>(S.size());
            // Every part of the group shares S and the solve is linear, so the parts' columns of
            // one row are summed into one right-hand side: as many columns as rows touch the group.
            std::vector<Index> rows;
            for (const std::size_t n : group) {
                const std::vector<Index> touched = touching_rows(G, parts[n].dofs);
                rows.insert(rows.end(), touched.begin(), touched.end());
            }
            std::sort(rows.begin(), rows.end());
            rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
            if (ns > 0 && !rows.empty()) {
                const Matrix rhs = parts_rhs(group, local, rows, ns);
                const Matrix x = solve_operator_region(op, S, local, rhs, g.dim, scratch);
                X.subtract(
                    x, Eigen::Map<const IndexVector>(rows.data(), static_cast<Index>(rows.size())),
                    S);
            }
            for (const Index u : S) local[static_cast<std::size_t>(u)] = -1;
        },
        by_part ? static_cast<Index>(groups.size()) + 1 : 2);
    return X.take();
}

/// The smallest diagonal entry of A (both triangles, on g.fine_dofs) at a node of level k+1 that
/// is not on the grid's boundary and has all its DOFs: the stiffness of the softest material at
/// the level's scale (2^dim K_e(0, 0) of its element on the finest level).
double soft_diagonal(const SparseMatrix& A, const StepGeometry& g) {
    const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
    double d = std::numeric_limits<double>::infinity();
    for (Index l0 = 0, l1 = 0; l0 < g.fine_dofs.size(); l0 = l1) {
        l1 = node_end(g.fine_dofs, g.dim, l0);
        const Eigen::Vector3i c = node_coordinates(g.fine_dofs[l0] / g.dim, g.fine_cells, g.dim);
        bool interior = l1 - l0 == g.dim;
        for (int a = 0; a < g.dim; ++a) interior = interior && c[a] > 0 && c[a] < nf[a] - 1;
        for (Index l = l0; interior && l < l1; ++l) d = std::min(d, A.coeff(l, l));
    }
    CG_VERIFY(std::isfinite(d) && d > 0,
              "mra: relaxed cell localization needs a node inside the grid of {} x {} x {} cells "
              "with a positive diagonal",
              g.fine_cells[0], g.fine_cells[1], g.fine_cells[2]);
    return d;
}

/// The relaxed step's operator M = A + penalty G^T G (compressed), stored as A is.
SparseMatrix penalized(const SparseMatrix& A, const SparseMatrix& G, double penalty,
                       Stored stored) {
    SparseMatrix gram = product(SparseMatrix(G.transpose()), G);
    if (stored == Stored::Lower) gram = gram.triangularView<Eigen::Lower>();
    SparseMatrix M = A + penalty * gram;
    M.makeCompressed();
    return M;
}

}  // namespace

SparseMatrix cell_localized_z(const SparseMatrix& B, const SparseMatrix& W,
                              const SparseMatrix& WPhi, const SparseMatrix& CdPhi,
                              const std::vector<CellStiffness>& parts, const StepGeometry& g,
                              int rings) {
    const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
    const std::vector<Index> fine_local = fine_local_index(g);
    const BoxUnknowns wavelets = [&](const Eigen::Vector3i& lo, const Eigen::Vector3i& hi,
                                     std::vector<Index>& local, std::vector<Index>& S) {
        box_wavelets(W, fine_local, nf, g.dim, lo, hi, local, S);
    };
    return cell_corrections({B}, static_cast<Index>(W.rows()), wavelets, WPhi, CdPhi,
                            SparseMatrix(), parts, g, rings);
}

bool regions_span_level(const std::vector<CellStiffness>& parts, int rings, const StepGeometry& g) {
    const Eigen::Vector3i nf = node_counts(g.fine_cells, g.dim);
    return std::all_of(parts.begin(), parts.end(), [&](const CellStiffness& part) {
        const auto [lo, hi] = cell_region(part, rings, nf);
        return lo.isZero() && hi == (nf.array() - 1).matrix();
    });
}

/// Columns of G^T whole_level_refinement solves at once: the solves stay matrix-matrix products
/// while the block stays small (27,783 by 256 doubles, 57 MB, at the 40^3 checker's coarse step).
constexpr Index kWholeLevelColumns = 256;

SparseMatrix whole_level_refinement(const SparseMatrix& A, const SparseMatrix& G, double penalty,
                                    Stored a_stored) {
    CG_VERIFY(A.rows() == A.cols() && G.cols() == A.rows() && penalty > 0,
              "mra: step on the whole level with a {}x{} operator, {}x{} measurements and "
              "penalty {}",
              A.rows(), A.cols(), G.rows(), G.cols(), penalty);
    solve::SolverOptions options;
    options.lower_triangle = a_stored == Stored::Lower;
    solve::SpdSolver solver(options);
    try {
        solver.compute(A);
    } catch (const NotPositiveDefinite&) {
        solver.compute(penalized(A, G, penalty, a_stored));
    }
    // Y = A^{-1} G^T (or M^{-1} G^T) by blocks of kWholeLevelColumns columns, and C̃ = (G Y)^{-1}
    // Y^T in place: at most two dense #finer-by-#coarser blocks are alive at once (Y and Y^T while
    // it is copied, then C̃ and its sparse copy), and A's factor is freed before them.
    const SparseMatrix Gt = G.transpose();
    Matrix Y(A.rows(), G.rows());
    for (Index c0 = 0; c0 < G.rows(); c0 += kWholeLevelColumns) {
        const Index c = std::min<Index>(kWholeLevelColumns, G.rows() - c0);
        Y.middleCols(c0, c) = solver.solve(Matrix(Gt.middleCols(c0, c)));
    }
    solver = solve::SpdSolver(options);
    solve::DenseCholesky GY;
    CG_VERIFY(GY.compute(sparse_times_dense(G, Y)) == 0,
              "mra: step on the whole level: G A^-1 G^T ({} measurements) is not definite: the "
              "measurements are dependent",
              G.rows());
    Matrix Ct = Y.transpose();
    Y = Matrix();
    GY.solve_in_place(Ct);
    SparseMatrix out = Ct.sparseView(0.0, 0.0);
    out.makeCompressed();
    return out;
}

SparseMatrix relaxed_adapted_refinement(const SparseMatrix& A, const SparseMatrix& C,
                                        const SparseMatrix& G, const SparseMatrix& Phi,
                                        const std::vector<CellStiffness>& parts,
                                        const StepGeometry& g, int rings, double relaxation,
                                        Stored a_stored) {
    const int dim = g.dim;
    const Eigen::Vector3i nf = node_counts(g.fine_cells, dim);
    const std::vector<Index> fine_local = fine_local_index(g);
    CG_VERIFY(G.rows() == C.rows() && G.cols() == C.cols(),
              "mra: {}x{} penalized measurements for a {}x{} refinement", G.rows(), G.cols(),
              C.rows(), C.cols());
    const double penalty = soft_diagonal(A, g) / relaxation;
    // The DOFs of the box's nodes but those on a face of the box inside the grid: the functions
    // supported in the box.
    const BoxUnknowns interior = [&](const Eigen::Vector3i& lo, const Eigen::Vector3i& hi,
                                     std::vector<Index>& local, std::vector<Index>& S) {
        S.clear();
        const auto inside = [&](int x, int a) {
            return (x > lo[a] || lo[a] == 0) && (x < hi[a] || hi[a] == nf[a] - 1);
        };
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) {
                    if (!inside(x, 0) || !inside(y, 1) || !inside(z, 2)) continue;
                    const Index v = x + nf[0] * (y + static_cast<Index>(nf[1]) * z);
                    for (int d = 0; d < dim; ++d)
                        if (const Index l = fine_local[static_cast<std::size_t>(dim * v + d)];
                            l >= 0)
                            S.push_back(l);
                }
        // Sorted as enumerated: the present DOFs are numbered in the order of the grid's.
        CG_ASSERT(std::is_sorted(S.begin(), S.end()), "mra: box DOFs out of order");
        for (std::size_t s = 0; s < S.size(); ++s)
            local[static_cast<std::size_t>(S[s])] = static_cast<Index>(s);
    };
    // Every region spanning the level: the step on the whole level, in the basis of the
    // measurements G, without the parts' right-hand sides or C Φ (on a coarse level the sum over
    // the parts' fine elements costs more than the step).
    if (regions_span_level(parts, rings, g)) return whole_level_refinement(A, G, penalty, a_stored);
    CG_ASSERT(Phi.rows() == A.rows(), "mra: relaxed step without its fine functions");
    // The sum A + penalty G^T G formed whole where it stays within a few times A's size (its
    // product's work, sum_r nnz(G[r, :])^2, a bound on G^T G's entries, at most 4 times A's: the
    // finest step, where G = C^{q-1}, about 1.4x on the 24^3 checker), else region by region (its
    // coarse step: 260x), and always from a lower A (solve_region reads a whole sum's blocks with
    // both triangles).
    std::vector<double> row_entries(static_cast<std::size_t>(G.rows()), 0.0);
    for (Index j = 0; j < G.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(G, j); it; ++it)
            ++row_entries[static_cast<std::size_t>(it.row())];
    const double gram_work =
        std::inner_product(row_entries.begin(), row_entries.end(), row_entries.begin(), 0.0);
    const Index unknowns = static_cast<Index>(A.rows());
    const SparseMatrix CPhi = product(C, Phi);
    if (a_stored == Stored::Both && gram_work <= 4.0 * static_cast<double>(A.nonZeros()))
        return cell_corrections({penalized(A, G, penalty, Stored::Both)}, unknowns, interior, Phi,
                                CPhi, C, parts, g, rings);
    return cell_corrections({A, &G, penalty, a_stored}, unknowns, interior, Phi, CPhi, C, parts, g,
                            rings);
}

SparseMatrix rigid_left_inverse(const SparseMatrix& C, const SparseMatrix& C_dagger,
                                const StepGeometry& g, const Matrix& rig_fine,
                                const Matrix& fine_positions, double rotation_scale) {
    const Vector sums = C * Vector::Ones(C.cols());
    Vector scale(sums.size());
    for (Index i = 0; i < sums.size(); ++i) scale[i] = sums[i] != 0.0 ? 1.0 / sums[i] : 0.0;
    SparseMatrix Y = scale.asDiagonal() * C;
    const Index num_fine = grid_nodes(g.fine_cells, g.dim);
    std::vector<int> present(static_cast<std::size_t>(num_fine), 0);
    for (Index l = 0; l < g.fine_dofs.size(); ++l)
        ++present[static_cast<std::size_t>(g.fine_dofs[l] / g.dim)];
    std::vector<char> skip(static_cast<std::size_t>(num_fine), 0);
    for (Index j = 0; j < num_fine; ++j)
        skip[static_cast<std::size_t>(j)] = present[static_cast<std::size_t>(j)] != g.dim;
    correct_invariance(Y, g, skip, Matrix(C * rig_fine), rig_fine, fine_positions, rotation_scale);
    const SparseMatrix YCt = Y * SparseMatrix(C.transpose());
    SparseMatrix X = Y + C_dagger - SparseMatrix(YCt * C_dagger);
    X.prune(0.0);
    X.makeCompressed();
    return X;
}

void truncate_rows(SparseMatrix& M, double tau, const IndexVector& fine_dofs, int dim) {
    CG_VERIFY(fine_dofs.size() == M.cols(), "mra: truncation of {} columns with {} DOFs", M.cols(),
              fine_dofs.size());
    if (tau <= 0) return;
    M.makeCompressed();
    Vector row_max = Vector::Zero(M.rows());
    for (Index j = 0; j < M.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(M, j); it; ++it)
            row_max[it.row()] = std::max(row_max[it.row()], std::abs(it.value()));
    // Per node (a run of columns), the largest |M_ij| of each row there; kept entries (but exact
    // zeros) are moved down in place.
    Index* outer = M.outerIndexPtr();
    Index* inner = M.innerIndexPtr();
    double* value = M.valuePtr();
    Vector node_max = Vector::Zero(M.rows());
    std::vector<Index> touched;
    Index kept = 0;
    for (Index j0 = 0, j1 = 0; j0 < M.cols(); j0 = j1) {
        j1 = node_end(fine_dofs, dim, j0);
        touched.clear();
        for (Index p = outer[j0]; p < outer[j1]; ++p) {
            if (node_max[inner[p]] == 0.0) touched.push_back(inner[p]);
            node_max[inner[p]] = std::max(node_max[inner[p]], std::abs(value[p]));
        }
        for (Index j = j0; j < j1; ++j) {
            const Index begin = outer[j];
            outer[j] = kept;
            for (Index p = begin; p < outer[j + 1]; ++p)
                if (value[p] != 0.0 && node_max[inner[p]] >= tau * row_max[inner[p]]) {
                    inner[kept] = inner[p];
                    value[kept++] = value[p];
                }
        }
        for (const Index i : touched) node_max[i] = 0.0;
    }
    outer[M.cols()] = kept;
    M.data().resize(kept);
}

namespace {

/// R(x): dim by nrot, the displacement at x of the unit rotations about the origin.
Matrix rotation_map(int dim, const Eigen::Vector3d& x) {
    if (dim == 2) return (Matrix(2, 1) << -x[1], x[0]).finished();
    Matrix R(3, 3);  // omega x x = -[x]_x omega
    R << 0, x[2], -x[1], -x[2], 0, x[0], x[1], -x[0], 0;
    return R;
}

}  // namespace

Matrix rigid_modes(int dim, const Matrix& positions, const IndexVector& dofs) {
    const int nrot = dim == 3 ? 3 : 1;
    Matrix R = Matrix::Zero(dofs.size(), dim + nrot);
    for (Index a = 0; a < dofs.size(); ++a) {
        const int c = static_cast<int>(dofs[a] % dim);
        const Eigen::Vector3d x = positions.row(dofs[a] / dim).transpose();
        R(a, c) = 1.0;
        R.block(a, dim, 1, nrot) = rotation_map(dim, x).row(c);
    }
    return R;
}

std::vector<char> correct_invariance(SparseMatrix& Ct, const StepGeometry& g,
                                     const std::vector<char>& skip_fine, const Matrix& rig_coarse,
                                     const Matrix& rig_fine, const Matrix& fine_positions,
                                     double rotation_scale) {
    const int dim = g.dim;
    const int nrot = dim == 3 ? 3 : 1;
    const int m = dim + nrot;
    const Index num_fine = static_cast<Index>(fine_positions.rows());
    std::vector<char> applied(static_cast<std::size_t>(num_fine), 0);
    const Index ncols = static_cast<Index>(Ct.cols());
    Ct.makeCompressed();
    const Index* outer = Ct.outerIndexPtr();
    const Index* inner = Ct.innerIndexPtr();
    double* value = Ct.valuePtr();
    // Per column: not corrected (skipped node), corrected and met, corrected but unmet.
    constexpr char kMet = 1, kUnmet = 2;
    constexpr double kInvarianceTolerance = 1e-10;
    std::vector<char> done(static_cast<std::size_t>(ncols), 0);
    // At most 6 modes: small matrices of fixed capacity, and N kept per thread. A heap
    // allocation per entry of C̃ makes this phase 2.6-3.7x slower (32^3, Dirac, rho = 5: 1.9 s
    // against 0.52 s).
    using Modes = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
    using ModeMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
#pragma omp parallel if (ncols >= kMinParallelColumns)
    {
        Matrix N;
#pragma omp for schedule(dynamic, 64)
        for (Index l = 0; l < ncols; ++l) {
            const Index j = g.fine_dofs[l] / dim;
            if (skip_fine[static_cast<std::size_t>(j)]) continue;
            // Modes about x_j: rotation columns minus the translation columns times R(x_j).
            const Eigen::Vector3d xj = fine_positions.row(j).transpose();
            const ModeMatrix Rj = rotation_map(dim, xj);
            const auto local = [&](const auto& row, auto&& out) {
                out.head(dim) = row.head(dim);
                out.tail(nrot) = (row.tail(nrot) - row.head(dim) * Rj) / rotation_scale;
            };
            const Index nnz = outer[l + 1] - outer[l];
            const Eigen::Map<Vector> x(value + outer[l], nnz);
            N.resize(nnz, m);
            for (Index p = 0; p < nnz; ++p) local(rig_coarse.row(inner[outer[l] + p]), N.row(p));
            Modes target(m);
            local(rig_fine.row(l), target.transpose());
            const Modes residual = target - N.transpose() * x;
            // Minimum-norm change: delta = N (N^T N)^+ residual.
            const Eigen::SelfAdjointEigenSolver<ModeMatrix> eig(ModeMatrix(N.transpose() * N));
            const Modes& lambda = eig.eigenvalues();
            const double cut = 1e-12 * std::max(lambda.maxCoeff(), 1e-300);
            Modes y = eig.eigenvectors().transpose() * residual;
            for (int a = 0; a < m; ++a) y[a] = lambda[a] > cut ? y[a] / lambda[a] : 0.0;
            const Modes z = eig.eigenvectors() * y;
            for (Index p = 0; p < nnz; ++p) value[outer[l] + p] += N.row(p).dot(z);
            // Too few entries (N^T N singular) can leave the conditions unmet.
            const double unmet = (target - N.transpose() * x).norm();
            done[static_cast<std::size_t>(l)] =
                unmet <= kInvarianceTolerance * std::max(1.0, target.norm()) ? kMet : kUnmet;
        }
    }
    for (Index l = 0; l < ncols; ++l)
        if (done[static_cast<std::size_t>(l)] == kMet)
            applied[static_cast<std::size_t>(g.fine_dofs[l] / dim)] = 1;
    for (Index l = 0; l < ncols; ++l)
        if (done[static_cast<std::size_t>(l)] == kUnmet)
            applied[static_cast<std::size_t>(g.fine_dofs[l] / dim)] = 0;
    return applied;
}

}  // namespace coarsegrain::mra::detail
