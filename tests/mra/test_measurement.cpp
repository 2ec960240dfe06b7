// Stiffness-weighted measurements (Measurement::Stiffness, weighted_refinement): the weighted
// quasi-interpolation of Peterseim-Scheichl / Hellman-Målqvist in the material-adapted hierarchy.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "coarsegrain/mra/multilevel_solver.hpp"
#include "coarsegrain/mra/refinement.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

Options stiffness_options(int levels) {
    Options o = test::exact_options(levels, Refinement::Linear);
    o.measurement = Measurement::Stiffness;
    return o;
}

double coarsest_error(const test::GridProblem& p, const Options& o) {
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
    MultilevelSolver s(h);
    return test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u);
}

TEST(MraMeasurementWeights, UniformOnOneMaterialAndScaledByTheStiffness) {
    // Every node of a one-material grid, corners and faces included, gets the same weight: the
    // element diagonal is the same at every corner of every element (reflection symmetry).
    for (const int dim : {2, 3}) {
        const Eigen::Vector3i cells =
            dim == 2 ? Eigen::Vector3i(4, 3, 1) : Eigen::Vector3i(4, 3, 2);
        const test::GridProblem p =
            test::hung_problem(dim, cells, 5.0, 5.0, [](const Eigen::VectorXd&) { return 1; });
        const Vector w = stiffness_weights(p.K, p.mesh.elements, dim);
        EXPECT_LT((w.array() - w[0]).abs().maxCoeff(), 1e-12 * w[0]) << dim << "D";
        // Linear in the stiffness: E 1000 times larger, weights 1000 times larger.
        const test::GridProblem q =
            test::hung_problem(dim, cells, 5e3, 5e3, [](const Eigen::VectorXd&) { return 1; });
        EXPECT_NEAR(stiffness_weights(q.K, q.mesh.elements, dim)[0], 1e3 * w[0], 1e-9 * w[0]);
    }
}

TEST(MraMeasurementWeights, WeightedRowsKeepTheirCoincidentCoefficient) {
    const Eigen::Vector3i coarse(2, 2, 1);
    const SparseMatrix C = canonical_refinement(coarse, 2, Refinement::Linear);
    const std::vector<Index> coincident = coincident_nodes(coarse, 2);
    Vector w(C.cols());
    for (Index j = 0; j < w.size(); ++j) w[j] = 1.0 + 0.5 * static_cast<double>(j % 7);
    const SparseMatrix Cw = weighted_refinement(C, coincident, w);
    ASSERT_EQ(Cw.nonZeros(), C.nonZeros());
    for (Index i = 0; i < C.rows(); ++i) {
        const Index p = coincident[static_cast<std::size_t>(i)];
        EXPECT_DOUBLE_EQ(Cw.coeff(i, p), 1.0);
        for (Index j = 0; j < C.cols(); ++j)
            EXPECT_DOUBLE_EQ(Cw.coeff(i, j), C.coeff(i, j) * w[j] / w[p]);
    }
    EXPECT_THROW(weighted_refinement(C, coincident, Vector::Ones(3)), Error);
}

TEST(MraMeasurement, OneMaterialGivesTheCanonicalHierarchy) {
    const test::GridProblem p = test::hung_problem(2, Eigen::Vector3i(8, 8, 1), 7.0, 7.0,
                                                   [](const Eigen::VectorXd&) { return 1; });
    const Hierarchy hc =
        build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(3, Refinement::Linear));
    const Hierarchy hs = build_hierarchy(p.mesh, p.K, p.bc.dofs, stiffness_options(3));
    for (int k = 1; k < hc.num_levels(); ++k) {
        const Matrix Ac(hc.level(k).A);
        EXPECT_LT((Ac - Matrix(hs.level(k).A)).norm(), 1e-12 * Ac.norm()) << "level " << k;
    }
}

class MraMeasurementExact : public ::testing::TestWithParam<int> {};

TEST_P(MraMeasurementExact, GlobalSolvesReproduceTheFineSolution) {
    // Any nested measurements give A-orthogonal wavelets with global solves (Eq. 12), so the
    // multilevel solve is exact: 1e-9 as for the canonical hierarchy (tests/mra/test_hierarchy).
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, test::checker_pattern);
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, stiffness_options(3));
    MultilevelSolver s(h);
    const Vector u = s.solve(p.f);
    EXPECT_LT((u - p.u).norm(), 1e-9 * p.u.norm());
    // ... with measurements that are not the canonical ones (contrast 1000 in the weights).
    const Hierarchy hc =
        build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(3, Refinement::Linear));
    const SparseMatrix& Cc = hc.level(hc.num_levels() - 1).C;
    EXPECT_GT((Matrix(h.level(h.num_levels() - 1).C) - Matrix(Cc)).norm(), 0.1 * Matrix(Cc).norm());
}

INSTANTIATE_TEST_SUITE_P(Dims, MraMeasurementExact, ::testing::Values(2, 3),
                         [](const ::testing::TestParamInfo<int>& i) {
                             return std::to_string(i.param) + "D";
                         });

TEST(MraMeasurementLocalized, StiffnessWeightsLocalizeALayeredColumn) {
    // A 1x4 column of layers 0.25 thick across its axis (contrast 1000), hung from its top under
    // gravity and a pull, 8x32 quads, one step to 4x16: each coarse cell is one layer, so every
    // coarse node sits on a stiff/soft interface and each stiff layer spans the width. With the
    // canonical measurements the cell-wise localized solves lock even when the regions (8 fine
    // rings) span the width and half the height; the stiffness-weighted measurements
    // give the global construction's error. Measured coarsest energy errors: canonical global
    // 0.00102, cell-wise 0.603; stiffness global 0.00641, cell-wise 0.00641. The weighted
    // global space is 6x less accurate than the canonical one here: a coarse node measures the
    // stiff layer, and the soft layer's stretching is left to the wavelets. Asserted: the weighted
    // cell-wise error within 1.5x of its global one and below a third
    // of the canonical cell-wise error.
    const test::GridProblem p = test::hung_problem(2, Eigen::Vector3i(8, 32, 1), 1e4, 1e7,
                                                   test::layers_across_y, Eigen::Vector3d(1, 4, 1));
    Options cc = test::exact_options(2, Refinement::Linear);
    const double canonical_global = coarsest_error(p, cc);
    cc.radius = {8};
    cc.localization = Localization::Cell;
    const double canonical_cell = coarsest_error(p, cc);
    Options sc = stiffness_options(2);
    const double stiffness_global = coarsest_error(p, sc);
    sc.radius = {8};
    sc.localization = Localization::Cell;
    const double stiffness_cell = coarsest_error(p, sc);
    std::printf(
        "layered column: canonical global %.4g cell %.4g; stiffness global %.4g cell %.4g\n",
        canonical_global, canonical_cell, stiffness_global, stiffness_cell);
    EXPECT_LT(stiffness_cell, 1.5 * stiffness_global);
    EXPECT_LT(stiffness_cell, canonical_cell / 3);
}

}  // namespace
}  // namespace coarsegrain::mra
