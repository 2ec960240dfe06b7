#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

const std::string kData = COARSEGRAIN_TEST_DATA;

/// A small grid of `type` with distorted interior nodes, coordinates that need all 17
/// significant digits, an offset that makes relative precision matter, and material ids
/// 0, 1, 2, 7 in runs of varying length (so Gmsh 4.1 needs several element blocks).
mesh::Mesh test_mesh(ElementType type) {
    const int dim = mesh::element_dim(type);
    Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi = Eigen::VectorXd::Ones(dim);
    Eigen::VectorXi cells = Eigen::VectorXi::Constant(dim, 3);
    hi[0] = 2.0;
    mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    test::distort_interior(m, 0.2, 5);
    m.rest_positions = (m.rest_positions * (M_PI / 3.0)).array() + 1e3 / 7.0;
    const Index ids[] = {0, 1, 2, 7};
    for (Index e = 0; e < m.num_elements(); ++e) m.material_ids[e] = ids[(e / 3 + e % 2) % 4];
    return m;
}

/// Positions equal to 1e-15 relative (the writers print the shortest representation that
/// reads back to the same double, so they are in fact exact), same connectivity and ids.
void expect_same_mesh(const mesh::Mesh& a, const mesh::Mesh& b) {
    ASSERT_EQ(a.type, b.type);
    ASSERT_EQ(a.rest_positions.rows(), b.rest_positions.rows());
    ASSERT_EQ(a.rest_positions.cols(), b.rest_positions.cols());
    const double scale = a.rest_positions.cwiseAbs().maxCoeff();
    EXPECT_LE((a.rest_positions - b.rest_positions).cwiseAbs().maxCoeff(), 1e-15 * scale);
    EXPECT_EQ(a.elements, b.elements);
    EXPECT_EQ(a.material_ids, b.material_ids);
}

double total_measure(const mesh::Mesh& m) {
    double total = 0;
    for (Index e = 0; e < m.num_elements(); ++e) total += mesh::element_measure(m, e);
    return total;
}

/// Measure of the elements of each material id.
std::map<Index, double> measure_by_material(const mesh::Mesh& m) {
    std::map<Index, double> out;
    for (Index e = 0; e < m.num_elements(); ++e)
        out[m.material_ids[e]] += mesh::element_measure(m, e);
    return out;
}

enum class Format { Gmsh2, Gmsh4, TetGen, Medit, Vtu };

std::string format_name(Format f) {
    switch (f) {
        case Format::Gmsh2:
            return "gmsh22";
        case Format::Gmsh4:
            return "gmsh41";
        case Format::TetGen:
            return "tetgen";
        case Format::Medit:
            return "medit";
        case Format::Vtu:
            return "vtu";
    }
    return "?";
}

class RoundTrip : public ::testing::TestWithParam<std::tuple<Format, ElementType>> {};

TEST_P(RoundTrip, WriteThenReadGivesTheSameMesh) {
    const auto [format, type] = GetParam();
    const mesh::Mesh m = test_mesh(type);
    const std::string dir = test::temp_dir("io_round_trip");
    mesh::Mesh back;
    switch (format) {
        case Format::Gmsh2:
            io::write_gmsh(dir + "/m.msh", m, 2);
            back = io::read_gmsh(dir + "/m.msh");
            break;
        case Format::Gmsh4:
            io::write_gmsh(dir + "/m.msh", m, 4);
            back = io::read_mesh(dir + "/m.msh");
            break;
        case Format::TetGen:
            io::write_mesh(dir + "/m.node", m);
            back = io::read_mesh(dir + "/m.ele");
            break;
        case Format::Medit:
            io::write_mesh(dir + "/m.mesh", m);
            back = io::read_mesh(dir + "/m.mesh");
            break;
        case Format::Vtu:
            io::write_mesh(dir + "/m.vtu", m);
            back = io::read_mesh(dir + "/m.vtu");
            break;
    }
    expect_same_mesh(m, back);
}

std::string round_trip_name(const ::testing::TestParamInfo<std::tuple<Format, ElementType>>& i) {
    return format_name(std::get<0>(i.param)) + "_" + mesh::element_name(std::get<1>(i.param));
}

INSTANTIATE_TEST_SUITE_P(
    AllTypes, RoundTrip,
    ::testing::Combine(::testing::Values(Format::Gmsh2, Format::Gmsh4, Format::Medit, Format::Vtu),
                       ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                         ElementType::Hex8)),
    round_trip_name);
INSTANTIATE_TEST_SUITE_P(Simplices, RoundTrip,
                         ::testing::Combine(::testing::Values(Format::TetGen),
                                            ::testing::Values(ElementType::Tri3,
                                                              ElementType::Tet4)),
                         round_trip_name);

TEST(TetGenWriter, RejectsQuadsAndHexesAndLeavesNoFile) {
    const std::string dir = test::temp_dir("io_tetgen_quads");
    EXPECT_THROW(io::write_tetgen(dir + "/m", test_mesh(ElementType::Quad4)), Error);
    EXPECT_THROW(io::write_tetgen(dir + "/m", test_mesh(ElementType::Hex8)), Error);
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

// gmsh 4.8 output: two unit boxes side by side, physical volumes 7 (x < 1) and 3 (x > 1),
// 48 tets, 23 nodes, plus boundary triangles of physical surface 11 that must be skipped.
TEST(GmshReference, Gmsh41BoxesHaveTwoUnitVolumesWithTheirPhysicalTags) {
    const mesh::Mesh m = io::read_gmsh(kData + "/gmsh41_boxes_tet.msh");
    EXPECT_EQ(m.type, ElementType::Tet4);
    EXPECT_EQ(m.num_nodes(), 23);
    EXPECT_EQ(m.num_elements(), 48);
    // The volumes are exact sums of tets filling the boxes: round-off only (1e-12).
    const auto by_material = measure_by_material(m);
    ASSERT_EQ(by_material.size(), 2u);
    EXPECT_NEAR(by_material.at(7), 1.0, 1e-12);
    EXPECT_NEAR(by_material.at(3), 1.0, 1e-12);
    const Matrix centroids = mesh::element_centroids(m);
    for (Index e = 0; e < m.num_elements(); ++e)
        EXPECT_EQ(m.material_ids[e], centroids(e, 0) < 1.0 ? 7 : 3) << "element " << e;
}

// The same geometry saved as 2.2 by the same gmsh: the same mesh.
TEST(GmshReference, Gmsh22BoxesEqualTheGmsh41Ones) {
    expect_same_mesh(io::read_gmsh(kData + "/gmsh41_boxes_tet.msh"),
                     io::read_gmsh(kData + "/gmsh22_boxes_tet.msh"));
}

// Medit from gmsh holds the elementary entity (1, 2) as the reference, not the physical tag.
TEST(GmshReference, MeditBoxesMatchTheGmshMesh) {
    const mesh::Mesh gmsh = io::read_gmsh(kData + "/gmsh41_boxes_tet.msh");
    mesh::Mesh medit = io::read_medit(kData + "/medit_boxes_tet.mesh");
    EXPECT_EQ(medit.rest_positions, gmsh.rest_positions);
    EXPECT_EQ(medit.elements, gmsh.elements);
    for (Index e = 0; e < gmsh.num_elements(); ++e)
        EXPECT_EQ(medit.material_ids[e], gmsh.material_ids[e] == 7 ? 1 : 2);
}

// 2D quads with sparse node tags (18 is missing), a stray point node at (5, 5) used only by a
// point element, and boundary lines: 19 nodes remain, 12 quads, area 1 per material.
TEST(GmshReference, Gmsh41SquaresAre2DWithSparseTagsRemapped) {
    const mesh::Mesh m = io::read_gmsh(kData + "/gmsh41_squares_quad.msh");
    EXPECT_EQ(m.type, ElementType::Quad4);
    EXPECT_EQ(m.dim(), 2);
    EXPECT_EQ(m.num_nodes(), 19);
    EXPECT_EQ(m.num_elements(), 12);
    EXPECT_LE(m.rest_positions.maxCoeff(), 2.0);  // the stray point is gone
    const auto by_material = measure_by_material(m);
    ASSERT_EQ(by_material.size(), 2u);
    EXPECT_NEAR(by_material.at(5), 1.0, 1e-12);
    EXPECT_NEAR(by_material.at(6), 1.0, 1e-12);
}

TEST(GmshReference, Gmsh22SquaresWithSparseTagsEqualTheGmsh41Ones) {
    expect_same_mesh(io::read_gmsh(kData + "/gmsh41_squares_quad.msh"),
                     io::read_gmsh(kData + "/gmsh22_squares_quad.msh"));
}

TEST(GmshReference, Gmsh41TrianglesAndHexes) {
    const mesh::Mesh tri = io::read_gmsh(kData + "/gmsh41_squares_tri.msh");
    EXPECT_EQ(tri.type, ElementType::Tri3);
    EXPECT_EQ(tri.num_nodes(), 8);
    EXPECT_EQ(tri.num_elements(), 8);
    EXPECT_NEAR(total_measure(tri), 2.0, 1e-12);
    const mesh::Mesh hex = io::read_gmsh(kData + "/gmsh41_block_hex.msh");
    EXPECT_EQ(hex.type, ElementType::Hex8);
    EXPECT_EQ(hex.num_nodes(), 12);
    EXPECT_EQ(hex.num_elements(), 2);
    EXPECT_EQ(hex.material_ids, IndexVector::Constant(2, 2));
    EXPECT_NEAR(total_measure(hex), 2.0, 1e-12);
}

// Sections the reader does not need are skipped whatever they hold, before and after the mesh.
TEST(GmshReader, SkipsUnknownSections) {
    const std::string file = test::temp_dir("io_gmsh_sections") + "/s.msh";
    std::ofstream(file) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                           "$Comments\n$Nodes\nnot a node\n$EndComments\n"
                           "$PhysicalNames\n1\n3 7 \"soft\"\n$EndPhysicalNames\n"
                           "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                           "$Elements\n1\n1 4 2 7 1 1 2 3 4\n$EndElements\n"
                           "$Periodic\n1\n2 1 2\n$EndPeriodic\n"
                           "$NodeData\n1\n\"u\"\n$EndNodeData\n";
    const mesh::Mesh m = io::read_gmsh(file);
    EXPECT_EQ(m.num_elements(), 1);
    EXPECT_EQ(m.material_ids[0], 7);
    EXPECT_NEAR(total_measure(m), 1.0 / 6.0, 1e-16);
}

// tetgen -Q on the unit cube's corners: 1-based, no attributes, 6 positive tets.
TEST(TetGenReference, CubeFromTetGen) {
    const mesh::Mesh m = io::read_tetgen(kData + "/tetgen_cube.1");
    EXPECT_EQ(m.type, ElementType::Tet4);
    EXPECT_EQ(m.num_nodes(), 8);
    EXPECT_EQ(m.num_elements(), 6);
    EXPECT_EQ(m.material_ids, IndexVector::Zero(6));
    EXPECT_NEAR(total_measure(m), 1.0, 1e-14);
}

// Triangle's 2D format numbered from 0 with node attributes, markers, comments, blank lines.
TEST(TetGenReference, ZeroBasedTriangleFileWithAttributes) {
    const mesh::Mesh m = io::read_mesh(kData + "/triangle_square.node");
    EXPECT_EQ(m.type, ElementType::Tri3);
    EXPECT_EQ(m.dim(), 2);
    EXPECT_EQ(m.num_nodes(), 5);
    EXPECT_EQ(m.elements.row(0), (Eigen::RowVector3i(0, 1, 4)));
    EXPECT_EQ(m.material_ids, (IndexVector(4) << 1, 1, 2, 2).finished());
    EXPECT_NEAR(total_measure(m), 1.0, 1e-15);
}

TEST(MeditReference, SkipsEdgesCornersRidgesAndBoundaryQuads) {
    const mesh::Mesh m = io::read_medit(kData + "/medit_two_cubes.mesh");
    EXPECT_EQ(m.type, ElementType::Hex8);
    EXPECT_EQ(m.num_nodes(), 12);
    EXPECT_EQ(m.material_ids, (IndexVector(2) << 4, 9).finished());
    EXPECT_NEAR(total_measure(m), 2.0, 1e-14);
}

// Gmsh itself (installed by scripts/setup.sh) reads what we write.
// Gmsh regroups elements by entity, so compare what survives any reordering: the element count
// and the volume of each material (sums of the same element volumes: round-off, 1e-12).
TEST(GmshWriter, GmshReadsOurFilesWhenInstalled) {
    const std::string dir = test::temp_dir("io_gmsh_check");
    for (int version : {2, 4}) {
        const std::string in = dir + "/in" + std::to_string(version) + ".msh";
        const std::string out = dir + "/out" + std::to_string(version) + ".msh";
        const mesh::Mesh m = test_mesh(ElementType::Tet4);
        io::write_gmsh(in, m, version);
        std::string log;
        ASSERT_EQ(test::run("gmsh -0 -format msh41 -save_all -o " + out + " " + in, &log), 0)
            << log;
        const mesh::Mesh back = io::read_gmsh(out);
        EXPECT_EQ(back.num_elements(), m.num_elements());
        const auto expected = measure_by_material(m), found = measure_by_material(back);
        ASSERT_EQ(found.size(), expected.size());
        for (const auto& [id, volume] : expected)
            EXPECT_NEAR(found.at(id), volume, 1e-12 * volume) << "material " << id;
    }
}

}  // namespace
