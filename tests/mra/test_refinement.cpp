// Canonical refinement, left inverse and kernel (Chen et al. 2019, Sec. 3.2 and 3.7).
#include <gtest/gtest.h>

#include <tuple>

#include "coarsegrain/mra/refinement.hpp"

namespace coarsegrain::mra {
namespace {

using RefinementParam = std::tuple<int, Refinement>;

class MraRefinement : public ::testing::TestWithParam<RefinementParam> {
  protected:
    int dim() const { return std::get<0>(GetParam()); }
    Refinement refinement() const { return std::get<1>(GetParam()); }
    Eigen::Vector3i coarse_cells() const {
        return dim() == 2 ? Eigen::Vector3i(3, 2, 1) : Eigen::Vector3i(2, 3, 2);
    }
    // All DOFs of the fine grid present.
    IndexVector all_fine_dofs() const {
        const Index n = dim() * grid_nodes(2 * coarse_cells(), dim());
        return IndexVector::LinSpaced(n, 0, n - 1);
    }
    // Fine DOFs without those of the nodes on the face y = max (a clamped face), and without the
    // x component of the nodes on x = 0 (a roller).
    IndexVector clamped_fine_dofs() const {
        const Eigen::Vector3i fc = 2 * coarse_cells();
        std::vector<Index> keep;
        for (Index v = 0; v < grid_nodes(fc, dim()); ++v) {
            const Eigen::Vector3i x = node_coordinates(v, fc, dim());
            if (x[1] == fc[1]) continue;
            for (int d = 0; d < dim(); ++d)
                if (!(x[0] == 0 && d == 0)) keep.push_back(dim() * v + d);
        }
        return Eigen::Map<IndexVector>(keep.data(), static_cast<Index>(keep.size()));
    }
};

// All weights are powers of two and every sum has at most 27 of them, so C W^T and C† C^T are
// computed without round-off: the identities are asserted exactly.
void expect_exact_identities(const RefinementOperators& ops) {
    const Matrix CWt = Matrix(ops.C * SparseMatrix(ops.W.transpose()));
    EXPECT_EQ(CWt.cwiseAbs().maxCoeff(), 0.0);
    const Matrix CdCt = Matrix(ops.C_dagger * SparseMatrix(ops.C.transpose()));
    EXPECT_EQ((CdCt - Matrix::Identity(CdCt.rows(), CdCt.cols())).cwiseAbs().maxCoeff(), 0.0);
    // Counting: the wavelets complete the coarse DOFs to the fine DOFs, and W has full row rank
    // (checked by the rank of a dense QR; the matrices are tiny).
    EXPECT_EQ(ops.W.rows() + ops.C.rows(), ops.C.cols());
    const Eigen::ColPivHouseholderQR<Matrix> qr{Matrix(ops.W)};
    EXPECT_EQ(qr.rank(), ops.W.rows());
}

TEST_P(MraRefinement, KernelAndLeftInverseAreExact) {
    const SparseMatrix C = canonical_refinement(coarse_cells(), dim(), refinement());
    const auto coincident = coincident_nodes(coarse_cells(), dim());
    const RefinementOperators ops =
        refinement_operators(C, coincident, dim(), all_fine_dofs(), false);
    EXPECT_EQ(ops.C.rows(), dim() * C.rows());
    EXPECT_EQ(ops.dropped_dofs.size(), 0);
    expect_exact_identities(ops);
    if (refinement() == Refinement::Dirac) {
        // Dirac: C† = C is also the Moore-Penrose inverse (C C^T = I).
        EXPECT_EQ(Matrix(ops.C_dagger - ops.C).cwiseAbs().maxCoeff(), 0.0);
    }
}

TEST_P(MraRefinement, KernelAndLeftInverseAreExactWithAbsentDofs) {
    const SparseMatrix C = canonical_refinement(coarse_cells(), dim(), refinement());
    const auto coincident = coincident_nodes(coarse_cells(), dim());
    const IndexVector fine = clamped_fine_dofs();
    for (const bool keep : {false, true}) {
        const RefinementOperators ops = refinement_operators(C, coincident, dim(), fine, keep);
        expect_exact_identities(ops);
        EXPECT_EQ(ops.coarse_dofs.size() + ops.dropped_dofs.size(), dim() * C.rows());
        // Eliminating drops every coarse DOF whose coincident fine DOF is absent; keeping
        // boundary rows retains them for the linear refinement (each has an exclusive pivot
        // one cell inside) and drops them for Dirac (their restricted rows vanish). The one
        // exception: the x components on the edge where the roller meets the clamped face (one
        // node in 2D, a row of cc[2] + 1 nodes in 3D), whose only present fine DOFs are also
        // weighted by the roller node below them, so no pivot is exclusive.
        const Eigen::Vector3i cc = coarse_cells();
        Index on_boundary = 0;
        for (Index v = 0; v < C.rows(); ++v) {
            const Eigen::Vector3i x = node_coordinates(v, cc, dim());
            if (x[1] == cc[1])
                on_boundary += dim();
            else if (x[0] == 0)
                on_boundary += 1;
        }
        const bool kept = keep && refinement() == Refinement::Linear;
        EXPECT_EQ(ops.dropped_dofs.size(), kept ? (dim() == 2 ? 1 : cc[2] + 1) : on_boundary);
    }
}

TEST_P(MraRefinement, LinearRefinementInterpolatesLinearFields) {
    // C^T carries coarse nodal values to fine ones: linear refinement reproduces the bilinear /
    // trilinear interpolant (exact for affine fields), Dirac keeps the coincident values only.
    const Eigen::Vector3i cc = coarse_cells();
    const SparseMatrix C = canonical_refinement(cc, dim(), refinement());
    const auto field = [](const Eigen::Vector3i& x, double h) {
        return 0.5 + 1.25 * x[0] * h - 0.75 * x[1] * h + 2.0 * x[2] * h;
    };
    Vector coarse(C.rows());
    for (Index v = 0; v < C.rows(); ++v) coarse[v] = field(node_coordinates(v, cc, dim()), 2.0);
    const Vector fine = C.transpose() * coarse;
    const auto coincident = coincident_nodes(cc, dim());
    std::vector<char> is_coincident(static_cast<std::size_t>(C.cols()), 0);
    for (const Index j : coincident) is_coincident[static_cast<std::size_t>(j)] = 1;
    for (Index j = 0; j < C.cols(); ++j) {
        const double expected = refinement() == Refinement::Linear || is_coincident[j]
                                    ? field(node_coordinates(j, 2 * cc, dim()), 1.0)
                                    : 0.0;
        // Sums of at most 8 products of powers of two with a few-digit field: 1e-14.
        EXPECT_NEAR(fine[j], expected, 1e-14) << "fine node " << j;
    }
}

INSTANTIATE_TEST_SUITE_P(Mra, MraRefinement,
                         ::testing::Combine(::testing::Values(2, 3),
                                            ::testing::Values(Refinement::Dirac,
                                                              Refinement::Linear)),
                         [](const auto& p) {
                             return std::to_string(std::get<0>(p.param)) + "D_" +
                                    (std::get<1>(p.param) == Refinement::Dirac ? "Dirac"
                                                                               : "Linear");
                         });

TEST(MraRefinementExpand, KroneckerWithIdentity) {
    SparseMatrix S(2, 3);
    S.insert(0, 1) = 0.5;
    S.insert(1, 2) = -2.0;
    const Matrix E = Matrix(expand_to_dofs(S, 3));
    Matrix expected = Matrix::Zero(6, 9);
    expected.block(0, 3, 3, 3) = 0.5 * Matrix::Identity(3, 3);
    expected.block(3, 6, 3, 3) = -2.0 * Matrix::Identity(3, 3);
    EXPECT_EQ((E - expected).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace coarsegrain::mra
