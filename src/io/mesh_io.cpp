#include "coarsegrain/io/mesh_io.hpp"

#include <filesystem>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/vtu.hpp"

namespace coarsegrain::io {

namespace {

std::string extension(const std::string& file) {
    return std::filesystem::path(file).extension().string();
}

}  // namespace

mesh::Mesh read_mesh(const std::string& file) {
    const std::string ext = extension(file);
    if (ext == ".msh") return read_gmsh(file);
    if (ext == ".node" || ext == ".ele") return read_tetgen(file);
    if (ext == ".mesh") return read_medit(file);
    if (ext == ".vtu") return read_vtu(file).first;
    if (ext == ".meshb")
        throw MeshReadError(fmt::format(
            "{}: binary Medit files (.meshb) are not supported; save as ASCII .mesh", file));
    throw MeshReadError(
        fmt::format("{}: unknown mesh file extension '{}'; expected .msh (Gmsh), "
                    ".node/.ele (TetGen), .mesh (Medit) or .vtu",
                    file, ext));
}

void write_mesh(const std::string& file, const mesh::Mesh& mesh) {
    const std::string ext = extension(file);
    if (ext == ".msh") return write_gmsh(file, mesh);
    if (ext == ".node" || ext == ".ele") return write_tetgen(file, mesh);
    if (ext == ".mesh") return write_medit(file, mesh);
    if (ext == ".vtu") return write_vtu(file, mesh, {});
    throw Error(
        fmt::format("cannot write {}: unknown mesh file extension '{}'; expected .msh, "
                    ".node/.ele, .mesh or .vtu",
                    file, ext));
}

}  // namespace coarsegrain::io
