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

/// Writes the mesh (2D meshes get z = 0) with fields as inline base64 binary DataArrays
/// (Float64 points and fields, Int32 connectivity/offsets and the cell field "material_id",
/// UInt8 cell types, UInt64 headers, little endian).
/// Written to a temporary name in the same folder and renamed, so a crash never leaves a
/// half-written file under the final name.
/// @throws Error naming the file if it cannot be written, or a field has the wrong size, no
///        name, a duplicate name, or the reserved cell field name "material_id"
void write_vtu(const std::string& file, const mesh::Mesh& mesh, const VtuFields& fields);

/// Reads a .vtu written by write_vtu or by ParaView/VTK without compression (DataArrays in
/// ascii, inline base64 binary, or appended raw/base64 data; any VTK scalar type; UInt32 or
/// UInt64 headers; one Piece): the mesh (element type from the VTK cell types, which must all
/// be the same: 5, 9, 10 or 12; triangles and quads must lie in z = 0 and give a 2D mesh;
/// material ids from the cell field "material_id", 0 if absent) and every other field. Unlike
/// the mesh readers, unused points are kept so that point fields stay aligned.
/// @throws MeshReadError "FILE:LINE: ..." naming the offending XML element
std::pair<mesh::Mesh, VtuFields> read_vtu(const std::string& file);

/// Writes a .pvd collection: one (time, vtu file name relative to the .pvd) per step.
void write_pvd(const std::string& file, const std::vector<std::pair<double, std::string>>& steps);

}  // namespace coarsegrain::io
