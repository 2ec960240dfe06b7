#pragma once
/// @file A 2D scene shared by the dynamics tests of the hierarchy.
#include <nlohmann/json.hpp>

namespace coarsegrain::test {

/// A 2D bar [0, 2] x [0, 1] of stiff/heavy (E = 1000, density 3) and soft/light (E = 1,
/// density 0.5) layers 0.25 thick across its axis, clamped at x = 0, under gravity (0, -1), on
/// 16x8 quads.
inline nlohmann::json layered_bar_json() {
    return {
        {"dimension", 2},
        {"mesh",
         {{"grid", {{"min", {0, 0}}, {"max", {2, 1}}, {"cells", {16, 8}}, {"element", "quad"}}}}},
        {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.25}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 1000.0}, {"nu", 0.3}, {"density", 3.0}}},
          {"2", {{"E", 1.0}, {"nu", 0.4}, {"density", 0.5}}}}},
        {"dirichlet", {{{"box", {{"min", {-1e-9, -1}}, {"max", {1e-9, 2}}}}}}},
        {"loads", {{"gravity", {0, -1}}}}};
}

}  // namespace coarsegrain::test
