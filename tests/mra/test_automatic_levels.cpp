// Automatic level meshes (carved simplicial background grids) on meshes with a hole, and the
// hierarchy on them: Algorithm 1's identities and exactness, as on given level meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "../test_util.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/mra/automatic_levels.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

/// A simplicial grid over [0, 1]^dim with n cells per axis, its interior nodes moved by up to a
/// quarter cell, without the elements whose centroid lies within `radius` of the centre: a mesh
/// with a hole, no grid. Unused nodes are dropped.
mesh::Mesh holed_mesh(int dim, int n, double radius, unsigned seed) {
    mesh::Mesh grid = mesh::make_grid(dim == 2 ? mesh::ElementType::Tri3 : mesh::ElementType::Tet4,
                                      Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                                      Eigen::VectorXi::Constant(dim, n));
    test::distort_interior(grid, 0.25, seed);
    const Matrix centres = mesh::element_centroids(grid);
    const Eigen::VectorXd middle = Eigen::VectorXd::Constant(dim, 0.5);
    std::vector<Index> kept, number(static_cast<std::size_t>(grid.num_nodes()), -1);
    for (Index e = 0; e < grid.num_elements(); ++e)
        if ((centres.row(e).transpose() - middle).norm() > radius) kept.push_back(e);
    mesh::Mesh m;
    m.type = grid.type;
    m.elements.resize(static_cast<Index>(kept.size()), grid.elements.cols());
    std::vector<Index> old;
    for (Index r = 0; r < m.num_elements(); ++r)
        for (Index a = 0; a < m.elements.cols(); ++a) {
            Index& v = number[grid.elements(kept[r], a)];
            if (v < 0) {
                v = static_cast<Index>(old.size());
                old.push_back(grid.elements(kept[r], a));
            }
            m.elements(r, a) = v;
        }
    m.rest_positions.resize(static_cast<Index>(old.size()), dim);
    for (Index v = 0; v < m.num_nodes(); ++v)
        m.rest_positions.row(v) = grid.rest_positions.row(old[v]);
    m.material_ids = IndexVector::Zero(m.num_elements());
    return m;
}

double measure(const mesh::Mesh& m) {
    double v = 0;
    for (Index e = 0; e < m.num_elements(); ++e) v += mesh::element_measure(m, e);
    return v;
}

/// Distance from x to the nearest point of `m` (0 inside).
double distance_to(const mesh::PointLocator& locator, const mesh::Mesh& m,
                   const Eigen::VectorXd& x) {
    const mesh::Location loc = locator.locate_nearest(x);
    Eigen::VectorXd nearest = Eigen::VectorXd::Zero(x.size());
    for (Index a = 0; a < m.elements.cols(); ++a)
        nearest += loc.weights[a] * m.rest_positions.row(m.elements(loc.element, a)).transpose();
    return (nearest - x).norm();
}

struct CountCase {
    int dim, cells, levels;
    double radius;
};

class AutomaticLevels : public ::testing::TestWithParam<CountCase> {};

TEST_P(AutomaticLevels, FollowTheSpacingAndCoverTheFinerLevel) {
    const CountCase c = GetParam();
    const mesh::Mesh fine = holed_mesh(c.dim, c.cells, c.radius, 7);
    const std::vector<mesh::Mesh> levels = automatic_level_meshes(fine, c.levels);
    ASSERT_EQ(static_cast<int>(levels.size()), c.levels - 1);
    const double V = measure(fine), N = static_cast<double>(fine.num_nodes());
    const double h = std::pow(V / N, 1.0 / c.dim);
    // The grids span the unit box with round(1 / h_1) cells at level 1, twice as many at each
    // finer level: level k's spacing s_k is h_k = 2^{q-k} h up to that rounding.
    const double coarsest_cells = std::max(1.0, std::round(1 / std::ldexp(h, c.levels - 1)));
    // The object's surface: the unit box's and the hole's (circle or sphere).
    const double surface =
        c.dim == 2 ? 4 + 2 * M_PI * c.radius : 6 + 4 * M_PI * std::pow(c.radius, 2);
    const double simplices_per_cell = c.dim == 2 ? 2 : 6;
    const mesh::Mesh* finer = &fine;
    for (int k = c.levels - 1; k >= 1; --k) {
        const mesh::Mesh& level = levels[static_cast<std::size_t>(k - 1)];
        const double s_k = 1 / std::ldexp(coarsest_cells, k - 1);
        // The object's measure holds V / s_k^d nodes of the grid; carving keeps the cells meeting
        // the object: at most one more layer of cells along its surface (surface / s_k^{d-1}
        // nodes), and at least the cells inside it, i.e. less that layer.
        const double inside = V / std::pow(s_k, c.dim), layer = surface / std::pow(s_k, c.dim - 1);
        EXPECT_GT(level.num_nodes(), inside - layer) << "level " << k;
        EXPECT_LT(level.num_nodes(), inside + layer) << "level " << k;
        // Against the fine mesh's N / 2^{d(q-k)}: the spacing's rounding (within 2/3 and 3/2 of
        // h_k here) and that layer make a factor 3 either way.
        const double N_k = std::ldexp(N, -c.dim * (c.levels - k));
        EXPECT_GT(level.num_nodes(), N_k / 3) << "level " << k;
        EXPECT_LT(level.num_nodes(), 3 * N_k) << "level " << k;
        // Every element is one of a cell's simplices (measure s_k^d / (2 or 6), positive): 1e-12
        // of s_k^d.
        EXPECT_NO_THROW(mesh::validate(level, "level"));
        for (Index e = 0; e < level.num_elements(); ++e)
            ASSERT_NEAR(mesh::element_measure(level, e) * simplices_per_cell, std::pow(s_k, c.dim),
                        1e-12 * std::pow(s_k, c.dim))
                << "level " << k << " element " << e;
        // Every node of the finer level lies in the level mesh or within one cell of it (its
        // diagonal, sqrt(d) s_k: below level q-1 only elements whose corners are all finer nodes
        // are kept, and a finer node at the midpoint of a dropped element's edge can be more than
        // s_k away).
        const mesh::PointLocator locator(level);
        double farthest = 0;
        for (Index v = 0; v < finer->num_nodes(); ++v)
            farthest = std::max(
                farthest, distance_to(locator, level, finer->rest_positions.row(v).transpose()));
        EXPECT_LT(farthest, std::sqrt(c.dim) * s_k) << "level " << k;
        finer = &level;
    }
}

INSTANTIATE_TEST_SUITE_P(Mra, AutomaticLevels,
                         ::testing::Values(CountCase{2, 48, 3, 0.25}, CountCase{2, 24, 4, 0.3},
                                           CountCase{3, 16, 3, 0.3}),
                         [](const auto& p) {
                             return std::to_string(p.param.dim) + "D_" +
                                    std::to_string(p.param.levels) + "_levels";
                         });

TEST(AutomaticLevelsInput, TooManyLevelsOrNoSimplicesAreErrors) {
    const mesh::Mesh fine = holed_mesh(2, 8, 0.2, 3);  // 81 nodes at most: 3 levels fit
    EXPECT_EQ(max_automatic_levels(fine), 3);
    test::expect_error([&] { automatic_level_meshes(fine, 4); },
                       "4 levels are too many for automatic level meshes");
    Options o;
    o.levels = 4;
    test::expect_error([&] { validate_automatic_levels(fine, o); }, "use at most 3 levels");
    o.levels = 3;
    o.radius = {2};
    o.patch = 2;
    test::expect_error([&] { validate_automatic_levels(fine, o); }, "(patch 1), got patch 2");
    const mesh::Mesh quads = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d::Zero(),
                                             Eigen::Vector2d::Ones(), Eigen::Vector2i(8, 8));
    test::expect_error([&] { automatic_level_meshes(quads, 2); }, "got quad elements");
}

class AutomaticLevelHierarchy : public ::testing::TestWithParam<std::tuple<int, Refinement>> {
  protected:
    int dim() const { return std::get<0>(GetParam()); }
    Refinement refinement() const { return std::get<1>(GetParam()); }
    /// The checkered two-material problem hung from the top of a mesh with a hole.
    test::GridProblem problem() const {
        return test::hung_problem_on(
            dim() == 2 ? holed_mesh(2, 16, 0.25, 5) : holed_mesh(3, 8, 0.3, 5), 1.0, 1e3,
            test::checker_pattern);
    }
};

TEST_P(AutomaticLevelHierarchy, OperatorsHoldToRoundOffAndTheSolveIsExact) {
    const test::GridProblem p = problem();
    for (const Options& o : test::exact_level_options(refinement())) {
        const Hierarchy h =
            build_hierarchy(automatic_level_meshes(p.mesh, o.levels), p.mesh, p.K, p.bc.dofs, o);
        for (int k = 1; k < h.num_levels(); ++k) {
            const Level& L = h.level(k);
            // C C^{†,T} = I: each row of C^† is a local dense least-norm solve of O(1) entries
            // (checked to 1e-12 inside); C W^T = C - C C^{†,T} C adds one product: 1e-12.
            const Matrix CCd = Matrix(L.C * SparseMatrix(L.C_dagger.transpose()));
            EXPECT_LT(test::max_abs(CCd - Matrix::Identity(CCd.rows(), CCd.cols())), 1e-12) << k;
            EXPECT_LT(test::max_abs(Matrix(L.C * SparseMatrix(L.W.transpose()))), 1e-12) << k;
        }
        // Exact block-diagonalization (Eq. 4): q + 1 sparse Cholesky solves' round-off: 1e-9.
        MultilevelSolver solver(h);
        EXPECT_LT((solver.solve(p.f) - p.u).norm(), 1e-9 * p.u.norm())
            << dirichlet_name(o.dirichlet);
    }
}

// A Kuhn-tetrahedron grid with its interior nodes moved by up to a quarter cell, no grid: on its
// automatic levels a matching of kernel pivots left C^†[:, P] singular (singular values down to
// 1e-15) and B^k with it; the eliminated pivots keep W^k of full rank, so the global hierarchy
// is exact (multilevel solve to the round-off of TEST_P above).
TEST(AutomaticLevelKernel, FullRankOnDistortedTetrahedra) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d::Ones(), Eigen::Vector3i::Constant(12));
    test::distort_interior(m, 0.25, 3);
    m.grid.reset();
    const test::GridProblem p =
        test::hung_problem_on(std::move(m), 1.0, 1e3, test::checker_pattern);
    for (Options o : test::exact_level_options(Refinement::Linear)) {
        o.levels = 2;
        const Hierarchy h =
            build_hierarchy(automatic_level_meshes(p.mesh, o.levels), p.mesh, p.K, p.bc.dofs, o);
        MultilevelSolver solver(h);
        EXPECT_LT((solver.solve(p.f) - p.u).norm(), 1e-9 * p.u.norm())
            << dirichlet_name(o.dirichlet);
    }
}

INSTANTIATE_TEST_SUITE_P(Mra, AutomaticLevelHierarchy,
                         ::testing::Combine(::testing::Values(2, 3),
                                            ::testing::Values(Refinement::Dirac,
                                                              Refinement::Linear)),
                         [](const auto& p) { return test::dim_refinement_label(p.param); });

}  // namespace
}  // namespace coarsegrain::mra
