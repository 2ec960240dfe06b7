// The relaxed cell-wise step (detail::relaxed_adapted_refinement, private to the library) with
// regions that do not span the level: its penalized operator A + p G^T G formed region by region
// (dense measurements G, as at the coarser steps) against the same sum formed whole.
#include <gtest/gtest.h>

#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "../../src/mra/detail.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/refinement.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra::detail {
namespace {

/// A with an explicit zero at every (i, j) not stored: the same operator, whose entries now bound
/// any product G^T G, so relaxed_adapted_refinement forms A + p G^T G whole.
SparseMatrix with_full_pattern(const SparseMatrix& A) {
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index j = 0; j < A.cols(); ++j)
        for (Index i = 0; i < A.rows(); ++i) t.emplace_back(i, j, A.coeff(i, j));
    SparseMatrix full(A.rows(), A.cols());
    full.setFromTriplets(t.begin(), t.end());
    return full;
}

/// C plus, in `dense_rows` rows spread over it (every row if negative), entries of size 0.1 at
/// random in a `density` fraction of the columns: measurements whose G^T G is much denser than A,
/// as the composed measurements of a coarser step.
SparseMatrix dense_measurements(const SparseMatrix& C, int dense_rows, double density) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> value(-0.1, 0.1), coin(0.0, 1.0);
    Matrix G(C);
    const Index stride = dense_rows < 0 ? 1 : std::max<Index>(1, G.rows() / dense_rows);
    for (Index i = 0; i < G.rows(); i += stride)
        for (Index j = 0; j < G.cols(); ++j)
            if (coin(rng) < density) G(i, j) += value(rng);
    return G.sparseView();
}

struct RegionCase {
    int dim;
    int dense_rows;  ///< rows of G given random entries (-1: all; 0: G = C, of Dirac refinement)
    double density;  ///< the fraction of their columns that get one
    int rings;
};

void PrintTo(const RegionCase& c, std::ostream* out) {
    *out << c.dim << "D, " << c.dense_rows << " dense rows, density " << c.density << ", "
         << c.rings << " rings";
}

class MraRelaxedRegions : public ::testing::TestWithParam<RegionCase> {};

TEST_P(MraRelaxedRegions, PenalizedBlocksFormedByRegionEqualTheSumFormedWhole) {
    // The same regions, right-hand sides and local systems; only where A + p G^T G is formed
    // differs: gathered per region (G[:, S]^T G[:, S] by BLAS dsyrk on small or dense blocks, by
    // a sparse product on sparse ones) or whole by a sparse product, or by region from A's lower
    // triangle (dense blocks read only their lower triangles, sparse ones are mirrored: with the
    // Dirac refinement's measurements, G^T G is diagonal and the regions' systems are sparse
    // enough for CHOLMOD, which reads them in a fill-reducing order). The densities are chosen so
    // that G^T G's work bound, sum_r nnz(G[r, :])^2, lies between 4 nnz(A) and 4 #unknowns^2:
    // above the first A gets the blocks by region, below the second its full pattern gets the
    // whole sum. 1 ring: regions of at most 100 unknowns, the dense branch; 2 rings in 3D: up to
    // 648, sparse. Equal up to the summation order: measured 5e-17 to 4e-16 relative; asserted
    // below 1e-12, which a penalty 1e-6 off in either branch exceeds.
    const auto [dim, dense_rows, density, rings] = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(16, 16, 1) : Eigen::Vector3i(8, 8, 8);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e2, test::checker_pattern);
    StepGeometry g;
    g.dim = dim;
    g.fine_cells = cells;
    g.coarse_cells = dim == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
    g.fine_spacing = Eigen::Vector3d::Constant(1.0 / cells[0]);
    g.fine_dofs = fem::free_dofs(p.mesh.num_dofs(), p.bc);
    g.coarse_dofs = IndexVector::LinSpaced(dim * grid_nodes(g.coarse_cells, dim), 0,
                                           dim * grid_nodes(g.coarse_cells, dim) - 1);
    const SparseMatrix A = fem::reduce(p.K, p.f, p.bc).K;
    const Refinement refinement = dense_rows == 0 ? Refinement::Dirac : Refinement::Linear;
    const SparseMatrix C_all =
        expand_to_dofs(canonical_refinement(g.coarse_cells, dim, refinement), dim);
    SparseMatrix C(C_all.rows(), g.fine_dofs.size());
    for (Index l = 0; l < g.fine_dofs.size(); ++l) C.col(l) = C_all.col(g.fine_dofs[l]);
    const SparseMatrix G = dense_rows == 0 ? C : dense_measurements(C, dense_rows, density);
    SparseMatrix Phi(A.rows(), A.rows());
    Phi.setIdentity();
    const std::vector<CellStiffness> parts = cell_stiffness(
        p.mesh, p.materials, g.fine_dofs, g.coarse_cells, 1, fem::Formulation::Standard);
    ASSERT_FALSE(regions_span_level(parts, rings, g));
    const Matrix by_region(relaxed_adapted_refinement(A, C, G, Phi, parts, g, rings, 3.0));
    const Matrix whole(
        relaxed_adapted_refinement(with_full_pattern(A), C, G, Phi, parts, g, rings, 3.0));
    const SparseMatrix A_lower = A.triangularView<Eigen::Lower>();
    const Matrix by_region_lower(
        relaxed_adapted_refinement(A_lower, C, G, Phi, parts, g, rings, 3.0, Stored::Lower));
    EXPECT_GT(by_region.norm(), 0.0);
    EXPECT_LT((by_region - whole).norm(), 1e-12 * whole.norm());
    EXPECT_LT((by_region_lower - by_region).norm(), 1e-12 * by_region.norm());
}

INSTANTIATE_TEST_SUITE_P(Cases, MraRelaxedRegions,
                         ::testing::Values(RegionCase{2, -1, 0.1, 1}, RegionCase{2, -1, 0.1, 2},
                                           RegionCase{3, -1, 0.08, 1}, RegionCase{3, -1, 0.08, 2},
                                           RegionCase{3, 2, 0.5, 2}, RegionCase{3, 0, 0.0, 2}),
                         [](const auto& param) {
                             const RegionCase& c = param.param;
                             return std::to_string(c.dim) + "D_" +
                                    (c.dense_rows < 0    ? std::string("all_rows")
                                     : c.dense_rows == 0 ? std::string("dirac")
                                                         : std::to_string(c.dense_rows) + "_rows") +
                                    "_" + std::to_string(c.rings) + "_rings";
                         });

}  // namespace
}  // namespace coarsegrain::mra::detail
