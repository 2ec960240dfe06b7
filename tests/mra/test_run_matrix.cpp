// RunMatrix (C̃^k's storage): exact round trip to CSC, products against Eigen's, bytes by hand,
// and the compression on a 3D localized hierarchy.
#include <gtest/gtest.h>

#include <random>

#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/mra/run_matrix.hpp"
#include "mra_test_util.hpp"
#include "test_util.hpp"

namespace coarsegrain::mra {
namespace {

/// A rows x cols matrix in C̃'s shape: column groups of `group` columns share a pattern of a few
/// runs, with an empty column, a singleton pattern and an explicitly stored zero among them.
SparseMatrix blocky_matrix(Index rows, Index cols, int group, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    std::uniform_int_distribution<Index> start(0, rows - 1), length(1, 12);
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index j0 = 0; j0 < cols; j0 += group) {
        std::vector<Index> pattern;
        const int runs = j0 % 7 == 0 ? 0 : 1 + static_cast<int>(j0 % 4);  // some columns empty
        for (int r = 0; r < runs; ++r)
            for (Index i = start(rng), n = length(rng); n > 0 && i < rows; ++i, --n)
                pattern.push_back(i);
        std::sort(pattern.begin(), pattern.end());
        pattern.erase(std::unique(pattern.begin(), pattern.end()), pattern.end());
        for (Index j = j0; j < std::min(cols, j0 + group); ++j)
            for (const Index i : pattern) t.emplace_back(i, j, value(rng));
    }
    SparseMatrix M(rows, cols);
    M.setFromTriplets(t.begin(), t.end());
    M.coeffRef(rows - 1, cols - 1) = 0.0;  // an explicitly stored zero
    M.makeCompressed();
    return M;
}

void expect_same_storage(const SparseMatrix& a, const SparseMatrix& b) {
    ASSERT_EQ(a.rows(), b.rows());
    ASSERT_EQ(a.cols(), b.cols());
    ASSERT_EQ(a.nonZeros(), b.nonZeros());
    for (Index j = 0; j <= a.cols(); ++j) EXPECT_EQ(a.outerIndexPtr()[j], b.outerIndexPtr()[j]);
    for (Index p = 0; p < a.nonZeros(); ++p) {
        EXPECT_EQ(a.innerIndexPtr()[p], b.innerIndexPtr()[p]);
        EXPECT_EQ(a.valuePtr()[p], b.valuePtr()[p]);  // bit for bit
    }
}

TEST(RunMatrix, KeepsEveryEntryBitForBit) {
    for (const int group : {1, 2, 3}) {
        const SparseMatrix M = blocky_matrix(300, 240, group, 7u + group);
        const RunMatrix R(M);
        EXPECT_EQ(R.rows(), 300);
        EXPECT_EQ(R.cols(), 240);
        EXPECT_EQ(R.nonZeros(), M.nonZeros());
        expect_same_storage(R.sparse(), M);
    }
    // An uncompressed input, and empty shapes.
    SparseMatrix U(5, 4);
    U.reserve(Eigen::VectorXi::Constant(4, 3));
    U.insert(3, 1) = 2.0;
    U.insert(4, 1) = -1.0;
    U.insert(0, 3) = 5.0;
    SparseMatrix Uc = U;
    Uc.makeCompressed();
    expect_same_storage(RunMatrix(U).sparse(), Uc);
    for (const auto& [r, c] : {std::pair{0, 0}, std::pair{5, 0}, std::pair{0, 5}}) {
        const RunMatrix E{SparseMatrix(r, c)};
        EXPECT_EQ(E.sparse().rows(), r);
        EXPECT_EQ(E.sparse().cols(), c);
        EXPECT_EQ((E * Matrix::Ones(c, 2)).rows(), r);
        EXPECT_EQ(E.transpose_times(Matrix::Ones(r, 2)).rows(), c);
    }
}

// From a moved matrix, whose pages are returned to the system as they are read (every 2^20
// entries): the same storage, bit for bit, over a matrix of several such spans, and the moved
// one left empty.
TEST(RunMatrix, FromAMovedMatrixKeepsEveryEntryBitForBit) {
    const SparseMatrix M = blocky_matrix(3000, 240000, 3, 5u);
    ASSERT_GT(M.nonZeros(), 3 << 20);
    SparseMatrix moved = M;
    const RunMatrix R(std::move(moved));
    EXPECT_EQ(moved.nonZeros(), 0);
    expect_same_storage(R.sparse(), M);
}

TEST(RunMatrix, ProductsAreEigensToRoundOff) {
    // Large enough for the parallel paths (>= 65,536 entries), and one right-hand side (serial).
    const SparseMatrix M = blocky_matrix(2000, 30000, 3, 11u);
    ASSERT_GE(M.nonZeros(), 1 << 16);
    const RunMatrix R(M);
    std::mt19937 rng(3);
    std::normal_distribution<double> normal;
    for (const Index n : {1, 4}) {
        const Matrix x = Matrix::NullaryExpr(M.cols(), n, [&] { return normal(rng); });
        const Matrix y = Matrix::NullaryExpr(M.rows(), n, [&] { return normal(rng); });
        // Each entry is a sum of at most ~40 products: the summation orders differ by at most
        // ~40 eps |M| |x| (|M|, |x| <= 1 and ~N(0,1)).
        EXPECT_LT((R * x - M * x).cwiseAbs().maxCoeff(), 1e-13) << n;
        EXPECT_LT((R.transpose_times(y) - M.transpose() * y).cwiseAbs().maxCoeff(), 1e-13) << n;
    }
    // A vector argument binds without a copy and returns a column.
    const Vector v = Vector::Ones(M.cols());
    const Vector Rv = R * v;
    EXPECT_LT((Rv - M * v).cwiseAbs().maxCoeff(), 1e-13);
    test::expect_error([&] { (void)(R * Vector::Ones(3)); }, "3 rows to multiply");
    test::expect_error([&] { (void)R.transpose_times(Vector::Ones(3)); }, "3 rows to multiply");
}

TEST(RunMatrix, BytesCountValuesRunsAndGroups) {
    // Columns 0 and 1 share rows {0, 1, 2, 4} (one group, runs [0, 3) and [4, 5)), column 2 is
    // empty (a group without runs), column 3 holds row 5 (one run).
    SparseMatrix M(6, 4);
    for (const Index j : {0, 1})
        for (const Index i : {0, 1, 2, 4}) M.insert(i, j) = 1.0 + i + 10 * j;
    M.insert(5, 3) = 7.0;
    M.makeCompressed();
    const RunMatrix R(M);
    // 9 values (8 bytes each), 3 runs (two ints), 3 groups + 1 sentinel (first column, first
    // run, first value: three ints).
    EXPECT_EQ(R.bytes(), 9u * 8 + 3u * 8 + 4u * 12);
    expect_same_storage(R.sparse(), M);
}

TEST(RunMatrix, KeepsALocalizedAdaptedRefinementInUnderNineBytesPerEntry) {
    // C̃^1 of a 3D hierarchy at rho = 3 fine rings: a group is a fine node's 3 columns (split
    // where the fixed face gives them different patterns; the truncation drops a row's entries
    // at a node together), a run the coarse DOFs of the nodes along x whose regions hold it.
    // CSC takes 12 bytes per entry. Measured 8.263, and 8.495 while the truncation dropped
    // entries one by one (splitting groups).
    const Eigen::Vector3i cells(16, 8, 8);
    const test::GridProblem p = test::hung_problem(3, cells, 1.0, 1e3, test::checker_pattern,
                                                   cells.cast<double>() / cells[1]);
    Options o;
    o.levels = 2;
    o.radius = {3};
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
    const RunMatrix& C = h.level(1).C_adapted;
    const double per_entry = static_cast<double>(C.bytes()) / C.nonZeros();
    std::printf("C: %d entries, %.3f bytes per entry\n", C.nonZeros(), per_entry);
    EXPECT_LT(per_entry, 8.35);
}

}  // namespace
}  // namespace coarsegrain::mra
