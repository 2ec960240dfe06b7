#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

mesh::Mesh small_grid(ElementType type) {
    const int dim = mesh::element_dim(type);
    mesh::Mesh m = mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                                   Eigen::VectorXi::Constant(dim, 2));
    for (Index e = 0; e < m.num_elements(); ++e) m.material_ids[e] = e % 3 - 1;  // -1, 0, 1
    return m;
}

/// Fields with values that need every bit of a double (Float64 in binary is exact).
io::VtuFields some_fields(const mesh::Mesh& m) {
    io::VtuFields f;
    const Index n = m.num_nodes(), ne = m.num_elements();
    Vector u(m.dim() * n);
    for (Index i = 0; i < u.size(); ++i) u[i] = std::sin(1.0 + i) / 3.0;
    f.add_point_vector("displacement", u, m.dim());
    f.add_point_scalar("temperature", Vector::LinSpaced(n, -1.0 / 7.0, 1e300));
    f.add_cell_scalar("energy", Vector::LinSpaced(ne, 1e-300, 2.0 / 3.0));
    f.add_cell("stress", Matrix::Random(ne, mandel_size(m.dim())));
    return f;
}

void expect_same_fields(const std::vector<io::Field>& a, const std::vector<io::Field>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].name, b[i].name);
        EXPECT_EQ(a[i].values, b[i].values) << a[i].name;  // binary Float64: exact
    }
}

class VtuRoundTrip : public ::testing::TestWithParam<ElementType> {};

// Write, read back: the mesh, its material ids and every field come back bit for bit.
TEST_P(VtuRoundTrip, MeshAndFieldsComeBackExactly) {
    const mesh::Mesh m = small_grid(GetParam());
    const io::VtuFields fields = some_fields(m);
    const std::string file = test::temp_dir("io_vtu_round_trip") + "/out.vtu";
    io::write_vtu(file, m, fields);
    const auto [back, back_fields] = io::read_vtu(file);
    EXPECT_EQ(back.type, m.type);
    EXPECT_EQ(back.rest_positions, m.rest_positions);
    EXPECT_EQ(back.elements, m.elements);
    EXPECT_EQ(back.material_ids, m.material_ids);
    expect_same_fields(back_fields.point_data, fields.point_data);
    expect_same_fields(back_fields.cell_data, fields.cell_data);
    // A 2D vector field is written with 3 components, z = 0 (for ParaView's Warp By Vector).
    EXPECT_EQ(back_fields.point_data[0].values.cols(), 3);
    if (m.dim() == 2) {
        EXPECT_EQ(back_fields.point_data[0].values.col(2).cwiseAbs().maxCoeff(), 0.0);
    }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, VtuRoundTrip,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param) { return mesh::element_name(param.param); });

// An independent XML parser (Python's minidom) accepts the file and sees the arrays we expect.
TEST(Vtu, WrittenXmlParsesWithPython) {
    const mesh::Mesh m = small_grid(ElementType::Tet4);
    io::VtuFields fields = some_fields(m);
    fields.add_point_scalar("a \"quoted\" <name> & more", Vector::Zero(m.num_nodes()));
    const std::string dir = test::temp_dir("io_vtu_xml");
    io::write_vtu(dir + "/out.vtu", m, fields);
    io::write_pvd(dir + "/series.pvd", {{0.0, "out.vtu"}, {0.5, "a&b.vtu"}});
    std::string out;
    ASSERT_EQ(test::run("python3 -c \"import xml.dom.minidom as d; "
                        "v = d.parse('" +
                            dir +
                            "/out.vtu'); "
                            "print(sorted(a.getAttribute('Name') for a in "
                            "v.getElementsByTagName('DataArray'))); "
                            "p = d.parse('" +
                            dir +
                            "/series.pvd'); "
                            "print([(s.getAttribute('timestep'), s.getAttribute('file')) for s in "
                            "p.getElementsByTagName('DataSet')])\"",
                        &out),
              0)
        << out;
    EXPECT_NE(out.find("'a \"quoted\" <name> & more'"), std::string::npos) << out;
    for (const char* name :
         {"'connectivity'", "'offsets'", "'types'", "'material_id'", "'displacement'", "'stress'"})
        EXPECT_NE(out.find(name), std::string::npos) << name << " in " << out;
    EXPECT_NE(out.find("[('0', 'out.vtu'), ('0.5', 'a&b.vtu')]"), std::string::npos) << out;
}

TEST(Vtu, UnwritableFolderIsNamedAndLeavesNoFile) {
    const std::string dir = test::temp_dir("io_vtu_unwritable");
    const mesh::Mesh m = small_grid(ElementType::Tri3);
    std::ofstream(dir + "/plain_file") << "not a folder";
    for (const std::string& folder : {dir + "/missing", dir + "/plain_file"}) {
        try {
            io::write_vtu(folder + "/out.vtu", m, {});
            FAIL() << "no exception for " << folder;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(folder), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(io::write_pvd(dir + "/missing/s.pvd", {{0.0, "a.vtu"}}), Error);
    // Only the plain file is there: no temporary or partial file was left.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                            std::filesystem::directory_iterator()),
              1);
}

TEST(Vtu, BadFieldsAreRejectedBeforeAnythingIsWritten) {
    const std::string dir = test::temp_dir("io_vtu_bad_fields");
    const mesh::Mesh m = small_grid(ElementType::Quad4);
    io::VtuFields wrong_rows;
    wrong_rows.add_point_scalar("p", Vector::Zero(m.num_nodes() + 1));
    io::VtuFields reserved;
    reserved.add_cell_scalar("material_id", Vector::Zero(m.num_elements()));
    io::VtuFields duplicate;
    duplicate.add_cell_scalar("c", Vector::Zero(m.num_elements()));
    duplicate.add_cell_scalar("c", Vector::Zero(m.num_elements()));
    for (const io::VtuFields* f : {&wrong_rows, &reserved, &duplicate})
        EXPECT_THROW(io::write_vtu(dir + "/out.vtu", m, *f), Error);
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

// A file as ParaView writes it in ASCII: Float32 points, Int64 connectivity and offsets, a
// 2-component cell field, an XML comment; two quads in z = 0 make a 2D mesh.
TEST(Vtu, ReadsAsciiFilesWithOtherTypes) {
    const std::string file = test::temp_dir("io_vtu_ascii") + "/a.vtu";
    std::ofstream(file) << R"(<?xml version="1.0"?>
<!-- written by hand -->
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="6" NumberOfCells="2">
      <PointData Scalars="t">
        <DataArray type="Float32" Name="t" format="ascii">0 1 2 3 4 5</DataArray>
      </PointData>
      <CellData>
        <DataArray type="Int32" Name="material_id" format="ascii">4 9</DataArray>
        <DataArray type="Float64" Name="g" NumberOfComponents="2" format="ascii">
          0.5 1.5
          2.5 3.5
        </DataArray>
      </CellData>
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">
          0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0
        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 4 3 1 2 5 4</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4 8</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">9 9</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
)";
    const auto [m, fields] = io::read_vtu(file);
    EXPECT_EQ(m.type, ElementType::Quad4);
    EXPECT_EQ(m.rest_positions.cols(), 2);
    EXPECT_EQ(m.material_ids, (IndexVector(2) << 4, 9).finished());
    EXPECT_EQ(m.elements.row(1), (Eigen::RowVector4i(1, 2, 5, 4)));
    ASSERT_EQ(fields.cell_data.size(), 1u);  // material_id went into the mesh
    EXPECT_EQ(fields.cell_data[0].values, (Matrix(2, 2) << 0.5, 1.5, 2.5, 3.5).finished());
    EXPECT_EQ(fields.point_data[0].values(5, 0), 5.0);
}

// Appended raw binary data (ParaView's default without compression), UInt32 headers.
TEST(Vtu, ReadsAppendedRawData) {
    std::string data;
    const auto block = [&data](const void* p, std::uint32_t bytes) {
        const std::size_t offset = data.size();
        data.append(reinterpret_cast<const char*>(&bytes), 4);
        data.append(static_cast<const char*>(p), bytes);
        return offset;
    };
    const double points[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const std::int32_t connectivity[] = {0, 1, 2, 3}, offsets[] = {4};
    const std::uint8_t types[] = {10};
    const std::size_t p = block(points, sizeof points), c = block(connectivity, 16),
                      o = block(offsets, 4), t = block(types, 1);
    const std::string file = test::temp_dir("io_vtu_appended") + "/a.vtu";
    std::ofstream(file, std::ios::binary)
        << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
           "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
        << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" "
           "offset=\""
        << p << "\"/></Points>\n<Cells>"
        << "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"" << c
        << "\"/><DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\"" << o
        << "\"/><DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" << t
        << "\"/></Cells>\n</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_" << data
        << "\n</AppendedData>\n</VTKFile>\n";
    const mesh::Mesh m = io::read_vtu(file).first;
    EXPECT_EQ(m.type, ElementType::Tet4);
    EXPECT_EQ(m.rest_positions, (Matrix(4, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished());
    EXPECT_EQ(m.material_ids, IndexVector::Zero(1));
}

struct BadVtu {
    const char* name;
    std::string content;
    int line;
    const char* what;
};

void PrintTo(const BadVtu& c, std::ostream* os) { *os << c.name; }

std::string tet_vtu(const std::string& points, const std::string& cells,
                    const std::string& root = "type=\"UnstructuredGrid\"") {
    return "<VTKFile " + root +
           ">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" "
           "NumberOfCells=\"1\">\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" "
           "format=\"ascii\">" +
           points + "</DataArray>\n</Points>\n<Cells>\n" + cells +
           "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

const std::string kPoints = "0 0 0 1 0 0 0 1 0 0 0 1";
const std::string kCells =
    "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>\n"
    "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
    "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray>\n";  // lines 8-10

const BadVtu kBadVtu[] = {
    {"Empty", "", 1, "no XML element found"},
    {"Unclosed", "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n", 3,
     "<UnstructuredGrid> (line 2) is not closed"},
    {"MismatchedTag", "<VTKFile>\n<A>\n</B>\n", 3, "expected </A> (opened on line 2), found </B>"},
    {"NotUnstructuredGrid", tet_vtu(kPoints, kCells, "type=\"PolyData\""), 1,
     "expected <VTKFile type=\"UnstructuredGrid\">"},
    {"Compressed",
     tet_vtu(kPoints, kCells, "type=\"UnstructuredGrid\" compressor=\"vtkZLibDataCompressor\""), 1,
     "compressed VTU files"},
    {"TooFewPoints", tet_vtu("0 0 0 1 0 0 0 1 0", kCells), 5, "holds 9 values, expected 12"},
    {"BadNumber", tet_vtu("0 0 0 1 0 0 0 1 0 0 0 x", kCells), 5, "expected a number, found 'x'"},
    {"NaNPoint", tet_vtu("0 0 0 1 0 0 0 1 0 0 0 nan", kCells), 5, "non-finite"},
    {"WedgeCell",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">"
             "0 1 2 3</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" "
             "format=\"ascii\">4</DataArray>\n<DataArray type=\"UInt8\" "
             "Name=\"types\" format=\"ascii\">13</DataArray>\n"),
     10, "VTK cell type 13"},
    {"BadOffsets",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">"
             "0 1 2 3</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" "
             "format=\"ascii\">3</DataArray>\n<DataArray type=\"UInt8\" "
             "Name=\"types\" format=\"ascii\">10</DataArray>\n"),
     9, "offset of cell 0 is 3, expected 4"},
    {"PointOutOfRange",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" "
             "format=\"ascii\">0 1 2 4</DataArray>\n<DataArray "
             "type=\"Int32\" Name=\"offsets\" format=\"ascii\">4"
             "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" "
             "format=\"ascii\">10</DataArray>\n"),
     8, "cell 0 refers to point 4"},
    {"Inverted",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" "
             "format=\"ascii\">0 2 1 3</DataArray>\n<DataArray "
             "type=\"Int32\" Name=\"offsets\" format=\"ascii\">4"
             "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" "
             "format=\"ascii\">10</DataArray>\n"),
     8, "is inverted"},
    {"BadBase64",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" "
             "format=\"binary\">!!!!</DataArray>\n<DataArray "
             "type=\"Int32\" Name=\"offsets\" format=\"ascii\">4"
             "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" "
             "format=\"ascii\">10</DataArray>\n"),
     8, "invalid or truncated base64"},
    {"WrongBlockSize",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" "
             "format=\"binary\">AAEAAA==</DataArray>\n<DataArray "
             "type=\"Int32\" Name=\"offsets\" format=\"ascii\">4"
             "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" "
             "format=\"ascii\">10</DataArray>\n"),
     8, "the block header declares 256 bytes, but the array needs 16"},
    {"MissingTypes",
     tet_vtu(kPoints,
             "<DataArray type=\"Int32\" Name=\"connectivity\" "
             "format=\"ascii\">0 1 2 3</DataArray>\n"),
     7, "<Cells> has no DataArray named types"},
};

class BadVtuInput : public ::testing::TestWithParam<BadVtu> {};

TEST_P(BadVtuInput, ThrowsMeshReadErrorNamingFileAndLine) {
    const BadVtu& c = GetParam();
    const std::string file = test::temp_dir(std::string("io_vtu_bad_") + c.name) + "/b.vtu";
    std::ofstream(file) << c.content;
    const std::string where = file + ":" + std::to_string(c.line) + ": ";
    try {
        io::read_vtu(file);
        FAIL() << "no exception";
    } catch (const MeshReadError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(where), std::string::npos) << message << "\nexpected " << where;
        EXPECT_NE(message.find(c.what), std::string::npos) << message << "\nexpected " << c.what;
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, BadVtuInput, ::testing::ValuesIn(kBadVtu),
                         [](const auto& param) { return std::string(param.param.name); });

}  // namespace
