#pragma once
/// @file Helpers of the end-to-end tests of the coarsegrain executable.
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

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

}  // namespace coarsegrain::test
