#pragma once
/// @file Reading the displacements ccx prints to <job>.dat (*NODE PRINT ... U).
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::test {

/// Every displacement block of a ccx .dat file, in time order: one row per node (row k: node
/// k + 1) with its three components; rows of nodes the block does not list are NaN.
inline std::vector<Matrix> read_ccx_displacements(const std::string& file) {
    std::ifstream in(file);
    std::vector<Matrix> blocks;
    for (std::string line; std::getline(in, line);) {
        if (line.find("displacements") != std::string::npos) {
            blocks.emplace_back(0, 3);
            continue;
        }
        std::istringstream s(line);
        Index node = 0;
        double u[3];
        if (blocks.empty() || !(s >> node >> u[0] >> u[1] >> u[2]) || node < 1) continue;
        Matrix& b = blocks.back();
        if (b.rows() < node) {
            const Index old = b.rows();
            b.conservativeResize(node, 3);
            b.bottomRows(node - old).setConstant(std::nan(""));
        }
        b.row(node - 1) << u[0], u[1], u[2];
    }
    return blocks;
}

/// A block's first `dim` components, interleaved by node (a model's DOF vector).
inline Vector interleaved(const Matrix& block, int dim) {
    Vector u(block.rows() * dim);
    for (Index v = 0; v < block.rows(); ++v)
        for (int k = 0; k < dim; ++k) u[dim * v + k] = block(v, k);
    return u;
}

}  // namespace coarsegrain::test
