#pragma once
/// @file VTK XML UnstructuredGrid (.vtu) and ParaView collections (.pvd) for time series.
#include <string>
#include <utility>
#include <vector>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::io {

/// A named field: values has one row per point (or cell) and one column per component.
struct Field {
    std::string name;
    Matrix values;
};

/// Fields attached to a VTU file.
struct VtuFields {
    std::vector<Field> point_data;
    std::vector<Field> cell_data;
    /// Adds an interleaved nodal vector field (dim values per node) as a point field with
    /// 3 components (z = 0 in 2D, so ParaView's "Warp By Vector" works).
    void add_point_vector(const std::string& name, const Vector& interleaved, int dim);
    void add_point_scalar(const std::string& name, const Vector& values);
    void add_cell_scalar(const std::string& name, const Vector& values);
    void add_cell(const std::string& name, const Matrix& values);
};

/// Writes the mesh (2D meshes get z = 0) with fields, ASCII-free base64 binary data.
/// Written to a temporary name in the same folder and renamed, so a crash never leaves a
/// half-written file under the final name.
/// @throws Error naming the file if it cannot be written, or a field has the wrong size
void write_vtu(const std::string& file, const mesh::Mesh& mesh, const VtuFields& fields);

/// Reads a .vtu written by write_vtu (or ParaView, ascii or base64 binary, uncompressed):
/// the mesh (element type from the VTK cell types; material id from a cell field
/// "material_id" if present) and all fields.
std::pair<mesh::Mesh, VtuFields> read_vtu(const std::string& file);

/// Writes a .pvd collection: one (time, vtu file name relative to the .pvd) per step.
void write_pvd(const std::string& file, const std::vector<std::pair<double, std::string>>& steps);

}  // namespace coarsegrain::io
