// Every method across material contrasts 1e0 to 1e9: a finite coarse model whose errors are
// finite, or an Error that says why; never NaN. The effective tensors of the checkerboard grow as
// contrast^2 where a coarse element's nodes ride on stiff squares (its coarse mollifier G has
// condition number 0.51 contrast): a property of Eq. 8, not round-off; from 1e7 on the corner
// element's tensor is refused by the relative positive-definiteness test, naming the element
// (docs/guide.md, "effective-tensor").
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/material/material.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

// A 2D square of checkered materials E = 1 and E = contrast, hung from its top edge: 16x16
// quads, a 4x4 triangle coarse mesh and 3 hierarchy levels.
scene::Scene checker(double contrast) {
    const nlohmann::json j = {
        {"mesh",
         {{"grid", {{"min", {0, 0}}, {"max", {1, 1}}, {"cells", {16, 16}}, {"element", "quad"}}}}},
        {"material_field", {{"checkerboard", {{"size", 0.25}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 1.0}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", contrast}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, 0.999}}, {"max", {2, 2}}}}}}},
        {"loads", {{"gravity", {0, -1}}}},
        {"coarse",
         {{"mesh",
           {{"grid", {{"min", {0, 0}}, {"max", {1, 1}}, {"cells", {4, 4}}, {"element", "tri"}}}}},
          {"levels", 3},
          {"cell_tensors", false},
          {"spectrum_max_dofs", 0}}}};
    return scene::parse_scene(j, "checker", "");
}

TEST(CoarsenContrastSlow, EveryMethodIsFiniteOrSaysWhy) {
    for (int p = 0; p <= 9; ++p) {
        const double contrast = std::pow(10.0, p);
        const scene::Scene sc = checker(contrast);
        const scene::FineModel fine = scene::build_fine_model(sc);
        const Vector u = scene::solve_static(fine, sc.solver).u;
        ASSERT_TRUE(u.allFinite()) << "contrast " << contrast;
        for (const std::string& method : coarsen::configured_methods(sc)) {
            SCOPED_TRACE(method + " at contrast " + std::to_string(contrast));
            try {
                const coarsen::CoarseModel m = coarsen::build_coarse_model(sc, fine, method);
                EXPECT_TRUE(Matrix(m.K).allFinite());
                const coarsen::CoarseSolution uc = coarsen::solve_coarse(m, sc.solver);
                const coarsen::Errors e = coarsen::compare(fine, u, uc.u_fine);
                for (const double v : {e.energy_rel, e.l2_rel, e.compliance_ratio, e.stress_rel})
                    EXPECT_TRUE(std::isfinite(v)) << v;
            } catch (const Error& e) {
                // A refusal must name what failed: a coarse element, a matrix or a material.
                EXPECT_THAT(e.what(), ::testing::AnyOf(::testing::HasSubstr("coarse element"),
                                                       ::testing::HasSubstr("positive definite"),
                                                       ::testing::HasSubstr("material")))
                    << e.what();
                std::printf("contrast %.0e %s: %s\n", contrast, method.c_str(), e.what());
            }
        }
    }
}

// Eq. 8 on the checkerboard, C_q = G_q^-T <G^T C G>_q G_q^-1: the coarse elements whose nodes lie
// on the edges of stiff squares see strains ~1/contrast in some harmonic combination whose fine
// energy, in the soft material between them, stays O(1), so their tensor is ~contrast^2 in that
// strain. Measured (the same with the harmonic problem solved in long double, whose residual is
// 3 orders smaller): cond(G) = 0.509-0.513 contrast from 1e3 to 1e9; the largest eigenvalue of
// C is 0.0425-0.0429 contrast^2 from 1e3 to 1e7, far above the stiffest phase (1.92 contrast):
// the tensors obey no Voigt bound; at contrast 1 they are the material's. From 1e8 the harmonic
// solve's round-off adds to it (0.07 contrast^2 at 1e8, 24 at 1e9; 0.05 and 1.4 with the long
// double solve).
TEST(CoarsenContrastSlow, EffectiveTensorsGrowAsContrastSquaredWhereTheMollifierIsIllConditioned) {
    for (int p = 0; p <= 9; ++p) {
        if (p == 1 || p == 2) continue;  // the c^2 law sets in from about 1e3
        const double contrast = std::pow(10.0, p);
        SCOPED_TRACE("contrast " + std::to_string(contrast));
        const scene::Scene sc = checker(contrast);
        const scene::FineModel fine = scene::build_fine_model(sc);
        const homogenize::Coarsening c = homogenize::coarsening(sc, fine, "effective-tensor");
        double cond = 0, lambda = 0;
        for (std::size_t q = 0; q < c.C.size(); ++q) {
            cond = std::max(cond, homogenize::condition_number(2, c.G_coarse[q]));
            lambda = std::max(
                lambda, Eigen::SelfAdjointEigenSolver<Matrix>(Matrix(c.C[q].topLeftCorner(3, 3)))
                            .eigenvalues()
                            .maxCoeff());
        }
        if (p == 0) {
            // One material: every tensor is that material's (round-off of the harmonic solves).
            const Matrix C = material::tensor(fine.materials.of(0), 2);
            for (const Mandel6& Cq : c.C) EXPECT_LT((Cq.topLeftCorner(3, 3) - C).norm(), 1e-8);
            continue;
        }
        EXPECT_GT(cond / contrast, 0.5);
        EXPECT_LT(cond / contrast, 0.52);
        if (p <= 7) {
            EXPECT_GT(lambda / (contrast * contrast), 0.042);
            EXPECT_LT(lambda / (contrast * contrast), 0.044);
        }
        // The coarse model holds up to 1e6; from 1e7 the tensor's eigenvalue ratio is below
        // 1e-12 and the model is refused, naming the element.
        if (p <= 6) {
            EXPECT_NO_THROW(coarsen::build_coarse_model(sc, fine, "effective-tensor"));
        } else {
            test::expect_error([&] { coarsen::build_coarse_model(sc, fine, "effective-tensor"); },
                               "the effective-tensor tensor of coarse element");
        }
    }
}

}  // namespace
}  // namespace coarsegrain
