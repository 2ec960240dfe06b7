#pragma once
/// @file Helpers of the end-to-end tests of the coarsegrain executable.
#include <cstdint>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace coarsegrain::test {

using nlohmann::json;

inline const std::string kCli = COARSEGRAIN_CLI;

// A small valid 3D scene: a 2x1x1 two-material bar clamped at x = 0, gravity and end traction.
inline json small_scene() {
    return json::parse(R"({
      "dimension": 3,
      "mesh": { "grid": { "min": [0,0,0], "max": [2,1,1], "cells": [8,4,4], "element": "hex" } },
      "material_field": { "layers": { "axis": "x", "thickness": 0.5, "ids": [1, 2] } },
      "materials": { "1": { "E": 1000, "nu": 0.3, "density": 1 },
                     "2": { "E": 10, "nu": 0.45, "density": 2 } },
      "dirichlet": [ { "box": { "min": [-1e-9,-1,-1], "max": [1e-9,2,2] } } ],
      "loads": { "gravity": [0,0,-1],
                 "traction": [ { "box": { "min": [2,-1,-1], "max": [2,2,2] }, "value": [0,0,-0.1] } ] },
      "probes": [ [2,0.5,0.5], [1,0.5,0.5] ]
    })");
}

inline std::string write_scene(const std::string& dir, const json& j,
                               const std::string& name = "scene.json") {
    const std::string file = dir + "/" + name;
    std::ofstream(file) << j.dump(2);
    return file;
}

inline json read_json(const std::string& file) {
    std::ifstream in(file);
    return json::parse(in);
}

struct Result {
    int code;
    std::string output;
};

inline Result cli(const std::string& args) {
    Result r;
    r.code = run(kCli + " --quiet " + args, &r.output);
    return r;
}

/// What a GIF file holds, read block by block (GIF89a specification): its size, its images
/// (frames) and their delays; `error` says why reading stopped before the trailer (empty if the
/// file is a well-formed GIF).
struct GifInfo {
    int width = 0, height = 0;
    int frames = 0;
    std::vector<int> delays_cs;  ///< delay of each Graphic Control Extension, 1/100 s
    std::string error;
};

inline GifInfo read_gif(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    const std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), {});
    GifInfo g;
    const auto fail = [&](const std::string& why) {
        g.error = why;
        return g;
    };
    std::size_t i = 0;
    const auto need = [&](std::size_t n) { return i + n <= b.size(); };
    const auto u16 = [&](std::size_t at) { return b[at] | b[at + 1] << 8; };
    const auto skip_sub_blocks = [&] {
        while (need(1) && b[i] != 0) i += 1 + b[i];
        if (!need(1)) return false;
        ++i;  // the block terminator
        return true;
    };
    const std::string signature(b.begin(), b.begin() + std::min<std::size_t>(6, b.size()));
    if (signature != "GIF89a" && signature != "GIF87a") return fail("no GIF signature");
    if (!need(13)) return fail("no logical screen descriptor");
    g.width = u16(6);
    g.height = u16(8);
    const int packed = b[10];
    i = 13 + (packed & 0x80 ? 3 * (2 << (packed & 7)) : 0);  // global colour table
    while (need(1)) {
        const int block = b[i++];
        if (block == 0x3B) return g;  // trailer
        if (block == 0x21) {          // extension: label, then sub-blocks
            if (!need(1)) break;
            if (b[i] == 0xF9 && need(6)) g.delays_cs.push_back(u16(i + 3));
            ++i;
            if (!skip_sub_blocks()) break;
        } else if (block == 0x2C) {  // image descriptor, local colour table, LZW data
            if (!need(10)) break;
            const int left = u16(i), top = u16(i + 2), w = u16(i + 4), h = u16(i + 6);
            if (left + w > g.width || top + h > g.height) return fail("image off screen");
            const int local = b[i + 8];
            i += 9 + (local & 0x80 ? 3 * (2 << (local & 7)) : 0) + 1;  // + LZW code size
            if (!skip_sub_blocks()) break;
            ++g.frames;
        } else {
            return fail("unknown block " + std::to_string(block));
        }
    }
    return fail("truncated (no trailer)");
}

}  // namespace coarsegrain::test
