// Cell-wise localization of the solves for Z (Localization::Cell, the element-wise correctors of
// Localized Orthogonal Decomposition), against global solves and node-wise localization.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Options cell_options(int levels, Refinement r, double radius) {
    Options o = test::exact_options(levels, r);
    o.radius = {radius};
    o.localization = Localization::Cell;
    return o;
}

class MraCellLocalized : public ::testing::TestWithParam<int> {};

TEST_P(MraCellLocalized, RadiusCoveringTheGridEqualsGlobalSolves) {
    // sum_T A_T = A^q, so with every region spanning the grid sum_T R^T = R and Z is the global
    // one, at every step (the coarser steps use Φ^{k+1} A_T Φ^{k+1,T}); also with T a block of
    // patch^dim cells (patch 3: blocks of 3 and 1 cells per axis at the finest step).
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, test::checker_pattern);
    for (const Refinement r : {Refinement::Linear, Refinement::Dirac}) {
        const Options global = test::exact_options(3, r);
        const Hierarchy hg = build_hierarchy(p.mesh, p.K, p.bc.dofs, global);
        for (const int patch : {1, 2, 3}) {
            Options cell = cell_options(3, r, 8);
            cell.patch = patch;
            const Hierarchy hc = build_hierarchy(p.mesh, p.K, p.bc.dofs, cell, &p.materials);
            for (int k = 1; k < hg.num_levels(); ++k) {
                // Sums of local solves (dense / sparse Cholesky) against one CHOLMOD solve, with
                // condition numbers below ~1e6 and the element matrices summed in another order
                // than the assembly: 1e-10 relative.
                const SparseMatrix& Cg = hg.level(k).C_adapted.sparse();
                EXPECT_LT(Matrix(Cg - hc.level(k).C_adapted.sparse()).norm(),
                          1e-10 * Matrix(Cg).norm())
                    << refinement_name(r) << " patch " << patch << " level " << k;
            }
        }
    }
}

TEST_P(MraCellLocalized, RelaxedWithRegionsCoveringTheGridGivesTheGlobalSpace) {
    // With every region spanning the grid the relaxed C̃^T is (d / gamma) M^{-1} G^T G C^T, M = A
    // + (d / gamma) G^T G, which spans A^{-1} G^T (Woodbury): for every gamma the space of global
    // solves with the measurements G. At the finest step G = C; at a coarser one G = C^k ..
    // C^{q-1} Φ^{k+1,T} measures the fine functions as the global construction's coefficients
    // do, so with three levels the coarsest space is the global one too (measuring C^k of the
    // relaxed coefficients instead: 6-23% off in 2D, 46-94% in 3D). Their bases differ (C C̃^T !=
    // I), so the solutions are compared, not C̃. Cells alone and in blocks of 2^dim (one
    // corrector per block). Asserted to 1e-8 relative in the energy norm: the local systems'
    // condition numbers reach ~1e6 at gamma 0.1 with contrast 1e3. Three levels up to gamma 3:
    // as gamma grows C̃^T = C^T - M^{-1} A C^T shrinks by cancellation, and two relaxed steps
    // lose digits to it (2D: 1.4e-6 relative at gamma 100, 1.1e-4 at 300).
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, test::checker_pattern);
    const auto solution = [&](const Options& o) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
        MultilevelSolver s(h);
        return Vector(s.solve_level(p.f, 1));
    };
    for (const int levels : {2, 3}) {
        const Vector u_global = solution(test::exact_options(levels, Refinement::Linear));
        for (const int patch : {1, 2})
            for (const double gamma : {0.1, 3.0, 100.0}) {
                if (levels == 3 && gamma > 3) continue;
                Options relaxed = cell_options(levels, Refinement::Linear, 8);
                relaxed.relaxation = gamma;
                relaxed.patch = patch;
                const Vector u = solution(relaxed);
                EXPECT_LT(test::energy_norm(p.K, u - u_global),
                          1e-8 * test::energy_norm(p.K, u_global))
                    << levels << " levels, gamma " << gamma << " patch " << patch;
                // An infinite radius is the same step on the whole level, at any step: the
                // same computation, so equal up to the summation order of threaded reductions
                // (1e-13 relative).
                const std::vector<std::vector<double>> infinite =
                    levels == 2
                        ? std::vector<std::vector<double>>{{kInf}}
                        : std::vector<std::vector<double>>{{kInf, 8}, {8, kInf}, {kInf, kInf}};
                for (const std::vector<double>& radius : infinite) {
                    relaxed.radius = radius;
                    EXPECT_LT(test::energy_norm(p.K, solution(relaxed) - u),
                              1e-13 * test::energy_norm(p.K, u))
                        << levels << " levels, gamma " << gamma << " patch " << patch << ", radius "
                        << radius.front() << ", " << radius.back();
                }
            }
    }
}

TEST_P(MraCellLocalized, RelaxedConstructionKeepsTheWaveletStiffness) {
    // The relaxed solves do not read B^k = W^k A^{k+1} W^{k,T}, which is then formed as the
    // hierarchy keeps it, its lower triangle (a grouped congruence); against Eigen's products,
    // the same sums in another order: 1e-12 relative.
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(16, 16, 1) : Eigen::Vector3i(8, 8, 8);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, test::checker_pattern);
    Options o = cell_options(3, Refinement::Linear, 2);
    o.relaxation = 3;
    o.patch = 2;
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
    for (int k = 1; k < 3; ++k) {
        const Level& L = h.level(k);
        const SparseMatrix A = k == 2 ? h.A_fine : symmetric_from_lower(h.level(k + 1).A);
        const Matrix B = Matrix(L.W * A * SparseMatrix(L.W.transpose()));
        ASSERT_GT(L.B.rows(), 0) << "level " << k;
        EXPECT_EQ(Matrix(L.B).triangularView<Eigen::StrictlyUpper>().toDenseMatrix().norm(), 0.0);
        EXPECT_LT((Matrix(symmetric_from_lower(L.B)) - B).norm(), 1e-12 * B.norm())
            << "level " << k;
    }
}

TEST_P(MraCellLocalized, RelaxedOnEveryWholeLevelIsTheGlobalHierarchy) {
    // An infinite radius with relaxation takes each step on the whole level in the basis of its
    // measurements G, C̃^T = A^{-1} G^T (G A^{-1} G^T)^{-1}: at the finest step G = C, which is
    // the global construction's C̃ (C C̃^T = I, least energy); then G = C^k C^{k+1} Φ^{k+1,T} =
    // C^k, since C^{k+1} C̃^{k+1,T} = I. So every level equals the global hierarchy's, computed
    // another way (one factorization of A^{k+1} instead of B^k's wavelet solves): 1e-10 relative,
    // as RadiusCoveringTheGridEqualsGlobalSolves. In 2D the finest step has over 256 measurements,
    // so its solves with G^T run in blocks (whole_level_refinement takes 256 columns at a time).
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(32, 32, 1) : Eigen::Vector3i(4, 4, 4);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, test::checker_pattern);
    for (const int levels : {2, 3}) {
        const Hierarchy hg = build_hierarchy(p.mesh, p.K, p.bc.dofs,
                                             test::exact_options(levels, Refinement::Linear));
        Options relaxed = cell_options(levels, Refinement::Linear, kInf);
        relaxed.relaxation = 3;
        const Hierarchy hr = build_hierarchy(p.mesh, p.K, p.bc.dofs, relaxed, &p.materials);
        for (int k = 1; k < levels; ++k) {
            const SparseMatrix& Cg = hg.level(k).C_adapted.sparse();
            EXPECT_LT(Matrix(Cg - hr.level(k).C_adapted.sparse()).norm(), 1e-10 * Matrix(Cg).norm())
                << levels << " levels, level " << k;
        }
    }
}

TEST(MraAutomaticConstruction, LocalizedOnlyOnLargeThreeDGridsWithDefaultLocalization) {
    Options o;  // radius empty: automatic
    // 48x16x16 hexes: 42,483 DOFs, above kLocalizedMinDofs; 44x16x16: 39,015, below.
    const Eigen::Vector3i big(48, 16, 16), small(44, 16, 16);
    const Options localized = automatic_construction(o, big, 3, true);
    EXPECT_EQ(localized.localization, Localization::Cell);
    EXPECT_EQ(localized.patch, kLocalizedPatch);
    EXPECT_EQ(localized.relaxation, kLocalizedRelaxation);
    // The coarser step on its whole level (24x8x8 hexes: 6,075 DOFs), the finest at
    // kLocalizedFineRings.
    EXPECT_EQ(localized.radius, (std::vector<double>{kInf, kLocalizedFineRings}));
    EXPECT_NO_THROW(validate(localized));
    o.levels = 2;
    EXPECT_EQ(automatic_construction(o, big, 3, true).radius,
              std::vector<double>{kLocalizedFineRings});
    // A coarser step on its whole level up to kWholeLevelMaxDofs DOFs of level k+1, in
    // kLocalizedCoarseRings rings above: 34^3 hexes, level 2 of 17^3 cells (17,496 DOFs); 36^3,
    // level 2 of 18^3 (20,577).
    o.levels = 3;
    EXPECT_EQ(automatic_construction(o, Eigen::Vector3i(34, 34, 34), 3, true).radius,
              (std::vector<double>{kInf, kLocalizedFineRings}));
    EXPECT_EQ(automatic_construction(o, Eigen::Vector3i(36, 36, 36), 3, true).radius,
              (std::vector<double>{kLocalizedCoarseRings, kLocalizedFineRings}));
    // 96^3 hexes, 4 levels: levels 3 and 2 (352,947 and 46,875 DOFs) above the bound; 5 levels:
    // level 2 of 12^3 cells (6,591 DOFs) on its whole level.
    o.levels = 4;
    EXPECT_EQ(
        automatic_construction(o, Eigen::Vector3i(96, 96, 96), 3, true).radius,
        (std::vector<double>{kLocalizedCoarseRings, kLocalizedCoarseRings, kLocalizedFineRings}));
    o.levels = 5;
    EXPECT_EQ(automatic_construction(o, Eigen::Vector3i(96, 96, 96), 3, true).radius,
              (std::vector<double>{kInf, kLocalizedCoarseRings, kLocalizedCoarseRings,
                                   kLocalizedFineRings}));
    // Levels out of range: left as they are, for validate's message.
    for (const int levels : {1, kMaxLevels + 1}) {
        o.levels = levels;
        EXPECT_TRUE(automatic_construction(o, big, 3, true).radius.empty());
        EXPECT_THROW(validate(automatic_construction(o, big, 3, true)), Error);
    }
    o.levels = 3;
    const auto global = [&](const Options& given, const Eigen::Vector3i& cells, int dim,
                            bool parts) {
        const Options r = automatic_construction(given, cells, dim, parts);
        return r.radius == std::vector<double>{kInf} && r.localization == given.localization &&
               r.patch == given.patch && r.relaxation == given.relaxation;
    };
    EXPECT_TRUE(global(o, small, 3, true));
    EXPECT_TRUE(global(o, Eigen::Vector3i(512, 512, 1), 2, true));
    EXPECT_TRUE(global(o, big, 3, false));  // no element materials, or level meshes
    const std::vector<std::function<void(Options&)>> excluded = {
        [](Options& x) { x.refinement = Refinement::Dirac; },
        [](Options& x) { x.dirichlet = DirichletTreatment::Penalty; },
        [](Options& x) { x.dirichlet = DirichletTreatment::DiagonalPenalty; },
        [](Options& x) { x.fine_operator = Operator::Step; },
        [](Options& x) { x.measurement = Measurement::Stiffness; },
        [](Options& x) { x.localization = Localization::Cell; },
        [](Options& x) { x.patch = 3; },
        [](Options& x) { x.patch_clip = true; },
        [](Options& x) { x.defect_tolerance = 1e-2; },
        [](Options& x) {
            x.localization = Localization::Cell;
            x.relaxation = 1;
        },
    };
    for (std::size_t i = 0; i < excluded.size(); ++i) {
        Options x = o;
        excluded[i](x);
        EXPECT_TRUE(global(x, big, 3, true)) << "case " << i;
    }
    for (const DirichletTreatment t : {DirichletTreatment::Eliminate, DirichletTreatment::Ignore}) {
        Options x = o;
        x.dirichlet = t;
        EXPECT_EQ(automatic_construction(x, big, 3, true).localization, Localization::Cell);
    }
    // A given radius is kept as it is.
    o.radius = {5};
    EXPECT_EQ(automatic_construction(o, big, 3, true).radius, std::vector<double>{5});
    EXPECT_EQ(automatic_construction(o, big, 3, true).localization, Localization::Node);
}

TEST(MraAutomaticConstruction, BuildRecordsWhatItResolvedTo) {
    // A small model: global solves, recorded in Hierarchy::options.
    const test::GridProblem p =
        test::hung_problem(3, Eigen::Vector3i(4, 4, 4), 1.0, 1e3, test::checker_pattern);
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, Options(), &p.materials);
    EXPECT_EQ(h.options.radius, std::vector<double>{kInf});
    EXPECT_EQ(h.options.localization, Localization::Node);
}

TEST_P(MraCellLocalized, NeedsMaterialsUnclippedPatchesAndNoPenalty) {
    const int dim = GetParam();
    const Eigen::Vector3i cells = dim == 2 ? Eigen::Vector3i(4, 4, 1) : Eigen::Vector3i(4, 4, 4);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 10.0, test::checker_pattern);
    Options o = cell_options(3, Refinement::Linear, 2);
    EXPECT_THROW(build_hierarchy(p.mesh, p.K, p.bc.dofs, o), Error);
    o.patch = 2;
    EXPECT_NO_THROW(build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials));
    o.patch_clip = true;
    EXPECT_THROW(build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials), Error);
    o.patch = 1;
    o.patch_clip = false;
    o.dirichlet = DirichletTreatment::Penalty;
    EXPECT_THROW(build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials), Error);
}

INSTANTIATE_TEST_SUITE_P(Dims, MraCellLocalized, ::testing::Values(2, 3),
                         [](const ::testing::TestParamInfo<int>& i) {
                             return std::to_string(i.param) + "D";
                         });

/// max over rigid motions r (unit translations, rotation about the grid centre) of
/// |C̃^T r_c - r| / ||r||_inf at the finest step of a free (unconstrained) 2D grid, over the fine
/// nodes at least `margin` nodes away from the boundary. r_c: the coarse coefficients of r, its
/// measurements C r, or with `nodal` its values at the coarse nodes (the relaxed construction's).
double rigid_defect(const Hierarchy& h, int margin, bool nodal = false) {
    const Level& L = h.level(h.num_levels() - 1);
    Matrix R = Matrix::Zero(h.fine_dofs.size(), 3);
    for (Index a = 0; a < h.fine_dofs.size(); ++a) {
        const int c = static_cast<int>(h.fine_dofs[a] % 2);
        const Eigen::VectorXd x = h.node_position(h.num_levels(), h.fine_dofs[a] / 2);
        R(a, c) = 1.0;
        R(a, 2) = c == 0 ? -(x[1] - 0.5) : x[0] - 0.5;
    }
    Matrix coefficients = L.C * R;
    if (nodal) {
        const std::vector<Index> fine_node = coincident_nodes(L.cells, 2);
        for (Index r = 0; r < L.dofs.size(); ++r)  // every DOF present: fine DOF = grid DOF
            coefficients.row(r) = R.row(2 * fine_node[L.dofs[r] / 2] + L.dofs[r] % 2);
    }
    const Matrix back = Matrix(SparseMatrix(L.C_adapted.sparse().transpose())) * coefficients;
    double worst = 0;
    for (Index a = 0; a < R.rows(); ++a) {
        const Eigen::Vector3i v = node_coordinates(h.fine_dofs[a] / 2, h.fine_cells, 2);
        if (std::min({v[0], v[1], h.fine_cells[0] - v[0], h.fine_cells[1] - v[1]}) < margin)
            continue;
        for (Index m = 0; m < 3; ++m)
            worst =
                std::max(worst, std::abs(back(a, m) - R(a, m)) / R.col(m).cwiseAbs().maxCoeff());
    }
    return worst;
}

TEST(MraCellLocalizedRigid, ReproducesRigidMotionsAwayFromTheBoundary) {
    // LOD's argument: if X C r = r for a rigid motion r (X: the left inverse that plays C^† in
    // Eq. 11), then A_T r = 0 (a grid without Dirichlet DOFs) makes every R^T C r vanish, Z C r = 0
    // whatever the radius and C̃^T C r = r without the invariance correction. Cell localization
    // builds such an X (rigid_left_inverse) for the linear refinement, exact except at fine
    // nodes on the boundary whose one-sided stencils cannot hold the rotation; their cells'
    // corrections reach `rings` + 2 fine nodes inward. 24x24, two levels, radius 2 fine rings:
    // exact from 9 nodes inward (measured 6e-15; 4.6e-4 from 6 nodes inward; round-off of
    // local solves with condition ~1e4: 1e-11).
    // Measured over all nodes: 0.019 (cell) against 3.1 (node); Dirac refinement (injection
    // C^†, no rigid X): 0.152 / 0.407. Node-wise is not exact anywhere: asserted > 1e-3.
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(24, 24, 1), 1.0, 100.0, test::checker_pattern);
    for (const Refinement r : {Refinement::Linear, Refinement::Dirac}) {
        const Options cell = cell_options(2, r, 2);
        Options node = cell;
        node.localization = Localization::Node;
        const Hierarchy hc = build_hierarchy(p.mesh, p.K, {}, cell, &p.materials);
        const Hierarchy hn = build_hierarchy(p.mesh, p.K, {}, node);
        Options patch = cell;
        patch.patch = 2;
        const Hierarchy hp = build_hierarchy(p.mesh, p.K, {}, patch, &p.materials);
        std::printf(
            "%s, radius 2: rigid defect cell %.3g (interior %.3g), patch 2 %.3g (%.3g), "
            "node %.3g (%.3g)\n",
            refinement_name(r).c_str(), rigid_defect(hc, 0), rigid_defect(hc, 9),
            rigid_defect(hp, 0), rigid_defect(hp, 11), rigid_defect(hn, 0), rigid_defect(hn, 6));
        if (r == Refinement::Linear) {
            EXPECT_LT(rigid_defect(hc, 9), 1e-11);
            EXPECT_LT(rigid_defect(hp, 11), 1e-11);
            EXPECT_GT(rigid_defect(hn, 6), 1e-3);
        }
    }
}

TEST(MraCellLocalizedRelaxed, ReproducesRigidMotionsEverywhere) {
    // The relaxed construction starts from the canonical basis, whose coefficients are nodal
    // values: C^T r_c = r for a rigid motion r with nodal values r_c (bilinear interpolation of a
    // linear field), boundary nodes included. Its correctors are linear in the start rows: their
    // sum with the weights r_c is driven by F A_T r = 0 on a free grid, so C̃^T r_c = r over the
    // whole grid, without the invariance correction (round-off of local solves with condition
    // ~1e4 at contrast 100: 1e-11). The exact construction's left inverse cannot hold the
    // rotation at boundary nodes (above).
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(24, 24, 1), 1.0, 100.0, test::checker_pattern);
    Options o = cell_options(2, Refinement::Linear, 2);
    o.relaxation = 3;
    const Hierarchy h = build_hierarchy(p.mesh, p.K, {}, o, &p.materials);
    std::printf("relaxed, radius 2: rigid defect %.3g\n", rigid_defect(h, 0, true));
    EXPECT_LT(rigid_defect(h, 0, true), 1e-11);
}

TEST(MraCellLocalizedAccuracy, FarBelowNodeWiseOnTheHungSquare) {
    // 16x16 hung checker square, contrast 100, three levels, bilinear refinement, no
    // correction or truncation, radius 2 fine rings. Measured coarsest energy errors: global
    // 0.109, node-wise 0.963, cell-wise 0.307 (0.881 with the injection C^† instead of the rigid
    // left inverse, 0.237 with the dense Moore-Penrose C^†). Asserted: global <= cell (the
    // localized space approximates the global one, whose basis has the least energy for the
    // measurements, Eq. 9: expected, though for one load not a theorem; 1e-9 for round-off)
    // and cell < 0.4 node.
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(16, 16, 1), 1.0, 100.0, test::checker_pattern);
    const auto error = [&](const Options& o) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
        MultilevelSolver s(h);
        return test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u);
    };
    const double e_global = error(test::exact_options(3, Refinement::Linear));
    Options node = cell_options(3, Refinement::Linear, 2);
    node.localization = Localization::Node;
    const double e_node = error(node);
    const double e_cell = error(cell_options(3, Refinement::Linear, 2));
    std::printf("hung square 16x16: global %.4g, node %.4g, cell %.4g\n", e_global, e_node, e_cell);
    EXPECT_GE(e_cell, e_global * (1 - 1e-9));
    EXPECT_LT(e_cell, 0.4 * e_node);
}

TEST(MraCellLocalizedAccuracy, RelaxedCoarseStepInRingsNearItsWholeLevel) {
    // 64x64 hung checker square, contrast 1e3, three levels, relaxed (gamma 3, patch 2), 6 fine
    // rings; the coarse step on its whole level (the global space with the composed
    // measurements) or in 3 rings of level 2 (33x33 nodes; regions of about 11x11, their blocks
    // of A^2 + p G^T G formed by region). Measured: 0.0706 whole, 0.0818 rings (1.16x; in 3D
    // 1.03-1.07x on the 24^3-48^3 checker). Asserted: the rings within 1.5x of the whole level,
    // the bound the automatic construction is held to, and no better (1e-9 for round-off): the
    // whole level's basis has the least energy for the measurements (expected, though for one
    // load not a theorem).
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(64, 64, 1), 1.0, 1e3, test::checker_pattern);
    const auto error = [&](double coarse_radius) {
        Options o = cell_options(3, Refinement::Linear, 6);
        o.radius = {coarse_radius, 6};
        o.relaxation = 3;
        o.patch = 2;
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
        MultilevelSolver s(h);
        return test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u);
    };
    const double whole = error(kInf), rings = error(3);
    std::printf("hung square 64x64, coarse step: whole level %.4g, 3 rings %.4g\n", whole, rings);
    EXPECT_GE(rings, whole * (1 - 1e-9));
    EXPECT_LT(rings, 1.5 * whole);
}

TEST(MraCellLocalizedAccuracy, ThreeDHomogeneousBlockAgainstTheTrilinearBaseline) {
    // A homogeneous 8x8x8 block hung from its top, two levels, trilinear refinement, radius 2
    // fine rings, the paper's invariance correction. The global adapted space beats the
    // trilinear FEM on the coarse grid. Node-wise
    // localized basis functions each have less energy than the trilinear ones (those lie in the
    // admissible set), but each carries its own truncation error, and these add up over a
    // smooth displacement: their span loses to the trilinear FEM. Cell-wise
    // localization (LOD) corrects a coarse field by the sum of its cells' correctors, each driven
    // by the field on one cell, and beats it.
    // Measured here (gravity and a traction on the bottom):
    // global 0.0596, node 0.799, cell 0.0683, trilinear 0.187; bench_mra on
    // bench/scenes/homogeneous_block.json at 16^3 (gravity only): 0.0112, 0.694, 0.0217, 0.0759.
    // Asserted: the comparisons with the trilinear baseline (cell-wise with a factor 2 of
    // margin) and that the cell-wise space does not beat the global one it approximates.
    // Node-wise losing to the trilinear FEM is a limitation, printed but not asserted.
    const test::GridProblem p =
        test::hung_problem(3, Eigen::Vector3i(8, 8, 8), 1.0, 1.0, test::checker_pattern);
    Options global = test::exact_options(2, Refinement::Linear);
    Options node = cell_options(2, Refinement::Linear, 2);
    node.localization = Localization::Node;
    node.invariance = true;
    Options cell = node;
    cell.localization = Localization::Cell;
    const auto errors = [&](const Options& o) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
        MultilevelSolver s(h);
        return std::pair(
            test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u),
            test::canonical_energy_error(h, p));
    };
    const auto [e_global, e_trilinear] = errors(global);
    const double e_node = errors(node).first, e_cell = errors(cell).first;
    std::printf("homogeneous 8^3 block: global %.4g, node %.4g, cell %.4g, trilinear %.4g\n",
                e_global, e_node, e_cell, e_trilinear);
    EXPECT_LT(e_global, e_trilinear);
    EXPECT_LT(e_cell, 0.5 * e_trilinear);
    EXPECT_GE(e_cell, e_global * (1 - 1e-9));
}

/// Stiff disks or balls of radius 0.06 centred on a lattice of 6 per axis over the unit square
/// or cube: isolated inclusions.
int lattice_inclusions(const Eigen::VectorXd& x) {
    double r2 = 0;
    for (int d = 0; d < x.size(); ++d) {
        const double t = x[d] * 6 - std::floor(x[d] * 6) - 0.5;
        r2 += t * t / 36;
    }
    return r2 < 0.06 * 0.06 ? 1 : 0;
}

/// Coarsest energy error and density of C̃^1 (nonzero fraction) of a two-level hierarchy.
std::pair<double, double> error_and_density(const test::GridProblem& p, const Options& o) {
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
    MultilevelSolver s(h);
    const SparseMatrix& C = h.level(h.num_levels() - 1).C_adapted.sparse();  // the finest step's
    return {test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u),
            static_cast<double>(C.nonZeros()) / static_cast<double>(C.rows() * C.cols())};
}

class MraRelaxedSlow : public ::testing::TestWithParam<int> {};

TEST_P(MraRelaxedSlow, IsolatedInclusionsWithinOneAndAHalfTimesTheGlobalError) {
    // Stiff disks / balls (contrast 1e3) on a 6-per-axis lattice, hung and pulled, two levels,
    // gamma 3, the default truncation and invariance correction. Measured (coarsest energy error,
    // C̃ density):
    //   2D 64^2: global 0.0192 / 0.19; relaxed 8 rings 0.0246 (1.28x) / 0.073; exact cell-wise
    //            4 rings 0.165 / 0.077, 6 rings 0.0272 / 0.105.
    //   3D 16^3: global 0.0339 / 0.99; relaxed 4 rings 0.0379 (1.12x) / 0.16, 6 rings 0.0339 /
    //            0.33, blocks of 2^3 cells 4 rings 0.0359 / 0.26; exact 4 rings 0.130 / 0.51,
    //            6 rings 0.0557 / 0.69.
    // Asserted: the relaxed space within 1.5x of the global error (the accuracy target of the
    // localized construction) and at most a third (2D: 0.4) as dense; in 2D the exact
    // constraints at no smaller density at least 3x less accurate.
    const int dim = GetParam();
    const Eigen::Vector3i cells =
        dim == 2 ? Eigen::Vector3i(64, 64, 1) : Eigen::Vector3i(16, 16, 16);
    const test::GridProblem p = test::hung_problem(dim, cells, 1.0, 1e3, lattice_inclusions);
    Options global;
    global.levels = 2;
    Options relaxed = global;
    relaxed.radius = {dim == 2 ? 8.0 : 4.0};
    relaxed.localization = Localization::Cell;
    relaxed.relaxation = 3;
    const auto [e_global, d_global] = error_and_density(p, global);
    const auto [e_relaxed, d_relaxed] = error_and_density(p, relaxed);
    std::printf("%dD inclusions: global %.4g (density %.3f), relaxed %.4g (%.3f)\n", dim, e_global,
                d_global, e_relaxed, d_relaxed);
    EXPECT_LT(e_relaxed, 1.5 * e_global);
    EXPECT_LT(d_relaxed, (dim == 2 ? 0.4 : 1.0 / 3) * d_global);
    if (dim == 2) {
        Options exact = relaxed;
        exact.relaxation = 0;
        exact.radius = {4};
        const auto [e_exact, d_exact] = error_and_density(p, exact);
        std::printf("2D inclusions: exact 4 rings %.4g (%.3f)\n", e_exact, d_exact);
        EXPECT_GE(d_exact, d_relaxed);
        EXPECT_GT(e_exact, 3 * e_relaxed);
    } else {
        // Blocks of 2^3 cells: each cell's corrector solved on its block's box, which holds the
        // cell's own box, so more accurate at the same radius (not a theorem for the coarse
        // solution, but each corrector is a Galerkin projection on a larger space).
        Options block = relaxed;
        block.patch = 2;
        const auto [e_block, d_block] = error_and_density(p, block);
        std::printf("3D inclusions: relaxed blocks %.4g (%.3f)\n", e_block, d_block);
        EXPECT_LT(e_block, e_relaxed);
    }
}

/// Cubes of side 1/4 in a checkerboard, stiff where the sum of their indices is even: stiff
/// inclusions that touch along edges.
int touching_cubes(const Eigen::VectorXd& x) {
    int sum = 0;
    for (int d = 0; d < x.size(); ++d) sum += static_cast<int>(std::floor(4 * x[d]));
    return sum % 2 == 0 ? 1 : 0;
}

/// Coarsest energy errors and densities (as error_and_density) of the global three-level
/// hierarchy and the relaxed one (gamma 3) at `rings` with blocks of patch^3 cells, printed
/// under `name`: {e_global, d_global, e_relaxed, d_relaxed}.
std::array<double, 4> three_level_comparison(const test::GridProblem& p, double rings, int patch,
                                             const char* name) {
    Options global;
    global.levels = 3;
    Options relaxed = global;
    relaxed.radius = {rings};
    relaxed.localization = Localization::Cell;
    relaxed.relaxation = 3;
    relaxed.patch = patch;
    const auto [e_global, d_global] = error_and_density(p, global);
    const auto [e_relaxed, d_relaxed] = error_and_density(p, relaxed);
    std::printf("%s, 3 levels: global %.4g (density %.3f), relaxed %.4g (%.3f)\n", name, e_global,
                d_global, e_relaxed, d_relaxed);
    return {e_global, d_global, e_relaxed, d_relaxed};
}

TEST(MraRelaxedThreeLevelsSlow, TouchingCubesWithinOneAndAHalfTimesTheGlobalError) {
    // Touching stiff cubes (contrast 1e3) on 16^3 hexes, hung and pulled, three levels (coarsest
    // 4^3 cells), relaxed 4 rings at both steps, gamma 3. A coarser step's penalty measures the
    // fine functions (C^1 C^2 Φ^{2,T} w); measuring the coefficients (C^1 w), which after a
    // relaxed step are not measurements, gave 0.611 (1.87x). Measured: global 0.3273 / density
    // 0.886; relaxed 0.3363 (1.03x) / 0.161. Asserted: within 1.5x of the global error, the
    // finest step at most a third as dense.
    const test::GridProblem p =
        test::hung_problem(3, Eigen::Vector3i(16, 16, 16), 1.0, 1e3, touching_cubes);
    const auto [e_global, d_global, e_relaxed, d_relaxed] =
        three_level_comparison(p, 4, 1, "3D touching cubes");
    EXPECT_LT(e_relaxed, 1.5 * e_global);
    EXPECT_LT(d_relaxed, d_global / 3);
}

TEST(MraRelaxedThreeLevelsSlow, LayeredColumnWithinOneAndAHalfTimesTheGlobalError) {
    // A 1 x 4 x 1 column of 16 layers across its axis (contrast 1e3), 12 x 48 x 12 hexes, hung
    // from its top and pulled sideways, three levels, blocks of 2^3 cells, gamma 3, 6 rings.
    // Each stiff layer is a plate across the whole section; a region stopping short of the
    // section's sides clamps the plates it crosses, so regions within rings / 3 of the grid's
    // boundary reach it (detail::kRegionSnap). Measured: global 0.00231 / density 0.299; relaxed
    // 0.00194 (0.84x) / 0.323; regions stopping short of the boundary 0.00357 (1.55x) / 0.235,
    // which fails. Asserted: within 1.5x of the global error.
    const test::GridProblem p = test::hung_problem(3, Eigen::Vector3i(12, 48, 12), 1.0, 1e3,
                                                   test::layers_across_y, Eigen::Vector3d(1, 4, 1));
    const auto [e_global, d_global, e_relaxed, d_relaxed] =
        three_level_comparison(p, 6, 2, "3D layered column");
    EXPECT_LT(e_relaxed, 1.5 * e_global);
}

TEST(MraAutomaticConstructionSlow, HungCheckerSlabAboveTheThresholdWithinTheGlobalError) {
    // A 48x48x8 hung checker slab (contrast 1e3; 64,827 DOFs), 3 levels, no radius: the automatic
    // construction is the relaxed cell-wise one with the coarser step on its whole level and 6
    // fine rings. The coarse step's measurements C^1 C^2 Φ^{2,T} of the localized fine basis
    // are far from C^1 (sigma_min / sigma_max of G C^T 4e-7 on the 40x40x8 slab), and the relaxed
    // basis of the whole level, Y S^{-1} G C^T, left A^1 numerically singular there; in the
    // measurements' basis A^1 = (G A^{-1} G^T)^{-1}. Measured: global 0.0779 / C̃^2 density
    // 0.28; automatic 0.0784 / 0.105. Asserted: within 1.5x of the global error.
    const test::GridProblem p =
        test::hung_problem(3, Eigen::Vector3i(48, 48, 8), 1.0, 1e3, test::checker_pattern,
                           Eigen::Vector3d(1, 1, 1.0 / 6));
    Options automatic;
    automatic.levels = 3;
    Options global = automatic;
    global.radius = {kInf};
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, automatic, &p.materials);
    EXPECT_EQ(h.options.localization, Localization::Cell);
    EXPECT_EQ(h.options.radius, (std::vector<double>{kInf, kLocalizedFineRings}));
    MultilevelSolver s(h);
    const double e_automatic =
        test::energy_norm(p.K, s.solve_level(p.f, 1) - p.u) / test::energy_norm(p.K, p.u);
    const double e_global = error_and_density(p, global).first;
    std::printf("48x48x8 hung checker, 3 levels: global %.4g, automatic %.4g\n", e_global,
                e_automatic);
    EXPECT_LT(e_automatic, 1.5 * e_global);
}

INSTANTIATE_TEST_SUITE_P(Dims, MraRelaxedSlow, ::testing::Values(2, 3),
                         [](const ::testing::TestParamInfo<int>& i) {
                             return std::to_string(i.param) + "D";
                         });

}  // namespace
}  // namespace coarsegrain::mra
