#pragma once
/// @file Feeds one fuzz input to a mesh reader. Shared by the libFuzzer target and by the tests
/// that replay the seed corpus and the saved crash inputs.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <tuple>

#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/io/vtu.hpp"

namespace coarsegrain::fuzz {

/// True if a and b hold the same values, NaN equal to NaN.
inline bool same_values(const Matrix& a, const Matrix& b) {
    if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
    for (Index i = 0; i < a.size(); ++i) {
        const double x = a.data()[i], y = b.data()[i];
        if (!(x == y || (x != x && y != y))) return false;
    }
    return true;
}

inline bool same_mesh(const mesh::Mesh& a, const mesh::Mesh& b) {
    return a.type == b.type && same_values(a.rest_positions, b.rest_positions) &&
           a.elements == b.elements && a.material_ids == b.material_ids;
}

/// The differential check: a mesh that was read successfully must survive every writer and
/// its reader unchanged. @throws std::logic_error (a bug, not bad input) otherwise
inline void check_round_trips(const mesh::Mesh& m, const io::VtuFields& fields,
                              const std::string& dir) {
    const auto expect = [](bool ok, const char* what) {
        if (!ok) throw std::logic_error(std::string("round trip changed the mesh: ") + what);
    };
    io::write_gmsh(dir + "/rt2.msh", m, 2);
    expect(same_mesh(io::read_gmsh(dir + "/rt2.msh"), m), "gmsh 2.2");
    io::write_gmsh(dir + "/rt4.msh", m, 4);
    expect(same_mesh(io::read_gmsh(dir + "/rt4.msh"), m), "gmsh 4.1");
    io::write_medit(dir + "/rt.mesh", m);
    expect(same_mesh(io::read_medit(dir + "/rt.mesh"), m), "medit");
    if (mesh::is_simplex(m.type)) {
        io::write_tetgen(dir + "/rt", m);
        expect(same_mesh(io::read_tetgen(dir + "/rt"), m), "tetgen");
    }
    io::write_vtu(dir + "/rt.vtu", m, fields);
    const auto [back, back_fields] = io::read_vtu(dir + "/rt.vtu");
    expect(same_mesh(back, m), "vtu");
    for (const auto* group : {&fields.point_data, &fields.cell_data}) {
        const auto& other =
            group == &fields.point_data ? back_fields.point_data : back_fields.cell_data;
        expect(other.size() == group->size(), "vtu field count");
        for (std::size_t i = 0; i < other.size(); ++i)
            expect(other[i].name == (*group)[i].name &&
                       same_values(other[i].values, (*group)[i].values),
                   "vtu field");
    }
}

/// Writes `data` (without its first byte) to files in `dir` and reads them; a mesh read
/// successfully then goes through check_round_trips. The first byte picks the reader, by its
/// value mod 4 (so '0' '1' '2' '3' in readable seeds): 0 Gmsh (.msh); 1 TetGen (.node, and
/// .ele = the part after the first NUL byte; no .ele if there is none); 2 Medit (.mesh); 3 VTU.
/// @throws coarsegrain::Error for bad input: any other exception is a bug
inline void read_fuzz_input(const std::uint8_t* data, std::size_t size, const std::string& dir) {
    if (size == 0) return;
    const auto* text = reinterpret_cast<const char*>(data + 1);
    const std::string body(text, size - 1);
    const auto write = [&](const std::string& name, const std::string& bytes) {
        std::ofstream(dir + "/" + name, std::ios::binary | std::ios::trunc) << bytes;
        return dir + "/" + name;
    };
    mesh::Mesh m;
    io::VtuFields fields;
    switch (data[0] % 4) {
        case 0:
            m = io::read_gmsh(write("input.msh", body));
            break;
        case 1: {
            const std::size_t nul = body.find('\0');
            write("input.node", body.substr(0, nul));
            if (nul == std::string::npos)
                std::filesystem::remove(dir + "/input.ele");
            else
                write("input.ele", body.substr(nul + 1));
            m = io::read_tetgen(dir + "/input");
            break;
        }
        case 2:
            m = io::read_medit(write("input.mesh", body));
            break;
        default:
            std::tie(m, fields) = io::read_vtu(write("input.vtu", body));
            break;
    }
    check_round_trips(m, fields, dir);
}

}  // namespace coarsegrain::fuzz
