// Every method across material contrasts 1e0 to 1e9: a finite coarse model whose errors are
// finite, or an Error that says why; never NaN. (From 1e7 on, the effective tensor of the
// checkerboard's corner element has a largest eigenvalue near 0.4 contrast^2, far above the
// stiffest phase, and is refused by the relative positive-definiteness test, naming the
// element; docs/guide.md, "effective-tensor".)
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/coarsen/runtime.hpp"
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

}  // namespace
}  // namespace coarsegrain
