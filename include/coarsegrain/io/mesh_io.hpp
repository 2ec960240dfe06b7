#pragma once
/// @file Mesh file readers and writers.
///
/// Readers keep only the elements of the highest dimension present (lower-dimensional
/// boundary elements in a Gmsh file are skipped); a file mixing two element types of that
/// dimension (e.g. tets and hexes) or holding an unsupported one (prisms, second-order
/// elements) is rejected. Nodes that no kept element uses (e.g. a Gmsh circle's centre) are
/// dropped; the others keep the file's order, renumbered 0..#V-1. A mesh of triangles or quads
/// is 2D (dim 2): its nodes must lie in the plane z = 0. Every reader validates the result
/// (mesh::validate) and reports errors as MeshReadError "FILE:LINE: what was expected, what was
/// found"; absurd counts in a small file are reported, never allocated.
#include <string>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::io {

/// Gmsh .msh ASCII, format 2.2 or 4.1: triangles, quads, tets, hexes. The element's first
/// physical tag is its material id (0 if it has none). Node tags may be sparse.
mesh::Mesh read_gmsh(const std::string& file);
/// Writes Gmsh ASCII 2.2 (version = 2) or 4.1 (version = 4); material ids as physical tags.
void write_gmsh(const std::string& file, const mesh::Mesh& mesh, int version = 4);

/// TetGen: `base.node` and `base.ele` (base may be given with either extension or none).
/// Numbering starts at 0 or 1 (the first node's number decides); attributes and boundary
/// markers of nodes are ignored. The first element attribute, if present, is the material id.
/// Also reads Triangle's 2D .node/.ele (3-node elements, 2D nodes).
mesh::Mesh read_tetgen(const std::string& base);
/// Writes `base.node` and `base.ele` (1-based, the material id as the element attribute).
/// @throws Error for quads and hexes, which TetGen and Triangle files cannot hold
void write_tetgen(const std::string& base, const mesh::Mesh& mesh);

/// Medit .mesh (ASCII): Vertices, Triangles, Quadrilaterals, Tetrahedra, Hexahedra; the
/// element reference is its material id.
mesh::Mesh read_medit(const std::string& file);
void write_medit(const std::string& file, const mesh::Mesh& mesh);

/// Dispatches on the extension: .msh, .node/.ele, .mesh, .vtu (read_vtu's mesh).
/// @throws MeshReadError for any other extension
mesh::Mesh read_mesh(const std::string& file);
/// Dispatches on the extension: .msh, .node/.ele, .mesh, .vtu.
void write_mesh(const std::string& file, const mesh::Mesh& mesh);

}  // namespace coarsegrain::io
