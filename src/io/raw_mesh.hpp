#pragma once
/// @file Internal: what a mesh reader collects before it becomes a mesh::Mesh. Shared by the
/// Gmsh, TetGen and Medit readers so that they choose element types, remap node numbers, drop
/// unused nodes, detect 2D meshes and validate the same way.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::io::detail {

class TextReader;

/// Elements of one supported type as the file numbers their nodes.
struct RawElements {
    std::vector<std::int64_t> nodes;  ///< nodes_per_element per element, node numbers of the file
    std::vector<Index> material;      ///< material id per element
    std::vector<int> line;            ///< line of the file per element (for messages)
};

/// Nodes and elements as read from a file.
struct RawMesh {
    std::vector<double> xyz;            ///< 3 coordinates per node (z = 0 for 2D files)
    std::vector<std::int64_t> tags;     ///< node number per node; empty: tag_base + position
    std::int64_t tag_base = 0;          ///< first node number when tags is empty (0 or 1)
    std::vector<int> node_line;         ///< line of the file per node
    std::array<RawElements, 4> blocks;  ///< indexed by mesh::ElementType

    /// Highest dimension among elements of types coarsegrain does not read (second-order,
    /// prisms, ...), the first such element's line and name; dim -1 if there were none.
    int other_dim = -1;
    int other_line = 0;
    std::string other_name;

    void add_node(double x, double y, double z, int line);
    void add_element(mesh::ElementType type, const std::int64_t* nodes, Index material, int line);
    /// Records an element of a type coarsegrain does not read; it is an error only if no
    /// readable element has a higher dimension (then it is not a skippable boundary element).
    void add_other(int dim, int line, const std::string& name);
};

/// Builds and validates the mesh: keeps the elements of the highest dimension (a file mixing
/// two element types of that dimension is an error), maps the file's node numbers to indices,
/// drops nodes no kept element uses (keeping the file order of the others), makes a tri/quad
/// mesh 2D (its nodes must lie in z = 0), and runs mesh::validate.
/// @param reader  for the file name and error messages; end_line is reported when the file has
///                no elements at all
/// @throws MeshReadError "FILE:LINE: ..." naming the offending element or node
mesh::Mesh build_mesh(const RawMesh& raw, const TextReader& reader, int end_line);

/// Runs mesh::validate and rethrows its error as MeshReadError "FILE:LINE: ...", the line
/// being that of the first bad element (element_line[e]; if empty, `fallback_line`).
void validate_read_mesh(const mesh::Mesh& mesh, const std::string& file,
                        const std::vector<int>& element_line, int fallback_line);

}  // namespace coarsegrain::io::detail
