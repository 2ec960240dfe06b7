// The "corotation" block's linear_solve key: its values, and bad values rejected with the key
// and the valid names.
#include <gtest/gtest.h>

#include "coarsegrain/scene/scene.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

TEST(CorotationOptions, LinearSolveNamesTheKrylovOption) {
    EXPECT_EQ(scene::parse_corotation_options(nlohmann::json::object(), "s.json").linear_solve,
              sim::LinearSolve::LaggedKrylov);
    for (const sim::LinearSolve solve : {sim::LinearSolve::Factorize, sim::LinearSolve::RestKrylov,
                                         sim::LinearSolve::LaggedKrylov}) {
        const nlohmann::json j = {{"linear_solve", sim::linear_solve_name(solve)}};
        EXPECT_EQ(scene::parse_corotation_options(j, "s.json").linear_solve, solve);
    }
}

TEST(CorotationOptions, BadLinearSolveIsRejectedNamingTheKey) {
    test::expect_error(
        [] {
            scene::parse_corotation_options({{"linear_solve", "pcg"}}, "s.json");
        },
        "s.json: corotation.linear_solve: unknown value \"pcg\"; expected one of "
        "\"factorize\", \"rest_krylov\", \"lagged_krylov\"");
    test::expect_error(
        [] {
            scene::parse_corotation_options({{"linear_solve", 1}}, "s.json");
        },
        "corotation.linear_solve");
    test::expect_error(
        [] {
            scene::parse_corotation_options({{"linear_solver", "factorize"}}, "s.json");
        },
        "linear_solver");
}

}  // namespace
}  // namespace coarsegrain
