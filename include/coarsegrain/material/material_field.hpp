#pragma once
/// @file Per-element material fields: analytic (layers, spheres, checkerboard), grayscale PNG
/// images and 3D label volumes. Each sets mesh.material_ids from the element centroids.
#include <map>
#include <string>

#include "coarsegrain/material/material.hpp"

namespace coarsegrain::material {

/// Layers normal to `axis`: material id = (floor((x_axis - origin) / thickness)) mod ids.size()
/// picks ids[...] cyclically. Sets mesh.material_ids.
void layers(mesh::Mesh& mesh, int axis, double origin, double thickness,
            const std::vector<int>& ids);

/// Spheres (discs in 2D): elements whose centroid is within radius of a centre get `inside`,
/// the others keep their id. centres: #S by dim.
void spheres(mesh::Mesh& mesh, const Matrix& centres, double radius, int inside);

/// Checkerboard of cubes of edge `size` starting at `origin` (size dim): ids a and b alternate.
void checkerboard(mesh::Mesh& mesh, const Eigen::VectorXd& origin, double size, int a, int b);

/// Options of an image-based material (DESIGN.md "material_field.image").
struct ImageField {
    std::string file;      ///< grayscale (or RGB, converted by luminance) PNG
    double E_black = 1.0;  ///< Young's modulus at intensity 0
    double E_white = 1.0;  ///< Young's modulus at intensity 255
    double nu = 0.3;
    double density = 1.0;
    PlaneMode mode = PlaneMode::Strain;
};

/// Material from a grayscale PNG on a 2D grid mesh (or any 2D mesh: the image spans its
/// bounding box). Intensity maps linearly to E between E_black and E_white. Each element takes
/// the pixel containing its centroid, the image spanning the grid box (top image row = largest
/// y): an image with the grid's resolution thus maps pixel to cell one to one (both triangles
/// of a Tri3 cell share the pixel), other resolutions take the nearest pixel. RGB(A) images are
/// converted by Rec. 601 luminance round(0.299 R + 0.587 G + 0.114 B); alpha is ignored.
/// Sets mesh.material_ids to the pixel intensity (0..255) and returns one isotropic material
/// per intensity that occurs.
/// @throws Error naming the file if it cannot be read or decoded, or if the mesh is not 2D
std::map<int, Material> image_field(mesh::Mesh& mesh, const ImageField& options);

/// A 3D label volume: raw bytes (one unsigned byte per voxel, x fastest, then y, then z), with
/// dims voxels spanning the mesh's bounding box. Each element gets the label of the voxel that
/// contains its centroid (label 0..255 = material id). Sets mesh.material_ids. A 2D mesh takes
/// a single slice (dims[2] = 1).
/// @throws Error naming the file if it cannot be read or its size is not dims.prod()
void voxel_field(mesh::Mesh& mesh, const std::string& file, const Eigen::Vector3i& dims);

}  // namespace coarsegrain::material
