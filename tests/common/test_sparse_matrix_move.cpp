// Move semantics of Eigen::SparseMatrix (include/coarsegrain/common/sparse_matrix_plugin.hpp):
// moves hand the storage over instead of copying the entries.
#include <gtest/gtest.h>

#include <type_traits>
#include <utility>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain {
namespace {

SparseMatrix diagonal(Index n, double value) {
    SparseMatrix M(n, n);
    for (Index i = 0; i < n; ++i) M.insert(i, i) = value;
    M.makeCompressed();
    return M;
}

TEST(SparseMatrixMove, ConstructionTakesTheStorage) {
    SparseMatrix a = diagonal(100, 2.0);
    const double* values = a.valuePtr();
    const SparseMatrix b(std::move(a));
    EXPECT_EQ(b.valuePtr(), values);
    EXPECT_EQ(b.nonZeros(), 100);
    EXPECT_EQ(b.coeff(99, 99), 2.0);
    EXPECT_EQ(a.rows(), 0);  // NOLINT(bugprone-use-after-move): the moved-from state is the API
    EXPECT_EQ(a.nonZeros(), 0);
}

TEST(SparseMatrixMove, AssignmentTakesTheStorageAndFreesTheOld) {
    SparseMatrix a = diagonal(100, 2.0), b = diagonal(7, 3.0);
    const double* values = a.valuePtr();
    b = std::move(a);
    EXPECT_EQ(b.valuePtr(), values);
    EXPECT_EQ(b.rows(), 100);
    EXPECT_EQ(a.rows(), 0);  // NOLINT(bugprone-use-after-move)
    EXPECT_EQ(a.nonZeros(), 0);
    a = diagonal(5, 1.0);  // a moved-from matrix is usable
    EXPECT_EQ(a.coeff(4, 4), 1.0);
}

TEST(SparseMatrixMove, VectorsRelocateWithoutCopies) {
    std::vector<SparseMatrix> v;
    v.push_back(diagonal(50, 1.0));
    const double* values = v.front().valuePtr();
    for (int i = 0; i < 20; ++i) v.push_back(diagonal(3, 1.0));  // reallocates
    EXPECT_EQ(v.front().valuePtr(), values);
    static_assert(std::is_nothrow_move_constructible_v<SparseMatrix>);
}

}  // namespace
}  // namespace coarsegrain
