#include "products.hpp"

#include <omp.h>
#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <new>
#include <numeric>
#include <utility>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/mra/refinement.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra::detail {

namespace {

/// Eigen's sparse-sparse product costs about this many times more per multiply-add than a dense
/// (blocked, vectorized) one (A^4 on the 32x32 grid after global solves: 1.4 s sparse against
/// 0.04 s dense). Products whose dense form needs more than 6e7 entries (480 MB) per operand are
/// always sparse.
constexpr double kSparseFlopPenalty = 30;
constexpr double kDenseProductMaxEntries = 6e7;

double entries(const SparseMatrix& M) {
    return static_cast<double>(M.rows()) * static_cast<double>(M.cols());
}

/// Multiply-adds of the sparse product X Y: sum over the entries Y_kj of nnz(X(:, k)).
double sparse_product_flops(const SparseMatrix& X, const SparseMatrix& Y) {
    double flops = 0;
    for (Index j = 0; j < Y.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(Y, j); it; ++it)
            flops += static_cast<double>(X.col(it.row()).nonZeros());
    return flops;
}

/// Columns per OpenMP chunk of sparse_product, and the fewest columns worth a second thread.
constexpr Index kProductChunk = 16;
constexpr Index kMinParallelProductColumns = 256;

/// The m x n matrix with column j holding rows[j] (sorted) and values[j]; empties both.
SparseMatrix from_columns(Index m, Index n, std::vector<std::vector<Index>>& rows,
                          std::vector<std::vector<double>>& values) {
    std::size_t nnz = 0;
    for (const auto& r : rows) nnz += r.size();
    SparseMatrix P(m, n);
    P.resizeNonZeros(static_cast<Index>(nnz));
    Index* outer = P.outerIndexPtr();
    outer[0] = 0;
    for (Index j = 0; j < n; ++j) {
        auto& r = rows[static_cast<std::size_t>(j)];
        auto& v = values[static_cast<std::size_t>(j)];
        outer[j + 1] = outer[j] + static_cast<Index>(r.size());
        std::copy(r.begin(), r.end(), P.innerIndexPtr() + outer[j]);
        std::copy(v.begin(), v.end(), P.valuePtr() + outer[j]);
        std::vector<Index>().swap(r);
        std::vector<double>().swap(v);
    }
    return P;
}

/// X Y by Gustavson's column-by-column algorithm with a dense accumulator per thread, in parallel
/// over the columns of Y (OpenMP). Cancellations are stored as zeros (the structural pattern);
/// the row indices come out sorted.
SparseMatrix sparse_product(const SparseMatrix& X, const SparseMatrix& Y) {
    if (!X.isCompressed()) {
        SparseMatrix compressed = X;
        compressed.makeCompressed();
        return sparse_product(compressed, Y);
    }
    const Index m = static_cast<Index>(X.rows()), n = static_cast<Index>(Y.cols());
    std::vector<std::vector<Index>> rows(static_cast<std::size_t>(n));
    std::vector<std::vector<double>> values(static_cast<std::size_t>(n));
#pragma omp parallel if (n >= kMinParallelProductColumns)
    {
        std::vector<double> acc(static_cast<std::size_t>(m), 0.0);
        std::vector<char> used(static_cast<std::size_t>(m), 0);
        std::vector<Index> pattern;
#pragma omp for schedule(dynamic, kProductChunk)
        for (Index j = 0; j < n; ++j) {
            pattern.clear();
            for (SparseMatrix::InnerIterator y(Y, j); y; ++y) {
                const Index k = static_cast<Index>(y.row());
                const Index* begin = X.innerIndexPtr() + X.outerIndexPtr()[k];
                const Index* end = X.innerIndexPtr() + X.outerIndexPtr()[k + 1];
                const double* v = X.valuePtr() + (begin - X.innerIndexPtr());
                for (const Index* i = begin; i != end; ++i, ++v) {
                    const auto r = static_cast<std::size_t>(*i);
                    if (!used[r]) {
                        used[r] = 1;
                        pattern.push_back(*i);
                    }
                    acc[r] += *v * y.value();
                }
            }
            std::sort(pattern.begin(), pattern.end());
            auto& col_rows = rows[static_cast<std::size_t>(j)];
            auto& col_values = values[static_cast<std::size_t>(j)];
            col_rows.reserve(pattern.size());
            col_values.reserve(pattern.size());
            for (const Index i : pattern) {
                const auto r = static_cast<std::size_t>(i);
                col_rows.push_back(i);
                col_values.push_back(acc[r]);
                acc[r] = 0.0;
                used[r] = 0;
            }
        }
    }
    return from_columns(m, n, rows, values);
}

/// One thread's scratch of triple_product: dense accumulators over the rows of A Y and of W A Y
/// with their patterns.
struct TripleScratch {
    std::vector<double> mid, out;
    std::vector<char> mid_used, out_used;
    std::vector<Index> mid_pattern, out_pattern;

    TripleScratch(Index n, Index m)
        : mid(static_cast<std::size_t>(n), 0.0), out(static_cast<std::size_t>(m), 0.0),
          mid_used(static_cast<std::size_t>(n), 0), out_used(static_cast<std::size_t>(m), 0) {}

    /// Accumulates column j of W (A Y) into out over out_pattern (unsorted), values only if
    /// `values`; leaves mid clean.
    void column(const SparseMatrix& W, const SparseMatrix& A, const SparseMatrix& Y, Index j,
                bool values) {
        mid_pattern.clear();
        out_pattern.clear();
        for (SparseMatrix::InnerIterator y(Y, j); y; ++y)
            scatter(A, y.row(), y.value(), mid, mid_used, mid_pattern, values);
        for (const Index i : mid_pattern) {
            const auto r = static_cast<std::size_t>(i);
            scatter(W, i, mid[r], out, out_used, out_pattern, values);
            mid[r] = 0.0;
            mid_used[r] = 0;
        }
    }

    /// acc += value * X(:, k) over the pattern.
    static void scatter(const SparseMatrix& X, Index k, double value, std::vector<double>& acc,
                        std::vector<char>& used, std::vector<Index>& pattern, bool values) {
        const Index begin = X.outerIndexPtr()[k], end = X.outerIndexPtr()[k + 1];
        const Index* rows = X.innerIndexPtr();
        const double* v = X.valuePtr();
        for (Index p = begin; p < end; ++p) {
            const auto r = static_cast<std::size_t>(rows[p]);
            if (!used[r]) {
                used[r] = 1;
                pattern.push_back(rows[p]);
            }
            if (values) acc[r] += v[p] * value;
        }
    }

    /// Clears the output accumulator's marks (and values).
    void clear_out() {
        for (const Index i : out_pattern) {
            out[static_cast<std::size_t>(i)] = 0.0;
            out_used[static_cast<std::size_t>(i)] = 0;
        }
    }
};

/// Whether the dense forms of X, Y and X Y fit.
bool dense_product_fits(const SparseMatrix& X, const SparseMatrix& Y) {
    return entries(X) <= kDenseProductMaxEntries && entries(Y) <= kDenseProductMaxEntries &&
           static_cast<double>(X.rows()) * static_cast<double>(Y.cols()) <= kDenseProductMaxEntries;
}

/// Whether X Y is cheaper through dense arithmetic, and fits.
bool dense_product_pays(const SparseMatrix& X, const SparseMatrix& Y) {
    return dense_product_fits(X, Y) && kSparseFlopPenalty * sparse_product_flops(X, Y) >
                                           entries(X) * static_cast<double>(Y.cols());
}

/// congruence goes dense (BLAS) when at least this fraction of M's entries is stored: C̃ of
/// global solves on Table 1's 40x20x20 box (32% dense) gives A^1 in 36.8 s against 80.6 s in the
/// grouped kernel, at a higher peak (7.0 against 5.8 GB). Measurements: docs/performance.md.
constexpr double kDenseCongruence = 0.3;

/// The dense congruence holds M, the result and one block M[J, :] X densely, and X too if it is
/// dense enough (kSparseDensePenalty): at most this many entries in all (4.8 GB), so that both
/// steps of three levels on 64x16x16 hexes after global solves fit (the fine one, M 8019 x
/// 55488, holds 5.4e8 entries).
constexpr double kDenseCongruenceMaxEntries = 6e8;

/// Eigen's sparse times dense product costs about this many times more per multiply-add than
/// BLAS's dense one (X 8019 square, banded, times an 8019 x 1275 dense matrix: 1.12 s at 5%
/// density against 1.14-1.17 s by dgemm, X's dense copy included).
constexpr double kSparseDensePenalty = 20;

/// The grouped congruence of an M at most this fraction dense reads M's rows through
/// kCongruenceBands transposed bands, not one transposed copy. A group's rows beyond its band
/// are then read by M's columns, which a sparse M's groups do anyway but the last few (see
/// by_rows); denser ones read most rows by rows.
constexpr double kBandedCongruence = 0.05;
constexpr int kCongruenceBands = 16;

/// Columns per block of the lower triangle's dense product.
constexpr Index kLowerBlock = 512;

/// X Y dense (BLAS, solve::gemm). Exact zeros are not stored.
SparseMatrix dense_product(const SparseMatrix& X, const SparseMatrix& Y) {
    const Matrix Xd(X), Yd(Y);
    Matrix P(Xd.rows(), Yd.cols());
    solve::gemm(Xd, false, Yd, false, 0.0, P);
    SparseMatrix out = P.sparseView(0.0, 0.0);
    out.makeCompressed();
    return out;
}

/// M X for a dense M and a sparse X, by columns of X in parallel (OpenMP): column j is the
/// combination of M's columns at X's entries in column j, each a contiguous multiply-add of
/// M.rows() values. (Eigen's X M^T writes each entry's row of the result across its columns,
/// with a stride of X.rows(): A^2 of the 48x12x12 accordion's fine step takes 6.65 s that way
/// against 4.56 s.)
Matrix times_sparse(const Eigen::Ref<const Matrix>& M, const SparseMatrix& X) {
    Matrix P(M.rows(), X.cols());
#pragma omp parallel for schedule(dynamic, 256)
    for (Index j = 0; j < X.cols(); ++j) {
        auto p = P.col(j);
        p.setZero();
        for (SparseMatrix::InnerIterator it(X, j); it; ++it)
            p.noalias() += it.value() * M.col(it.row());
    }
    return P;
}

/// Whether products with X are cheaper through a dense copy of X (kSparseDensePenalty).
bool dense_pays(const SparseMatrix& X) {
    return kSparseDensePenalty * static_cast<double>(X.nonZeros()) > entries(X);
}

/// The lower triangle of M X M^T, dense, by blocks J of kLowerBlock result columns: P[j:, J] =
/// M[j:, :] (M[J, :] X)^T from the block's first column j on (BLAS; X is symmetric), about half
/// the multiply-adds of M X M^T. X densely where that pays (dense_pays).
SparseMatrix dense_congruence(const SparseMatrix& M, const SparseMatrix& X) {
    const Matrix Md(M);
    const Index m = static_cast<Index>(Md.rows());
    const bool dense_x = dense_pays(X);
    const Matrix Xd = dense_x ? Matrix(X) : Matrix();
    Matrix P = Matrix::Zero(m, m);
    for (Index b = 0; b < m; b += kLowerBlock) {
        const Index nb = std::min(kLowerBlock, m - b);
        Matrix Yt;  // M[J, :] X
        if (dense_x) {
            Yt.resize(nb, Xd.cols());
            solve::gemm(Md.middleRows(b, nb), false, Xd, false, 0.0, Yt);
        } else {
            Yt = times_sparse(Md.middleRows(b, nb), X);
        }
        solve::gemm(Md.bottomRows(m - b), false, Yt, true, 0.0, P.block(b, b, m - b, nb));
    }
    for (Index j = 1; j < m; ++j) P.col(j).head(j).setZero();
    SparseMatrix out = P.sparseView(0.0, 0.0);
    out.makeCompressed();
    return out;
}

/// Whether dense_congruence fits kDenseCongruenceMaxEntries: M, the result, one block M[J, :] X
/// and, where it pays, X.
bool dense_congruence_fits(const SparseMatrix& M, const SparseMatrix& X) {
    const double m = static_cast<double>(M.rows()), n = static_cast<double>(M.cols());
    return m * n + m * m + n * kLowerBlock + (dense_pays(X) ? n * n : 0) <=
           kDenseCongruenceMaxEntries;
}

/// Grouped congruence: per thread, one map from keys (DOF indices) to dense rows of W values.
template <int W>
class RowAccumulator {
  public:
    explicit RowAccumulator(Index keys) : position_(static_cast<std::size_t>(keys), -1) {}

    /// The row of `key`, zero when first asked for.
    double* row(Index key) {
        Index& p = position_[static_cast<std::size_t>(key)];
        if (p < 0) {
            p = static_cast<Index>(keys_.size());
            keys_.push_back(key);
            values_.resize(values_.size() + W, 0.0);
        }
        return values_.data() + static_cast<std::size_t>(p) * W;
    }
    bool has(Index key) const { return position_[static_cast<std::size_t>(key)] >= 0; }
    const double* existing_row(Index key) const {
        return values_.data() +
               static_cast<std::size_t>(position_[static_cast<std::size_t>(key)]) * W;
    }
    const std::vector<Index>& keys() const { return keys_; }
    void clear() {
        for (const Index k : keys_) position_[static_cast<std::size_t>(k)] = -1;
        keys_.clear();
        values_.clear();
    }

  private:
    std::vector<Index> position_;
    std::vector<Index> keys_;
    std::vector<double> values_;
};

/// Longest run of columns accumulate takes at once: a node's DOFs in 3D.
constexpr Index kMaxColumnRun = 3;

/// Whether columns a and b of S have the same rows outside [first, last).
bool same_rows_outside(const SparseMatrix& S, Index a, Index b, Index first, Index last) {
    const Index* outer = S.outerIndexPtr();
    const Index* inner = S.innerIndexPtr();
    const auto outside = [&](Index j) {
        const Index *begin = inner + outer[j], *end = inner + outer[j + 1];
        const Index* from = std::lower_bound(begin, end, first);
        return std::array{begin, from, std::lower_bound(from, end, last), end};
    };
    const auto x = outside(a), y = outside(b);
    return std::equal(x[0], x[1], y[0], y[1]) && std::equal(x[2], x[3], y[2], y[3]);
}

/// S's columns in runs of at most kMaxColumnRun consecutive columns s.. whose row patterns agree
/// outside the run's own rows [offset + s, offset + s + length): a node's DOFs in an interleaved
/// symmetric matrix stored whole, by its lower triangle or as the transposed rows of that (the
/// node's own block is triangular in the last two), and in C̃ (see truncate_rows). Run r is
/// columns [start[r], start[r + 1]), column f is in run run_of[f], and uniform[r] says whether
/// the run's columns have one pattern, their own rows included.
struct ColumnRuns {
    std::vector<Index> start{0}, run_of;
    std::vector<char> uniform;

    explicit ColumnRuns(const SparseMatrix& S, Index offset = 0)
        : run_of(static_cast<std::size_t>(S.cols())) {
        for (Index j = 1; j < S.cols(); ++j)
            if (j - start.back() >= kMaxColumnRun ||
                !same_rows_outside(S, start.back(), j, offset + start.back(), offset + j + 1))
                start.push_back(j);
        start.push_back(S.cols());
        uniform.assign(start.size() - 1, 1);
        for (std::size_t r = 0; r + 1 < start.size(); ++r) {
            std::fill(run_of.begin() + start[r], run_of.begin() + start[r + 1],
                      static_cast<Index>(r));
            for (Index j = start[r] + 1; j < start[r + 1]; ++j)
                uniform[r] = uniform[r] && same_rows_outside(S, start[r], j, 0, 0);
        }
    }
};

/// acc[i, :] += sum_t S[i, s + t] rows[offset + s + t, :] over the L columns s.. of one run of
/// S, from row `first_row` of S on: each row of acc is read and written once per run instead of
/// once per column (the kernel streams acc's rows; on the 64^3 Galerkin product that traffic
/// dominates); unless the run is `uniform`, its own rows [offset + s, offset + s + L) column by
/// column.
template <int W, int L>
void accumulate_run(const SparseMatrix& S, Index s, bool uniform, const RowAccumulator<W>& rows,
                    RowAccumulator<W>& acc, Index first_row, Index offset) {
    const Index* outer = S.outerIndexPtr();
    const Index* inner = S.innerIndexPtr();
    const double* value = S.valuePtr();
    const double* p[L];
    // Per column: where its rows from first_row on begin, and where they enter and leave the
    // run's own rows (the same rows before and after in every column).
    Index begin[L], inside[L], after[L];
    for (int t = 0; t < L; ++t) {
        const Index *b = inner + outer[s + t], *e = inner + outer[s + t + 1];
        const Index* from = std::lower_bound(b, e, first_row);
        const Index* in = uniform ? e : std::lower_bound(from, e, offset + s);
        begin[t] = from - inner;
        inside[t] = in - inner;
        after[t] = uniform ? inside[t]
                           : std::lower_bound(in, e, std::max(first_row, offset + s + L)) - inner;
        p[t] = rows.existing_row(offset + s + t);
    }
    const auto joint = [&](const Index* at, Index count) {
        for (Index k = 0; k < count; ++k) {
            double* a = acc.row(inner[at[0] + k]);
            for (int c = 0; c < W; ++c) {
                double sum = value[at[0] + k] * p[0][c];
                for (int t = 1; t < L; ++t) sum += value[at[t] + k] * p[t][c];
                a[c] += sum;
            }
        }
    };
    joint(begin, inside[0] - begin[0]);
    for (int t = 0; t < L; ++t)
        for (Index k = inside[t]; k < after[t]; ++k) {
            double* a = acc.row(inner[k]);
            for (int c = 0; c < W; ++c) a[c] += value[k] * p[t][c];
        }
    joint(after, outer[s + 1] - after[0]);
}

/// acc[i, :] += S[i, f - offset] rows[f, :] for every key f of `rows` in [offset, offset +
/// S.cols()), from row `first_row` of S on (S's row indices sorted), by the runs of S's columns
/// whose every column is at a key.
template <int W>
void accumulate(const SparseMatrix& S, const ColumnRuns& runs, const RowAccumulator<W>& rows,
                RowAccumulator<W>& acc, Index first_row, Index offset = 0) {
    for (const Index key : rows.keys()) {
        const Index f = key - offset;
        if (f < 0 || f >= S.cols()) continue;
        const Index r = runs.run_of[static_cast<std::size_t>(f)];
        const Index s = runs.start[static_cast<std::size_t>(r)];
        const Index length = runs.start[static_cast<std::size_t>(r) + 1] - s;
        bool whole = length > 1;
        for (Index t = s; whole && t < s + length; ++t) whole = rows.has(offset + t);
        const bool uniform = runs.uniform[static_cast<std::size_t>(r)];
        if (!whole)
            accumulate_run<W, 1>(S, f, true, rows, acc, first_row, offset);
        else if (f == s && length == 2)
            accumulate_run<W, 2>(S, s, uniform, rows, acc, first_row, offset);
        else if (f == s)
            accumulate_run<W, 3>(S, s, uniform, rows, acc, first_row, offset);
    }
}

/// A sparse matrix's columns, written by OpenMP threads in any order, each thread into blocks of
/// its own, then moved into one compressed matrix a block at a time, each block unmapped once
/// copied. A block is a mapping of its own, resident only as it is written and returned to the
/// system when freed, even where the allocator keeps freed memory (retain_freed_memory), and
/// the matrix's arrays are resident only as they are filled: the result is held about once
/// while it is assembled. Columns kept as vectors, copied into the matrix and freed are held
/// twice (the 64^3 checker's A^2: 2.4 GB more at the build's peak).
class ColumnStore {
  public:
    ColumnStore(Index rows, Index cols, int threads)
        : rows_(rows),
          pieces_(static_cast<std::size_t>(cols)),
          blocks_(static_cast<std::size_t>(threads)) {}

    /// Starts column j in thread t with room for `capacity` entries (push them with push).
    void begin(int t, Index j, Index capacity) {
        auto& blocks = blocks_[static_cast<std::size_t>(t)];
        const auto needed = static_cast<std::size_t>(capacity);
        if (blocks.empty() || blocks.back()->size + needed > blocks.back()->capacity)
            blocks.push_back(std::make_unique<Block>(std::max(kBlockEntries, needed)));
        Block& b = *blocks.back();
        pieces_[static_cast<std::size_t>(j)] = {static_cast<Index>(b.size), 0};
        b.columns.push_back(j);
    }
    /// Appends (row, value) to column j, begun last in thread t, rows ascending.
    void push(int t, Index j, Index row, double value) {
        Block& b = *blocks_[static_cast<std::size_t>(t)].back();
        b.rows[b.size] = row;
        b.values[b.size++] = value;
        ++pieces_[static_cast<std::size_t>(j)].count;
    }
    /// The rows x cols matrix of the columns written (a column not begun is empty); empties the
    /// store.
    SparseMatrix take() {
        const auto cols = static_cast<Index>(pieces_.size());
        SparseMatrix S(rows_, cols);
        Index* outer = S.outerIndexPtr();
        outer[0] = 0;
        for (Index j = 0; j < cols; ++j)
            outer[j + 1] = outer[j] + pieces_[static_cast<std::size_t>(j)].count;
        S.resizeNonZeros(outer[cols]);
        for (auto& blocks : blocks_)
            for (auto& b : blocks) {
                for (const Index j : b->columns) {
                    const Piece& p = pieces_[static_cast<std::size_t>(j)];
                    std::copy_n(b->rows + p.offset, p.count, S.innerIndexPtr() + outer[j]);
                    std::copy_n(b->values + p.offset, p.count, S.valuePtr() + outer[j]);
                }
                b.reset();
            }
        blocks_.clear();
        pieces_.clear();
        return S;
    }

  private:
    /// Entries per block (96 MB).
    static constexpr std::size_t kBlockEntries = std::size_t{1} << 23;
    /// `capacity` entries in one anonymous mapping: the values, then their rows.
    struct Block {
        std::size_t capacity, size = 0;
        void* mapping;
        double* values;
        Index* rows;
        std::vector<Index> columns;  // begun here, in order

        explicit Block(std::size_t entries)
            : capacity(entries),
              mapping(mmap(nullptr, bytes(), PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                           -1, 0)) {
            if (mapping == MAP_FAILED) throw std::bad_alloc();
            values = static_cast<double*>(mapping);
            rows = reinterpret_cast<Index*>(values + capacity);
        }
        ~Block() { munmap(mapping, bytes()); }
        Block(const Block&) = delete;
        Block& operator=(const Block&) = delete;
        std::size_t bytes() const { return capacity * (sizeof(double) + sizeof(Index)); }
    };
    struct Piece {
        Index offset, count;
    };
    Index rows_;
    std::vector<Piece> pieces_;
    std::vector<std::vector<std::unique_ptr<Block>>> blocks_;  // per thread
};

/// acc[i, :] = sum_f M[i, f] rows[f, :] over the keys f of `rows`, for every row i of M in
/// [first_row, band.last) that meets a key, from Mt = M[band.first : band.last, :]^T: row by
/// row, each kept in registers.
template <int W>
void accumulate_rows(const SparseMatrix& Mt, Index band_first, const RowAccumulator<W>& rows,
                     RowAccumulator<W>& acc, Index first_row) {
    const Index* outer = Mt.outerIndexPtr();
    const Index* inner = Mt.innerIndexPtr();
    const double* value = Mt.valuePtr();
    for (Index i = first_row - band_first; i < Mt.outerSize(); ++i) {
        double sum[W] = {};
        bool met = false;
        for (Index k = outer[i]; k < outer[i + 1]; ++k) {
            if (!rows.has(inner[k])) continue;
            const double* p = rows.existing_row(inner[k]);
            const double v = value[k];
            for (int c = 0; c < W; ++c) sum[c] += v * p[c];
            met = true;
        }
        if (met) std::copy(sum, sum + W, acc.row(band_first + i));
    }
}

/// Rows [first, last) of M and the groups of rows congruence takes with them.
struct RowBand {
    Index first = 0, last = 0;
    std::vector<Index> groups;
};

/// The groups in `bands` bands of M's rows, by their first rows: band b takes the groups whose
/// first row is where the entries of M in the rows above it reach b / bands of all; each band's
/// rows span its groups' rows. Empty bands are left out.
std::vector<RowBand> row_bands(const SparseMatrix& M, const std::vector<IndexVector>& groups,
                               int bands) {
    std::vector<double> above(static_cast<std::size_t>(M.rows()) + 1, 0.0);
    for (Index p = 0; p < M.nonZeros(); ++p)
        ++above[static_cast<std::size_t>(M.innerIndexPtr()[p]) + 1];
    std::partial_sum(above.begin(), above.end(), above.begin());
    const double total = std::max(above.back(), 1.0);
    std::vector<RowBand> out(static_cast<std::size_t>(bands));
    for (std::size_t g = 0; g < groups.size(); ++g) {
        const Index first = groups[g].minCoeff(), last = groups[g].maxCoeff() + 1;
        const auto b = std::min<std::size_t>(
            static_cast<std::size_t>(bands * above[static_cast<std::size_t>(first)] / total),
            static_cast<std::size_t>(bands) - 1);
        RowBand& band = out[b];
        band.first = band.groups.empty() ? first : std::min(band.first, first);
        band.last = band.groups.empty() ? last : std::max(band.last, last);
        band.groups.push_back(static_cast<Index>(g));
    }
    std::erase_if(out, [](const RowBand& band) { return band.groups.empty(); });
    return out;
}

/// M[first : last, :]^T: its column i - first is row i of M, with M's column indices ascending;
/// `strictly_lower`: of M's entries below the diagonal only.
SparseMatrix transposed_rows(const SparseMatrix& M, Index first, Index last,
                             bool strictly_lower = false) {
    const Index n = M.cols();
    const Index* outer = M.outerIndexPtr();
    const Index* inner = M.innerIndexPtr();
    std::vector<Index> begin(static_cast<std::size_t>(n));
    SparseMatrix T(n, last - first);
    Index* t_outer = T.outerIndexPtr();
    std::fill(t_outer, t_outer + (last - first) + 1, 0);
    for (Index f = 0; f < n; ++f) {
        const Index from = strictly_lower ? std::max(first, f + 1) : first;
        const Index* b = std::lower_bound(inner + outer[f], inner + outer[f + 1], from);
        begin[static_cast<std::size_t>(f)] = static_cast<Index>(b - inner);
        for (; b != inner + outer[f + 1] && *b < last; ++b) ++t_outer[*b - first + 1];
    }
    std::partial_sum(t_outer, t_outer + (last - first) + 1, t_outer);
    T.resizeNonZeros(t_outer[last - first]);
    std::vector<Index> next(t_outer, t_outer + (last - first));
    for (Index f = 0; f < n; ++f)
        for (Index p = begin[static_cast<std::size_t>(f)]; p < outer[f + 1] && inner[p] < last;
             ++p) {
            const Index q = next[static_cast<std::size_t>(inner[p] - first)]++;
            T.innerIndexPtr()[q] = f;
            T.valuePtr()[q] = M.valuePtr()[p];
        }
    return T;
}

/// Whether M's rows in [first, band.last) (accumulate_rows, from Mt = the band's rows
/// transposed) are cheaper to scan for (M xmt)[first : band.last, :] than M's columns at the
/// keys of xmt (accumulate): when at least half of the rows' entries meet a key. Every entry
/// met costs the same multiply-adds either way, but the columns add them to a row of the result
/// in memory and the rows in registers.
template <int W>
bool by_rows(const SparseMatrix& M, const SparseMatrix& Mt, const RowBand& band,
             const RowAccumulator<W>& xmt, Index first) {
    const Index* outer = M.outerIndexPtr();
    const Index* inner = M.innerIndexPtr();
    double met = 0;
    for (const Index f : xmt.keys()) {
        const Index* end = inner + outer[f + 1];
        const Index* from = std::lower_bound(inner + outer[f], end, first);
        met += static_cast<double>(std::lower_bound(from, end, band.last) - from);
    }
    const Index* t_outer = Mt.outerIndexPtr();
    const double scanned =
        static_cast<double>(t_outer[Mt.outerSize()] - t_outer[first - band.first]);
    return scanned <= 2 * met;
}

/// The columns of M that the nonempty columns of Mt = M[rows, :]^T reach: [first, last).
std::pair<Index, Index> reached_columns(const SparseMatrix& Mt) {
    Index first = Mt.rows(), last = 0;
    for (Index i = 0; i < Mt.outerSize(); ++i) {
        const Index begin = Mt.outerIndexPtr()[i], end = Mt.outerIndexPtr()[i + 1];
        if (begin == end) continue;
        first = std::min(first, Mt.innerIndexPtr()[begin]);
        last = std::max(last, Mt.innerIndexPtr()[end - 1] + 1);
    }
    return {std::min(first, last), last};
}

/// Returns the pages of S's entries to the system: a temporary about to be freed into a heap that
/// keeps freed memory (retain_freed_memory), whose pages would stay resident beside the next
/// results (the 64^3 checker's A^1 product: C̃^1 and A^2's upper triangle transposed, 3.8 GB).
void release_entries(SparseMatrix& S) {
    release_pages(S.valuePtr(), S.valuePtr() + S.nonZeros());
    release_pages(S.innerIndexPtr(), S.innerIndexPtr() + S.nonZeros());
}

/// The lower triangle of M X M^T, group by group of kernel width W, band by band of M's rows
/// (see congruence). X by its lower triangle (`x_lower`): per band, X's strictly upper entries
/// in the columns the band's rows of M reach are the transposed rows of X there.
template <int W>
SparseMatrix grouped_congruence(const SparseMatrix& M, const SparseMatrix& X,
                                const std::vector<IndexVector>& groups, int bands, bool x_lower) {
    const Index m = M.rows(), n = M.cols();
    const ColumnRuns m_runs(M), x_runs(X);
    ColumnStore store(m, m, omp_get_max_threads());
    SparseMatrix Mt, X_upper;  // the band's, each freed for the next; the last one's released
    for (const RowBand& band : row_bands(M, groups, bands)) {
        Mt = transposed_rows(M, band.first, band.last);
        // Named, not bound: clang 14 cannot capture structured bindings (the parallel region).
        const std::pair<Index, Index> reach = x_lower ? reached_columns(Mt) : std::pair{n, n};
        const Index reach_first = reach.first;
        X_upper =
            x_lower ? transposed_rows(X, reach_first, reach.second, true) : SparseMatrix(n, 0);
        const ColumnRuns upper_runs(X_upper, reach_first);
        const auto n_groups = static_cast<Index>(band.groups.size());
#pragma omp parallel if (n_groups > 1)
        {
            const int thread = omp_get_thread_num();
            RowAccumulator<W> mt(n), xmt(n), result(m);
            std::vector<Index> sorted;
#pragma omp for schedule(dynamic, 1)
            for (Index g = 0; g < n_groups; ++g) {
                const IndexVector& J = groups[static_cast<std::size_t>(band.groups[g])];
                for (Index c = 0; c < J.size(); ++c)
                    for (SparseMatrix::InnerIterator it(Mt, J[c] - band.first); it; ++it)
                        mt.row(static_cast<Index>(it.row()))[c] = it.value();
                accumulate(X, x_runs, mt, xmt, 0);
                if (x_lower) accumulate(X_upper, upper_runs, mt, xmt, 0, reach_first);
                const Index first = J.minCoeff();
                if (by_rows(M, Mt, band, xmt, first)) {
                    accumulate_rows(Mt, band.first, xmt, result, first);
                    if (band.last < m) accumulate(M, m_runs, xmt, result, band.last);
                } else {
                    accumulate(M, m_runs, xmt, result, first);
                }
                sorted = result.keys();
                std::sort(sorted.begin(), sorted.end());
                for (Index c = 0; c < J.size(); ++c) {
                    store.begin(thread, J[c], static_cast<Index>(sorted.size()));
                    for (const Index r : sorted) {
                        const double v = result.existing_row(r)[c];
                        if (r >= J[c] && v != 0.0) store.push(thread, J[c], r, v);
                    }
                }
                mt.clear();
                xmt.clear();
                result.clear();
            }
        }
    }
    release_entries(Mt);
    release_entries(X_upper);
    return store.take();
}

}  // namespace

SparseMatrix product(const SparseMatrix& X, const SparseMatrix& Y) {
    return dense_product_pays(X, Y) ? dense_product(X, Y) : sparse_product(X, Y);
}

Matrix sparse_times_dense(const SparseMatrix& X, const Eigen::Ref<const Matrix>& Y) {
    CG_VERIFY(X.cols() == Y.rows(), "mra: product of a {}x{} sparse and a {}x{} dense matrix",
              X.rows(), X.cols(), Y.rows(), Y.cols());
    Matrix P(X.rows(), Y.cols());
    if (dense_pays(X) && entries(X) <= kDenseProductMaxEntries) {
        solve::gemm(Matrix(X), false, Y, false, 0.0, P);
        return P;
    }
#pragma omp parallel for schedule(dynamic, 16)
    for (Index j = 0; j < Y.cols(); ++j) P.col(j).noalias() = X * Y.col(j);
    return P;
}

SparseMatrix triple_product(const SparseMatrix& W, const SparseMatrix& A, const SparseMatrix& Y) {
    CG_VERIFY(W.cols() == A.rows() && A.cols() == Y.rows(),
              "mra: triple product of {}x{}, {}x{} and {}x{} matrices", W.rows(), W.cols(),
              A.rows(), A.cols(), Y.rows(), Y.cols());
    if (!W.isCompressed() || !A.isCompressed() || !Y.isCompressed()) {
        SparseMatrix Wc = W, Ac = A, Yc = Y;
        Wc.makeCompressed();
        Ac.makeCompressed();
        Yc.makeCompressed();
        return triple_product(Wc, Ac, Yc);
    }
    if (dense_product_pays(A, Y)) return product(W, product(A, Y));
    const Index m = W.rows(), n = Y.cols();
    SparseMatrix P(m, n);
    Index* outer = P.outerIndexPtr();
    // Pass 1: each column's pattern size; pass 2: its values, written in place.
    for (const bool values : {false, true}) {
        if (values) {
            outer[0] = 0;
            for (Index j = 0; j < n; ++j) outer[j + 1] += outer[j];
            P.resizeNonZeros(outer[n]);
        }
#pragma omp parallel if (n >= kMinParallelProductColumns)
        {
            TripleScratch s(A.rows(), m);
#pragma omp for schedule(dynamic, kProductChunk)
            for (Index j = 0; j < n; ++j) {
                s.column(W, A, Y, j, values);
                if (!values) {
                    outer[j + 1] = static_cast<Index>(s.out_pattern.size());
                } else {
                    std::sort(s.out_pattern.begin(), s.out_pattern.end());
                    Index p = outer[j];
                    for (const Index i : s.out_pattern) {
                        P.innerIndexPtr()[p] = i;
                        P.valuePtr()[p++] = s.out[static_cast<std::size_t>(i)];
                    }
                }
                s.clear_out();
            }
        }
    }
    return P;
}

SparseMatrix symmetrized(SparseMatrix S) {
    S.makeCompressed();
    // A structurally symmetric S (as the sparse products keep their structural patterns): each
    // entry averaged with its mirror, found in O(1) by a cursor per column (visiting the columns
    // in order meets the entries of each column in row order), instead of adding a transposed
    // copy. Both give 0.5 (m_ij + m_ji), bit for bit.
    const Index n = S.cols();
    const Index* outer = S.outerIndexPtr();
    const Index* inner = S.innerIndexPtr();
    double* value = S.valuePtr();
    bool mirrored = S.rows() == n;
    std::vector<Index> cursor(outer, outer + n);
    for (Index j = 0; j < n && mirrored; ++j)
        for (Index p = outer[j]; p < outer[j + 1]; ++p) {
            const Index i = inner[p];
            if (i < j) continue;  // its pair was averaged from column i
            const Index q = cursor[static_cast<std::size_t>(i)]++;
            if (q >= outer[i + 1] || inner[q] != j) {
                mirrored = false;
                break;
            }
            value[p] = value[q] = 0.5 * (value[p] + value[q]);
        }
    // Every entry on or above the diagonal was met as a mirror.
    for (Index i = 0; i < n && mirrored; ++i) {
        const Index q = cursor[static_cast<std::size_t>(i)];
        mirrored = q == outer[i + 1] || inner[q] > i;
    }
    if (mirrored) return S;
    // The pairs averaged before the mismatch hold their mean twice, which the sum keeps.
    S = 0.5 * (S + SparseMatrix(S.transpose()));
    S.makeCompressed();
    return S;
}

SparseMatrix congruence(const SparseMatrix& M, const SparseMatrix& X,
                        const std::vector<IndexVector>& groups, Stored x_stored) {
    Index covered = 0, widest = 0;
    for (const IndexVector& J : groups) {
        covered += J.size();
        widest = std::max<Index>(widest, J.size());
    }
    CG_VERIFY(covered == M.rows() && widest <= kMaxGroup,
              "mra: congruence groups cover {} of {} rows, widest {} (at most {})", covered,
              M.rows(), widest, kMaxGroup);
    const bool dense = static_cast<double>(M.nonZeros()) >= kDenseCongruence * entries(M);
    const bool x_lower = x_stored == Stored::Lower;
    if (dense && x_lower) return congruence(M, symmetric_from_lower(X), groups, Stored::Both);
    if (dense && dense_congruence_fits(M, X)) return dense_congruence(M, X);
    const int bands =
        static_cast<double>(M.nonZeros()) <= kBandedCongruence * entries(M) ? kCongruenceBands : 1;
    if (widest <= 8) return grouped_congruence<8>(M, X, groups, bands, x_lower);
    if (widest <= 16) return grouped_congruence<16>(M, X, groups, bands, x_lower);
    if (widest <= 24) return grouped_congruence<24>(M, X, groups, bands, x_lower);
    return grouped_congruence<kMaxGroup>(M, X, groups, bands, x_lower);
}

std::vector<IndexVector> consecutive_groups(Index n, Index size) {
    CG_VERIFY(n >= 0 && size >= 1 && size <= kMaxGroup, "mra: {} rows in groups of {} (1..{})", n,
              size, kMaxGroup);
    std::vector<IndexVector> groups;
    for (Index first = 0; first < n; first += size) {
        const Index count = std::min(size, n - first);
        groups.push_back(IndexVector::LinSpaced(count, first, first + count - 1));
    }
    return groups;
}

std::vector<IndexVector> node_blocks(const IndexVector& dofs, const Eigen::Vector3i& cells, int dim,
                                     int side) {
    const Eigen::Vector3i nodes = node_counts(cells, dim);
    Eigen::Vector3i blocks = Eigen::Vector3i::Ones();
    for (int d = 0; d < dim; ++d) blocks[d] = (nodes[d] + side - 1) / side;
    std::vector<std::vector<Index>> members(static_cast<std::size_t>(blocks.prod()));
    for (Index l = 0; l < dofs.size(); ++l) {
        const Eigen::Vector3i b = node_coordinates(dofs[l] / dim, cells, dim) / side;
        members[static_cast<std::size_t>(b[0] + blocks[0] * (b[1] + blocks[1] * b[2]))].push_back(
            l);
    }
    std::vector<IndexVector> groups;
    for (const auto& m : members)
        if (!m.empty())
            groups.emplace_back(
                Eigen::Map<const IndexVector>(m.data(), static_cast<Index>(m.size())));
    return groups;
}

std::vector<IndexVector> position_blocks(const IndexVector& dofs, const Matrix& positions,
                                         int dim) {
    std::map<std::array<long, 3>, std::vector<Index>> members;
    for (Index l = 0; l < dofs.size(); ++l) {
        std::array<long, 3> cube{0, 0, 0};
        for (int d = 0; d < dim; ++d)
            cube[static_cast<std::size_t>(d)] =
                static_cast<long>(std::floor(positions(dofs[l] / dim, d)));
        members[cube].push_back(l);
    }
    const Index per_group = kMaxGroup / dim * dim;  // whole nodes
    std::vector<IndexVector> groups;
    for (const auto& [cube, m] : members)
        for (std::size_t first = 0; first < m.size();
             first += static_cast<std::size_t>(per_group)) {
            const std::size_t last =
                std::min(m.size(), first + static_cast<std::size_t>(per_group));
            groups.emplace_back(
                Eigen::Map<const IndexVector>(m.data() + first, static_cast<Index>(last - first)));
        }
    return groups;
}

}  // namespace coarsegrain::mra::detail
