#pragma once
/// @file A sparse matrix stored by column groups and row runs: how the hierarchy keeps its adapted
/// refinements C̃^k.
#include <cstddef>
#include <span>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::mra {

/// A column-major sparse matrix in a variable-block layout (Saad's VBR format, by columns):
/// consecutive columns with the same row pattern form a group, and a group's pattern is stored
/// once, as runs of consecutive rows. The values are those of the compressed CSC matrix, in its
/// order. In C̃^k a group is the dim columns of a fine node (its 3x3 blocks C̃_ij, Sec. 3.1) and
/// a run the coarse DOFs of the nodes along x whose regions hold it. Measured at Table 1's
/// setting (40x20x20 hexes, rho = 5 fine rings, truncation 1e-7): C̃^1 takes 8.6 bytes per
/// entry against CSC's 12 (190 against 266 MB). A matrix of short runs and single-column groups
/// can take more than CSC (up to 16 bytes per entry).
/// Products are dense along the runs.
class RunMatrix {
  public:
    RunMatrix() = default;
    /// M's entries, bit for bit (explicitly stored zeros included).
    explicit RunMatrix(const SparseMatrix& M);
    /// M's entries, as above, M's storage returned to the system as it is read (on Linux, every
    /// kReleaseEntries entries) and M left empty: M and the runs are not held at once (the build
    /// stores C̃^{q-1} so after the solves that read it: 6.1e8 entries on the 64^3 checker with 4
    /// fine rings, 7.3 GB as CSC, about 4.9 GB as runs).
    explicit RunMatrix(SparseMatrix&& M);

    Index rows() const { return m_rows; }
    Index cols() const { return m_cols; }
    Index nonZeros() const { return static_cast<Index>(m_values.size()); }
    /// The stored values, column after column (those of the compressed CSC matrix).
    std::span<const double> values() const { return m_values; }
    /// Bytes kept: values, runs and the groups' offsets.
    std::size_t bytes() const;
    /// The matrix as a compressed Eigen one (entries bit for bit).
    SparseMatrix sparse() const;
    /// M x, x #cols by n.
    Matrix operator*(const Eigen::Ref<const Matrix>& x) const;
    /// M^T y, y #rows by n.
    Matrix transpose_times(const Eigen::Ref<const Matrix>& y) const;

  private:
    struct Run {
        Index first;   ///< first row
        Index length;  ///< number of consecutive rows
    };
    Index m_rows = 0;
    Index m_cols = 0;
    std::vector<Index> m_group_first{0};  ///< group g: columns [m_group_first[g], ...[g + 1])
    std::vector<Index> m_group_runs{0};   ///< group g: m_runs[m_group_runs[g] .. [g + 1])
    /// group g: its columns' values from m_group_values[g], one column after the other.
    std::vector<Index> m_group_values{0};
    std::vector<Run> m_runs;
    std::vector<double> m_values;

    /// Entries read between two releases of a moved-from matrix's pages (12 MB).
    static constexpr Index kReleaseEntries = 1 << 20;

    /// Reads m's (compressed) groups, runs and values; with `release`, returns the pages of m's
    /// arrays read to the system as it goes (m is then left unreadable).
    void read(const SparseMatrix& m, bool release);
    Index groups() const { return static_cast<Index>(m_group_first.size()) - 1; }
    /// Rows per column of group g.
    Index pattern_size(Index g) const;
};

}  // namespace coarsegrain::mra
