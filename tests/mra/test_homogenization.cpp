// Coarse-graining quality (Chen et al. 2019, Fig. 2 and Fig. 9).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

/// Vertical layers (constant along y) of thickness `t`, stiff first.
test::MaterialPattern layers(double t) {
    return [t](const Eigen::VectorXd& x) {
        return static_cast<int>(std::floor(x[0] / t)) % 2 == 0 ? 1 : 0;
    };
}

// Fig. 9: layered composite (soft E = 100, stiff E = 5e6) on a 32x32 grid hung from its top,
// coarsened down to one element (6 levels), global solves. The homogenization error
// ||u^k - u||_A / ||g||_2 of the single-level solves decreases from coarse to fine (Galerkin
// projections on nested spaces, Eq. 4), and the linear refinement beats Dirac at every level.
// Rate: with measurements in L2 (the bilinear hats of the linear refinement) the energy error
// is O(H ||g||) (Owhadi 2017; the paper's "optimal error decay rate in energy norm"), with a
// constant that grows with the contrast: the error halves per level once the coarse cells
// resolve the layers (4 fine cells thick: levels 4 and 5, layers 1 and 2 cells thick), and
// falls more slowly while they do not. Measured, levels 1..5: linear 0.0895 0.0796 0.0629
// 0.0412 0.0213 (last step x0.52, the O(H) halving; fitted slope over all levels -0.51 per
// level), Dirac 0.0980 0.0945 0.0883 0.0876 0.0510. Asserted for the linear refinement: the
// last step at least H^{3/4} (a factor 2^{-3/4} = 0.59), margin for the constant of the
// bound. Dirac measurements are not in H^{-1} in 2D, so the theory gives Dirac no rate; only
// its monotone decrease is asserted.
TEST(MraHomogenizationSlow, ErrorDecreasesFromCoarseToFineAndLinearBeatsDirac) {
    const test::GridProblem p =
        test::hung_problem(2, Eigen::Vector3i(32, 32, 1), 100.0, 5e6, layers(0.125));
    std::map<Refinement, std::vector<double>> errors;
    for (const Refinement r : {Refinement::Dirac, Refinement::Linear}) {
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(6, r));
        MultilevelSolver solver(h);
        for (int k = 1; k < h.num_levels(); ++k) {
            const Vector u = solver.solve_level(p.f, k);
            errors[r].push_back(test::energy_norm(p.K, u - p.u) / p.f.norm());
        }
        // Slope of log2(error) against the level (the cell size halves per level), least
        // squares over the levels, printed for comparison with Fig. 9 (measured -0.20 for
        // Dirac, -0.51 for linear: the paper reports similar slopes for both, on its own,
        // unstated, loads); the asserted rate is the last step's (see above).
        const auto& e = errors[r];
        const int n = static_cast<int>(e.size());
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        for (int k = 0; k < n; ++k) {
            const double y = std::log2(e[static_cast<std::size_t>(k)]);
            sx += k;
            sy += y;
            sxx += k * k;
            sxy += k * y;
        }
        const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        std::printf("%-6s errors (level 1..5):", refinement_name(r).c_str());
        for (const double x : e) std::printf(" %.4g", x);
        std::printf("  slope %.2f per level (log2)\n", slope);
        for (int k = 1; k < n; ++k)
            EXPECT_LT(e[static_cast<std::size_t>(k)], e[static_cast<std::size_t>(k - 1)])
                << refinement_name(r) << " level " << k + 1;
        if (r == Refinement::Linear) {
            EXPECT_LT(e[4], std::pow(2.0, -0.75) * e[3]) << "linear, level 4 to 5";
        }
    }
    for (std::size_t k = 0; k < errors[Refinement::Linear].size(); ++k)
        EXPECT_LT(errors[Refinement::Linear][k], errors[Refinement::Dirac][k]) << "level " << k + 1;
}

// Fig. 2: a 16x16 bimaterial square hung from its top edge under gravity, coarsened to 2x2
// cells with the bilinear refinement. Its coarsest level must be far more accurate than plain
// bilinear finite elements on the same 2x2 grid with volume-averaged (Voigt) tensors.
TEST(MraHomogenization, CoarsestLevelBeatsAveragedBilinearElements) {
    const Eigen::Vector3i cells(16, 16, 1);
    const test::GridProblem p = test::hung_problem(2, cells, 1.0, 1e3, test::checker_pattern,
                                                   Eigen::Vector3d::Ones(), false);
    const Hierarchy h =
        build_hierarchy(p.mesh, p.K, p.bc.dofs, test::exact_options(4, Refinement::Linear));
    MultilevelSolver solver(h);
    const double u_norm = test::energy_norm(p.K, p.u);
    const double e_mra = test::energy_norm(p.K, solver.solve_level(p.f, 1) - p.u) / u_norm;

    // 2x2 bilinear elements; each gets the average of the tensors of its 8x8 fine elements.
    const mesh::Mesh coarse = mesh::make_grid(mesh::ElementType::Quad4, Eigen::VectorXd::Zero(2),
                                              Eigen::VectorXd::Ones(2), Eigen::Vector2i(2, 2));
    material::ElementMaterials mats;
    mats.dim = 2;
    mats.index.resize(4);
    const Matrix centres = mesh::element_centroids(p.mesh);
    for (Index c = 0; c < 4; ++c) {
        Matrix C = Matrix::Zero(3, 3);
        for (Index e = 0; e < p.mesh.num_elements(); ++e) {
            const int cx = centres(e, 0) > 0.5, cy = centres(e, 1) > 0.5;
            if (cx + 2 * cy == c) C += material::tensor(p.materials.of(e), 2) / 64.0;
        }
        mats.table.push_back(material::anisotropic(2, C, 1.0));
        mats.index[c] = static_cast<Index>(c);
    }
    const SparseMatrix Kc = fem::stiffness_matrix(coarse, mats);
    // Coarse bilinear hats are the canonical linear refinement of the fine ones (Eq. 6), so the
    // chain C = C^1 C^2 C^3 gives the Galerkin load C f and the interpolation u = C^T u_c.
    SparseMatrix C =
        expand_to_dofs(canonical_refinement(Eigen::Vector3i(2, 2, 1), 2, Refinement::Linear), 2);
    for (int s = 2; s <= 8; s *= 2)
        C = SparseMatrix(
            C * expand_to_dofs(
                    canonical_refinement(Eigen::Vector3i(s, s, 1), 2, Refinement::Linear), 2));
    fem::Dirichlet bc;
    bc.fix_nodes({6, 7, 8}, Eigen::Vector2d::Zero());  // the top row of the 3x3 nodes
    const fem::ReducedSystem sys = fem::reduce(Kc, C * p.f, bc);
    solve::SpdSolver s;
    s.compute(sys.K);
    const Vector uc = fem::expand(sys, s.solve(sys.rhs), bc, 18);
    const double e_fem = test::energy_norm(p.K, Vector(C.transpose() * uc) - p.u) / u_norm;
    std::printf("2x2 coarsest level: mra %.4f, averaged bilinear FEM %.4f (energy, relative)\n",
                e_mra, e_fem);
    EXPECT_LT(e_mra, 0.2 * e_fem);
}

}  // namespace
}  // namespace coarsegrain::mra
