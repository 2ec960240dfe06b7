#pragma once
/// @file Feeds one fuzz input to a mesh reader. Shared by the libFuzzer target and by the test
/// that replays the saved crash inputs in tests/data/fuzz_regressions.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/io/vtu.hpp"

namespace coarsegrain::fuzz {

/// Writes `data` (without its first byte) to files in `dir` and reads them. The first byte
/// picks the reader, by its value mod 4 (so '0' '1' '2' '3' in readable seeds):
/// 0 Gmsh (.msh); 1 TetGen (.node, and .ele = the part after the first NUL byte; no .ele if
/// there is none); 2 Medit (.mesh); 3 VTU.
/// @throws coarsegrain::Error (or MeshReadError) for bad input: anything else is a bug
inline void read_fuzz_input(const std::uint8_t* data, std::size_t size, const std::string& dir) {
    if (size == 0) return;
    const auto* text = reinterpret_cast<const char*>(data + 1);
    const std::string body(text, size - 1);
    const auto write = [&](const std::string& name, const std::string& bytes) {
        std::ofstream(dir + "/" + name, std::ios::binary | std::ios::trunc) << bytes;
        return dir + "/" + name;
    };
    switch (data[0] % 4) {
        case 0: io::read_gmsh(write("input.msh", body)); break;
        case 1: {
            const std::size_t nul = body.find('\0');
            write("input.node", body.substr(0, nul));
            if (nul == std::string::npos)
                std::filesystem::remove(dir + "/input.ele");
            else
                write("input.ele", body.substr(nul + 1));
            io::read_tetgen(dir + "/input");
            break;
        }
        case 2: io::read_medit(write("input.mesh", body)); break;
        default: io::read_vtu(write("input.vtu", body)); break;
    }
}

}  // namespace coarsegrain::fuzz
