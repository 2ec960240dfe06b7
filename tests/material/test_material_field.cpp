#include <gtest/gtest.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <fstream>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using test::expect_error;
using mesh::ElementType;

namespace {

mesh::Mesh grid2(ElementType type, int nx, int ny, double sx = 1.0, double sy = 1.0) {
    return mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(sx, sy),
                           Eigen::Vector2i(nx, ny));
}

mesh::Mesh grid3(int nx, int ny, int nz) {
    return mesh::make_grid(ElementType::Hex8, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1),
                           Eigen::Vector3i(nx, ny, nz));
}


/// Writes a w x h PNG with `channels` channels; pixel(row, col, channel) gives the bytes.
template <class F>
std::string write_png(const std::string& name, int w, int h, int channels, F&& pixel) {
    const std::string file = test::temp_dir("material_field_" + name) + "/" + name + ".png";
    std::vector<unsigned char> data(static_cast<std::size_t>(w * h * channels));
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
            for (int k = 0; k < channels; ++k)
                data[static_cast<std::size_t>((r * w + c) * channels + k)] = pixel(r, c, k);
    EXPECT_NE(stbi_write_png(file.c_str(), w, h, channels, data.data(), w * channels), 0);
    return file;
}

// Layers along x of thickness 0.25 from origin 0 with ids {1, 2}: cells alternate; an origin
// of -0.25 shifts the pattern by one layer (periodic in both directions).
TEST(Layers, AlternateAlongTheAxis) {
    mesh::Mesh m = grid2(ElementType::Quad4, 4, 2);
    material::layers(m, 0, 0.0, 0.25, {1, 2});
    EXPECT_EQ(m.material_ids, (IndexVector(8) << 1, 2, 1, 2, 1, 2, 1, 2).finished());
    material::layers(m, 1, -0.5, 0.5, {4, 5, 6});  // y layers: cell centres 0.25, 0.75
    EXPECT_EQ(m.material_ids, (IndexVector(8) << 5, 5, 5, 5, 6, 6, 6, 6).finished());
    EXPECT_THROW(material::layers(m, 2, 0, 1, {1}), Error);
    EXPECT_THROW(material::layers(m, 0, 0, 0, {1}), Error);
}

// A disc of radius 0.3 at the centre of a 4x4 grid on the unit square holds exactly the four
// central cells (centroids at distance 0.177); the rest keep their id.
TEST(Spheres, MarkElementsWithCentroidInside) {
    mesh::Mesh m = grid2(ElementType::Quad4, 4, 4);
    material::spheres(m, (Matrix(1, 2) << 0.5, 0.5).finished(), 0.3, 9);
    for (Index e = 0; e < m.num_elements(); ++e) {
        const int i = e % 4, j = e / 4;
        const bool centre = (i == 1 || i == 2) && (j == 1 || j == 2);
        EXPECT_EQ(m.material_ids[e], centre ? 9 : 0) << e;
    }
}

// Checkerboard of cubes of edge 0.5 on a 4^3 grid: id a where (i/2 + j/2 + k/2) is even.
TEST(Checkerboard, AlternatesInThreeDimensions) {
    mesh::Mesh m = grid3(4, 4, 4);
    material::checkerboard(m, Eigen::Vector3d::Zero(), 0.5, 1, 2);
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i)
                EXPECT_EQ(m.material_ids[i + 4 * (j + 4 * k)], (i / 2 + j / 2 + k / 2) % 2 ? 2 : 1);
}

// An image with the grid's resolution maps pixel to cell one to one, top image row = top grid
// row; E interpolates linearly between E_black (0) and E_white (255); only the intensities that
// occur get a material. Both triangles of a cell take the cell's pixel.
TEST(ImageField, PixelToCellOneToOne) {
    const int w = 4, h = 3;
    const auto value = [](int r, int c) { return static_cast<unsigned char>(20 * r + 50 * c); };
    const std::string file =
        write_png("gray", w, h, 1, [&](int r, int c, int) { return value(r, c); });
    material::ImageField opt;
    opt.file = file;
    opt.E_black = 1000;
    opt.E_white = 10;
    opt.nu = 0.25;
    for (const ElementType type : {ElementType::Quad4, ElementType::Tri3}) {
        mesh::Mesh m = grid2(type, w, h, 2.0, 1.5);
        const std::map<int, material::Material> by_id = material::image_field(m, opt);
        const int per_cell = type == ElementType::Tri3 ? 2 : 1;
        for (Index e = 0; e < m.num_elements(); ++e) {
            const int cell = e / per_cell, i = cell % w, j = cell / w;
            EXPECT_EQ(m.material_ids[e], value(h - 1 - j, i)) << "element " << e;
        }
        EXPECT_EQ(by_id.size(), 12u);  // 12 distinct intensities
        const material::Material& mat = by_id.at(value(0, 3));
        // E = 1000 + (10 - 1000) * 150 / 255, exact up to round-off (1e-12 relative).
        EXPECT_NEAR(mat.E, 1000 - 990 * 150 / 255.0, 1e-12 * 1000);
        EXPECT_EQ(mat.nu, 0.25);
        EXPECT_NO_THROW(material::assign(m, by_id));
    }
}

// An 8x6 RGB image on a 4x3 grid: each cell takes the pixel at its centre, (2i+1, 2j+1), and
// colour becomes Rec. 601 luminance round(0.299 R + 0.587 G + 0.114 B).
TEST(ImageField, ResampledRgbImageUsesLuminance) {
    const auto rgb = [](int r, int c, int k) {
        return static_cast<unsigned char>(k == 0 ? 30 * c : k == 1 ? 40 * r : 200);
    };
    const std::string file = write_png("rgb", 8, 6, 3, rgb);
    material::ImageField opt;
    opt.file = file;
    mesh::Mesh m = grid2(ElementType::Quad4, 4, 3);
    const auto by_id = material::image_field(m, opt);
    for (Index e = 0; e < m.num_elements(); ++e) {
        const int i = e % 4, j = e / 4;
        const int row = 6 - 1 - (2 * j + 1), col = 2 * i + 1;
        const int expected = static_cast<int>(std::lround(
            0.299 * rgb(row, col, 0) + 0.587 * rgb(row, col, 1) + 0.114 * rgb(row, col, 2)));
        EXPECT_EQ(m.material_ids[e], expected) << "element " << e;
        EXPECT_EQ(by_id.count(expected), 1u);
    }
}

TEST(ImageField, ErrorsNameTheFile) {
    mesh::Mesh m = grid2(ElementType::Quad4, 2, 2);
    material::ImageField opt;
    opt.file = "/nonexistent/tiling.png";
    expect_error([&] { material::image_field(m, opt); }, "cannot read '/nonexistent/tiling.png'");
    opt.file = test::temp_dir("material_field_corrupt") + "/corrupt.png";
    std::ofstream(opt.file) << "this is not a png";
    expect_error([&] { material::image_field(m, opt); }, "corrupt.png' as a PNG image");
    mesh::Mesh m3 = grid3(1, 1, 1);
    opt.file = write_png("one", 1, 1, 1, [](int, int, int) { return 0; });
    expect_error([&] { material::image_field(m3, opt); }, "needs a 2D mesh");
}

// Voxel labels written x fastest: on a grid with the voxel resolution each element gets its
// voxel; on a grid twice as fine each element gets the voxel containing its centroid.
TEST(VoxelField, RoundTripAndResampling) {
    const Eigen::Vector3i dims(3, 2, 2);
    std::vector<unsigned char> bytes;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 3; ++i)
                bytes.push_back(static_cast<unsigned char>(10 + i + 3 * j + 6 * k));
    const std::string file = test::temp_dir("voxel_field") + "/labels.raw";
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    mesh::Mesh m = grid3(3, 2, 2);
    material::voxel_field(m, file, dims);
    for (Index e = 0; e < m.num_elements(); ++e) EXPECT_EQ(m.material_ids[e], bytes[e]);
    mesh::Mesh fine = grid3(6, 4, 4);
    material::voxel_field(fine, file, dims);
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 6; ++i)
                EXPECT_EQ(fine.material_ids[i + 6 * (j + 4 * k)],
                          10 + i / 2 + 3 * (j / 2) + 6 * (k / 2));

    expect_error([&] { material::voxel_field(m, file, Eigen::Vector3i(2, 2, 2)); },
                 "has 12 bytes, expected 2x2x2 = 8");
    expect_error([&] { material::voxel_field(m, "/nonexistent/v.raw", dims); },
                 "cannot open '/nonexistent/v.raw'");
}

}  // namespace
