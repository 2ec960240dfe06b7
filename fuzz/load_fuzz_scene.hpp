#pragma once
/// @file Feeds one fuzz input to the scene loader: JSON text in, parse and validate, no
/// assembly or solve. Shared by the libFuzzer target and the test that replays its seeds.
#include <cstdint>
#include <string>
#include <string_view>

#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::fuzz {

/// Largest grid (cells over all axes) the fuzz target builds: the loader accepts any grid this
/// machine can hold (tests/scene checks those limits), but a fuzz execution must take
/// milliseconds, not build a ten-million-cell mesh.
inline constexpr double kMaxFuzzGridCells = 1e4;

/// True if some "cells" array of `j` multiplies out above kMaxFuzzGridCells.
inline bool has_large_grid(const nlohmann::json& j) {
    if (j.is_object()) {
        for (const auto& [key, value] : j.items()) {
            if (key == "cells" && value.is_array()) {
                double cells = 1;
                for (const auto& c : value) cells *= c.is_number() ? std::abs(c.get<double>()) : 1;
                if (cells > kMaxFuzzGridCells) return true;
            }
            if (has_large_grid(value)) return true;
        }
    } else if (j.is_array()) {
        for (const auto& value : j)
            if (has_large_grid(value)) return true;
    }
    return false;
}

/// Parses `data` as a scene with relative files resolved against `base_dir`. Throws
/// coarsegrain::Error for bad input; anything else escaping is a bug.
inline void load_fuzz_scene(const std::uint8_t* data, std::size_t size,
                            const std::string& base_dir) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const nlohmann::json j = scene::parse_json(text, "fuzz.json");
    if (has_large_grid(j)) return;
    scene::parse_scene(j, "fuzz.json", base_dir);
}

}  // namespace coarsegrain::fuzz
