#include "coarsegrain/material/material_field.hpp"

// stb_image is a third-party single-file library: its own warnings are not ours to fix.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wsign-compare"
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_FAILURE_USERMSG
#include <stb_image.h>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/grid.hpp"

namespace coarsegrain::material {

namespace {

/// Index of the cell of a uniform subdivision of [lo, hi] into n cells that contains x (clamped
/// to 0..n-1, so points on the upper face belong to the last cell).
int cell_index(double x, double lo, double hi, int n) {
    const int i = static_cast<int>(std::floor((x - lo) / (hi - lo) * n));
    return std::clamp(i, 0, n - 1);
}

/// floor(a / b) mod n for b > 0, always in 0..n-1.
int periodic_index(double a, double b, int n) {
    const long long k = static_cast<long long>(std::floor(a / b));
    return static_cast<int>(((k % n) + n) % n);
}

}  // namespace

void layers(mesh::Mesh& mesh, int axis, double origin, double thickness,
            const std::vector<int>& ids) {
    CG_VERIFY(axis >= 0 && axis < mesh.dim(), "layers: axis = {} must be in 0..{}", axis,
              mesh.dim() - 1);
    CG_VERIFY(std::isfinite(thickness) && thickness > 0, "layers: thickness = {} must be > 0",
              thickness);
    CG_VERIFY(!ids.empty(), "layers: the list of material ids is empty");
    const Matrix c = mesh::element_centroids(mesh);
    const int n = static_cast<int>(ids.size());
    mesh.material_ids.resize(mesh.num_elements());
    for (Index e = 0; e < mesh.num_elements(); ++e)
        mesh.material_ids[e] =
            ids[static_cast<std::size_t>(periodic_index(c(e, axis) - origin, thickness, n))];
}

void spheres(mesh::Mesh& mesh, const Matrix& centres, double radius, int inside) {
    CG_VERIFY(centres.cols() == mesh.dim(), "spheres: centres have {} coordinates, expected {}",
              centres.cols(), mesh.dim());
    CG_VERIFY(std::isfinite(radius) && radius > 0, "spheres: radius = {} must be > 0", radius);
    CG_VERIFY(mesh.material_ids.size() == mesh.num_elements(),
              "spheres: {} material ids for {} elements", mesh.material_ids.size(),
              mesh.num_elements());
    const Matrix c = mesh::element_centroids(mesh);
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (Index s = 0; s < centres.rows(); ++s)
            if ((c.row(e) - centres.row(s)).squaredNorm() <= radius * radius) {
                mesh.material_ids[e] = inside;
                break;
            }
}

void checkerboard(mesh::Mesh& mesh, const Eigen::VectorXd& origin, double size, int a, int b) {
    CG_VERIFY(origin.size() == mesh.dim(), "checkerboard: origin has {} coordinates, expected {}",
              origin.size(), mesh.dim());
    CG_VERIFY(std::isfinite(size) && size > 0, "checkerboard: size = {} must be > 0", size);
    const Matrix c = mesh::element_centroids(mesh);
    mesh.material_ids.resize(mesh.num_elements());
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        int parity = 0;
        for (int d = 0; d < mesh.dim(); ++d) parity += periodic_index(c(e, d) - origin[d], size, 2);
        mesh.material_ids[e] = parity % 2 == 0 ? a : b;
    }
}

std::map<int, Material> image_field(mesh::Mesh& mesh, const ImageField& options) {
    CG_VERIFY(mesh.dim() == 2, "image_field '{}': needs a 2D mesh, got a {} mesh", options.file,
              mesh::element_name(mesh.type));
    CG_VERIFY(std::filesystem::is_regular_file(options.file),
              "image_field: cannot read '{}': no such file", options.file);
    int w = 0, h = 0, channels = 0;
    const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
        stbi_load(options.file.c_str(), &w, &h, &channels, 0), stbi_image_free);
    CG_VERIFY(pixels != nullptr, "image_field: cannot read '{}' as a PNG image: {}", options.file,
              stbi_failure_reason());

    // Grayscale intensity per pixel: gray (+alpha) as is; RGB(A) by Rec. 601 luminance
    // 0.299 R + 0.587 G + 0.114 B, rounded; alpha is ignored.
    const auto intensity = [&](int row, int col) {
        const unsigned char* p =
            pixels.get() + (static_cast<std::size_t>(row) * w + col) * channels;
        if (channels < 3) return static_cast<int>(p[0]);
        return static_cast<int>(std::lround(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]));
    };

    // The image spans the grid box (or the bounding box of another mesh); each element takes
    // the pixel that contains its centroid, which for an image with the grid's resolution is
    // the pixel of the element's cell (one to one). Image row 0 is the largest y.
    Eigen::Vector2d lo, hi;
    if (mesh.grid) {
        lo = mesh.grid->min.head<2>();
        hi = mesh.grid->max.head<2>();
    } else {
        const Matrix box = mesh::bounding_box(mesh);
        lo = box.row(0).transpose();
        hi = box.row(1).transpose();
    }
    const Matrix c = mesh::element_centroids(mesh);
    mesh.material_ids.resize(mesh.num_elements());
    std::set<int> present;
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        const int col = cell_index(c(e, 0), lo[0], hi[0], w);
        const int row = h - 1 - cell_index(c(e, 1), lo[1], hi[1], h);
        const int value = intensity(row, col);
        mesh.material_ids[e] = value;
        present.insert(value);
    }
    std::map<int, Material> by_id;
    for (const int value : present) {
        const double E = options.E_black + (options.E_white - options.E_black) * value / 255.0;
        by_id[value] = isotropic(2, E, options.nu, options.density, options.mode);
    }
    return by_id;
}

void voxel_field(mesh::Mesh& mesh, const std::string& file, const Eigen::Vector3i& dims) {
    CG_VERIFY((dims.array() >= 1).all(), "voxel_field '{}': dims {}x{}x{} must all be >= 1", file,
              dims[0], dims[1], dims[2]);
    CG_VERIFY(mesh.dim() == 3 || dims[2] == 1,
              "voxel_field '{}': a 2D mesh needs dims[2] = 1, got {}", file, dims[2]);
    std::ifstream in(file, std::ios::binary);
    CG_VERIFY(in.good(), "voxel_field: cannot open '{}'", file);
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                           std::istreambuf_iterator<char>());
    const std::size_t expected = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
    CG_VERIFY(bytes.size() == expected,
              "voxel_field: '{}' has {} bytes, expected {}x{}x{} = {} (one byte per voxel)", file,
              bytes.size(), dims[0], dims[1], dims[2], expected);
    const Matrix box = mesh::bounding_box(mesh);
    const Matrix c = mesh::element_centroids(mesh);
    mesh.material_ids.resize(mesh.num_elements());
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        std::size_t v = 0;
        for (int d = mesh.dim() - 1; d >= 0; --d)
            v = v * static_cast<std::size_t>(dims[d]) +
                static_cast<std::size_t>(cell_index(c(e, d), box(0, d), box(1, d), dims[d]));
        mesh.material_ids[e] = bytes[v];
    }
}

}  // namespace coarsegrain::material
