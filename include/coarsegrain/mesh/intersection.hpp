#pragma once
/// @file Exact intersection measures |T_p ∩ 𝕋_q| between the elements of two simplicial meshes
/// of the same object: the weights of the fine-to-coarse average of Kharevych et al. 2009,
/// Eq. 8. The meshes need not be nested or aligned, and the coarse one may stick out of the
/// fine one.
///
/// Method: the smaller simplex of a pair is clipped by the D+1 half-spaces of the other
/// (Sutherland-Hodgman on a polygon in 2D; in 3D the same on a polyhedron stored as a graph of
/// degree-3 vertices, after Powell & Abel 2015, "An exact general remeshing scheme applied to
/// physically conservative voxelization"), and the measure of what remains is summed from a fan
/// of triangles (2D, shoelace) or tets (3D, divergence theorem). The result is a continuous
/// function of the corners, so round-off only perturbs it by round-off.
///
/// Tolerance: a vertex within 1e-14 H of a clipping plane, H the larger bounding-box extent of
/// the two simplices, counts as lying on it. Shared faces, coincident vertices and coplanar
/// faces (nested or aligned grids) thus give exact results: a simplex inside the other is
/// returned with its own measure untouched, simplices that only touch give exactly 0. Results
/// below 1e-13 times the smaller measure (what is left of a lower-dimensional contact after
/// round-off) are reported as 0.
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// One pair of overlapping elements and the measure (area in 2D, volume in 3D) of their
/// intersection.
struct Overlap {
    Index fine;
    Index coarse;
    double measure;
};

/// Measure of the intersection of two simplices (triangles in 2D: 3x2 corners; tets in 3D: 4x3
/// corners), by convex clipping. Either orientation of the corners is accepted. Symmetric to the
/// last bit: measure(a, b) == measure(b, a).
/// @param[in] a  D+1 by D corners, one row per corner
/// @param[in] b  D+1 by D corners
/// @return |a ∩ b| >= 0
/// @throws Error if the shapes are not 3x2 or 4x3 (both the same) or a simplex is degenerate
///         (measure <= 1e-12 h^D, h its bounding-box extent, as in mesh::validate)
double simplex_intersection_measure(const Matrix& a, const Matrix& b);

/// Every (fine element, coarse element) pair with positive intersection measure, candidates
/// from a bounding-volume hierarchy (AabbTree) over the elements of the mesh with fewer of
/// them; sorted by coarse, then fine. Both meshes simplicial (Tri3 or Tet4) of the same
/// dimension. Runs in parallel (OpenMP).
///
/// Each measure is bit-for-bit simplex_intersection_measure of the two elements' corners. For
/// meshes of the same domain, sum over coarse of the measures = |T_p| and sum over fine =
/// |𝕋_q|, up to round-off; where the coarse mesh sticks out, the sum over fine is |𝕋_q ∩ Ω|.
/// @throws Error if a mesh is not simplicial, the dimensions differ, or an element is
///         degenerate (naming the mesh and element)
std::vector<Overlap> intersect(const Mesh& fine, const Mesh& coarse);

}  // namespace coarsegrain::mesh
