#include "coarsegrain/mra/run_matrix.hpp"

#include <algorithm>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra {

namespace {

/// Products with fewer right-hand sides than this, or fewer entries than kMinParallelEntries, run
/// on one thread: the scatter of M x runs one right-hand side per thread.
constexpr Index kMinParallelColumns = 2;
constexpr Index kMinParallelEntries = 1 << 16;

}  // namespace

RunMatrix::RunMatrix(const SparseMatrix& M) : m_rows(M.rows()), m_cols(M.cols()) {
    if (M.isCompressed()) {
        read(M, false);
    } else {
        SparseMatrix compressed = M;
        compressed.makeCompressed();
        read(compressed, true);
    }
}

RunMatrix::RunMatrix(SparseMatrix&& M) : m_rows(M.rows()), m_cols(M.cols()) {
    M.makeCompressed();
    read(M, true);
    M = SparseMatrix();
}

void RunMatrix::read(const SparseMatrix& m, bool release) {
    const Index* outer = m.outerIndexPtr();
    const Index* inner = m.innerIndexPtr();
    m_values.reserve(static_cast<std::size_t>(outer[m_cols]));
    const auto same_pattern = [&](Index a, Index b) {
        return outer[a + 1] - outer[a] == outer[b + 1] - outer[b] &&
               std::equal(inner + outer[a], inner + outer[a + 1], inner + outer[b]);
    };
    Index released = 0;  // entries of m before this one are read no more
    for (Index j = 0; j < m_cols; ++j) {
        m_values.insert(m_values.end(), m.valuePtr() + outer[j], m.valuePtr() + outer[j + 1]);
        if (j > 0 && same_pattern(m_group_first.back(), j)) continue;
        if (j > 0) {
            m_group_first.push_back(j);
            m_group_runs.push_back(static_cast<Index>(m_runs.size()));
            m_group_values.push_back(outer[j]);
        }
        // The patterns of columns before this group's first are compared no more.
        if (release && outer[j] - released >= kReleaseEntries) {
            release_pages(m.valuePtr() + released, m.valuePtr() + outer[j]);
            release_pages(inner + released, inner + outer[j]);
            released = outer[j];
        }
        for (Index p = outer[j]; p < outer[j + 1]; ++p) {
            if (p > outer[j] && inner[p] == inner[p - 1] + 1)
                ++m_runs.back().length;
            else
                m_runs.push_back({inner[p], 1});
        }
    }
    if (m_cols > 0) {
        m_group_first.push_back(m_cols);
        m_group_runs.push_back(static_cast<Index>(m_runs.size()));
        m_group_values.push_back(outer[m_cols]);
    }
}

Index RunMatrix::pattern_size(Index g) const {
    return (m_group_values[g + 1] - m_group_values[g]) / (m_group_first[g + 1] - m_group_first[g]);
}

std::size_t RunMatrix::bytes() const {
    return m_values.size() * sizeof(double) + m_runs.size() * sizeof(Run) +
           m_group_first.size() * 3 * sizeof(Index);
}

SparseMatrix RunMatrix::sparse() const {
    SparseMatrix M(m_rows, m_cols);
    M.resizeNonZeros(static_cast<Index>(m_values.size()));
    Index* outer = M.outerIndexPtr();
    Index* inner = M.innerIndexPtr();
    std::copy(m_values.begin(), m_values.end(), M.valuePtr());
    outer[0] = 0;
    Index k = 0;
    for (Index g = 0; g < groups(); ++g)
        for (Index j = m_group_first[g]; j < m_group_first[g + 1]; ++j) {
            for (Index r = m_group_runs[g]; r < m_group_runs[g + 1]; ++r)
                for (Index t = 0; t < m_runs[r].length; ++t) inner[k++] = m_runs[r].first + t;
            outer[j + 1] = k;
        }
    return M;
}

Matrix RunMatrix::operator*(const Eigen::Ref<const Matrix>& x) const {
    CG_VERIFY(x.rows() == m_cols, "RunMatrix: {} rows to multiply by a {} x {} matrix", x.rows(),
              m_rows, m_cols);
    Matrix y = Matrix::Zero(m_rows, x.cols());
    const Index n = static_cast<Index>(x.cols());
#pragma omp parallel for schedule(static) if (n >= kMinParallelColumns && \
                                              nonZeros() >= kMinParallelEntries)
    for (Index c = 0; c < n; ++c) {
        auto yc = y.col(c);
        for (Index g = 0; g < groups(); ++g) {
            const Index size = pattern_size(g);
            const double* v = m_values.data() + m_group_values[g];
            for (Index j = m_group_first[g]; j < m_group_first[g + 1]; ++j, v += size) {
                const double xj = x(j, c);
                if (xj == 0.0) continue;
                const double* w = v;
                for (Index r = m_group_runs[g]; r < m_group_runs[g + 1]; ++r) {
                    const Run& run = m_runs[r];
                    yc.segment(run.first, run.length) +=
                        xj * Eigen::Map<const Vector>(w, run.length);
                    w += run.length;
                }
            }
        }
    }
    return y;
}

Matrix RunMatrix::transpose_times(const Eigen::Ref<const Matrix>& y) const {
    CG_VERIFY(y.rows() == m_rows,
              "RunMatrix: {} rows to multiply by the transpose of a {} x {} "
              "matrix",
              y.rows(), m_rows, m_cols);
    Matrix x(m_cols, y.cols());
#pragma omp parallel for schedule(dynamic, 64) if (nonZeros() >= kMinParallelEntries)
    for (Index g = 0; g < groups(); ++g) {
        const Index size = pattern_size(g);
        const double* v = m_values.data() + m_group_values[g];
        for (Index j = m_group_first[g]; j < m_group_first[g + 1]; ++j, v += size)
            for (Index c = 0; c < y.cols(); ++c) {
                double sum = 0;
                const double* w = v;
                for (Index r = m_group_runs[g]; r < m_group_runs[g + 1]; ++r) {
                    const Run& run = m_runs[r];
                    sum += Eigen::Map<const Vector>(w, run.length)
                               .dot(y.col(c).segment(run.first, run.length));
                    w += run.length;
                }
                x(j, c) = sum;
            }
    }
    return x;
}

}  // namespace coarsegrain::mra
