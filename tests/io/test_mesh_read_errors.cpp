// Every reader turns bad input into MeshReadError "FILE:LINE: ..." naming the offending line.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

struct BadInput {
    const char* name;
    const char* file;  ///< written in a temporary folder; its extension picks the reader
    std::string content;
    const char* reported;       ///< the file the message must name (for TetGen, .node or .ele)
    int line;                   ///< the line the message must name
    const char* what;           ///< a part of the message
    const char* ele = nullptr;  ///< TetGen: content of t.ele (none if null)
};

void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name; }

// clang-format off
const std::string kNodes22 =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"            // lines 1-3
    "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";  // lines 4-10
const std::string kTet22 = "$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n";  // lines 11-14

const std::string kMesh41 =
    "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"            // 1-3
    "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 5 0\n$EndEntities\n"  // 4-7: volume 1, physical 5
    "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"           // 8-14
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n";           // 15-19
const std::string kMedit =
    "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n"  // 1-4
    "0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";              // 5-8
const std::string kNode = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";  // 1-5

const char kBinary[] = "$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n";

const BadInput kCases[] = {
    {"GmshEmpty", "m.msh", "", "m.msh", 1, "empty"},
    {"GmshBinary", "m.msh", std::string(kBinary, sizeof kBinary - 1),
     "m.msh", 2, "binary Gmsh files are not supported; save as ASCII"},
    {"GmshVersion40", "m.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n", "m.msh", 2,
     "version '4' is not supported"},
    {"GmshTruncatedNodes", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n"
     "1 0 0 0\n2 1 0 0\n3 0 1 0\n", "m.msh", 8, "unexpected end of file: expected node 4 of 4"},
    {"GmshFewerNodesThanCount", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n"
     "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 10,
     "expected node 5 of 5, found '$EndNodes'"},
    {"GmshMoreNodesThanCount", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n"
     "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 9,
     "expected $EndNodes after 3 nodes"},
    {"GmshNodeOutOfRange", "m.msh", kNodes22 + "$Elements\n1\n1 4 2 1 1 1 2 3 9\n$EndElements\n",
     "m.msh", 13, "refers to node 9"},
    {"GmshNaN", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 nan 0 0\n"
     "3 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 7, "finite"},
    {"GmshInf", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n"
     "3 0 -inf 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 8, "finite"},
    {"GmshHugeCoordinate", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n"
     "2 1e999 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 7, "out of the double range"},
    {"GmshUnknownElementType", "m.msh", kNodes22 + "$Elements\n1\n1 99 2 1 1 1 2 3 4\n"
     "$EndElements\n", "m.msh", 13, "unknown Gmsh element type 99"},
    {"GmshUnparseableNumber", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n"
     "2 1.0.0 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 7,
     "expected a coordinate (a number), found '1.0.0'"},
    {"GmshNegativeCount", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n-4\n", "m.msh",
     5, "a count >= 0"},
    {"GmshAbsurdCount", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
     "1000000000000000000\n1 0 0 0\n", "m.msh", 5, "more than coarsegrain supports"},
    {"GmshLargeCountInSmallFile", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
     "2000000000\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n", "m.msh", 10,
     "expected node 5 of 2000000000"},
    {"GmshOverflowingCount", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
     "99999999999999999999999\n", "m.msh", 5, "out of the 64-bit integer range"},
    {"GmshMissingElements", "m.msh", kNodes22, "m.msh", 10, "without an $Elements section"},
    {"GmshMissingNodes", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" + kTet22, "m.msh", 7,
     "without a $Nodes section"},
    {"GmshMissingEndSection", "m.msh", kNodes22 + "$PhysicalNames\n1\n3 1 \"a\"\n", "m.msh", 11,
     "section $PhysicalNames has no $EndPhysicalNames"},
    {"GmshMixedTrianglesAndQuads", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n"
     "1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 2 0 0\n$EndNodes\n$Elements\n2\n1 3 2 1 1 1 2 3 4\n"
     "2 2 2 1 1 2 5 3\n$EndElements\n", "m.msh", 15,
     "mixes triangles (first on line 15) and quads (first on line 14)"},
    {"GmshPrism", "m.msh", kNodes22 + "$Elements\n2\n1 4 2 1 1 1 2 3 4\n"
     "2 6 2 1 1 1 2 3 4 1 2\n$EndElements\n", "m.msh", 14,
     "6-node prism elements are not supported"},
    {"GmshSecondOrderTet", "m.msh", kNodes22 + "$Elements\n1\n1 11 0 1 2 3 4 1 2 3 4 1 2\n"
     "$EndElements\n", "m.msh", 13, "10-node tetrahedron elements are not supported"},
    {"GmshInvertedTet", "m.msh", kNodes22 + "$Elements\n1\n1 4 2 1 1 1 3 2 4\n$EndElements\n",
     "m.msh", 13, "is inverted"},
    {"GmshDegenerateTet", "m.msh", kNodes22 + "$Elements\n1\n1 4 2 1 1 1 2 3 3\n$EndElements\n",
     "m.msh", 13, "is degenerate"},
    {"GmshTrianglesNotInPlaneZ0", "m.msh", kNodes22 + "$Elements\n1\n1 2 2 1 1 1 2 4\n"
     "$EndElements\n", "m.msh", 9, "node 4 has z = 1, but a mesh of triangles must lie in the "
     "plane z = 0"},
    {"GmshDuplicateNodeTag", "m.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n"
     "2 1 0 0\n2 0 1 0\n4 0 0 1\n$EndNodes\n" + kTet22, "m.msh", 8,
     "node 2 is defined twice (first on line 7)"},
    {"GmshElementFieldCount", "m.msh", kNodes22 + "$Elements\n1\n1 4 2 1 1 1 2 3\n$EndElements\n",
     "m.msh", 13, "expected an element line"},
    {"GmshGarbageAfterSections", "m.msh", kNodes22 + "hello\n", "m.msh", 11,
     "expected a section header such as $Nodes or $Elements, found 'hello'"},
    {"Gmsh41MissingEntity", "m.msh", kMesh41 + "$Elements\n1 1 1 1\n3 2 4 1\n1 1 2 3 4\n"
     "$EndElements\n", "m.msh", 22, "entity 2 of dimension 3 is not listed in $Entities"},
    {"Gmsh41NodeBlockCount", "m.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5 1 5\n"
     "3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n", "m.msh", 14,
     "the node blocks hold 4 nodes, but the header announced 5"},
    {"Gmsh41TruncatedElements", "m.msh", kMesh41 + "$Elements\n1 2 1 2\n3 1 4 2\n1 1 2 3 4\n",
     "m.msh", 23, "unexpected end of file: expected element 2 of 2"},
    {"Gmsh41ParametricCoordinatesMissing", "m.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
     "$Nodes\n1 1 1 1\n2 1 1 1\n1\n0 0 0\n$EndNodes\n", "m.msh", 8,
     "expected node coordinates 'x y z' and parametric coordinates (5 fields)"},

    {"TetGenMissingEle", "t.node", kNode, "t.node", 1, "no element file"},
    {"TetGenEmptyNode", "t.node", "# nothing\n\n", "t.node", 1, "empty", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenTruncatedNode", "t.node", "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "t.node", 5,
     "unexpected end of file: expected node 5 of 5", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenFirstNumber", "t.node", "4 3 0 0\n2 0 0 0\n", "t.node", 2,
     "expected the first node number to be 0 or 1", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenNumberGap", "t.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n4 0 1 0\n", "t.node", 4,
     "expected node number 3", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenNaN", "t.node", "4 3 0 0\n1 0 0 0\nnan\n", "t.node", 3,
     "expected a node line 'number x y z [attributes] [marker]' (4 fields)",
     "1 4 0\n1 1 2 3 4\n"},
    {"TetGenNaNCoordinate", "t.node", "4 3 0 0\n1 0 0 0\n2 NaN 0 0\n", "t.node", 3, "finite",
     "1 4 0\n1 1 2 3 4\n"},
    {"TetGenExtraNodes", "t.node", kNode + "5 1 1 1\n", "t.node", 6,
     "expected the end of the file after 4 nodes", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenNegativeCount", "t.node", kNode, "t.ele", 1, "a count >= 0", "-1 4 0\n"},
    {"TetGenAbsurdCount", "t.node", "3000000000 3 0 0\n", "t.node", 1,
     "more than coarsegrain supports", "1 4 0\n1 1 2 3 4\n"},
    {"TetGenSecondOrder", "t.node", kNode, "t.ele", 1, "second-order elements (10 nodes)",
     "1 10 0\n1 1 2 3 4 1 2 3 4 1 2\n"},
    {"TetGenNodeOutOfRange", "t.node", kNode, "t.ele", 3, "refers to node 5",
     "# the element attribute is the material\n1 4 1\n1 1 2 3 5 7\n"},
    {"TetGenFractionalAttribute", "t.node", kNode, "t.ele", 2,
     "expected an integer region attribute (the material id), found '1.5'",
     "1 4 1\n1 1 2 3 4 1.5\n"},
    {"TetGenTruncatedEle", "t.node", kNode, "t.ele", 2,
     "unexpected end of file: expected element 2 of 2", "2 4 0\n1 1 2 3 4\n"},
    {"TetGenEmptyEle", "t.node", kNode, "t.ele", 1, "empty", ""},

    {"MeditEmpty", "m.mesh", "\n  \n", "m.mesh", 1, "empty"},
    {"MeditNoVersion", "m.mesh", "Dimension 3\n", "m.mesh", 1,
     "expected MeshVersionFormatted at the start, found 'Dimension'"},
    {"MeditVerticesBeforeDimension", "m.mesh", "MeshVersionFormatted 2\nVertices\n0\n", "m.mesh",
     2, "Vertices before Dimension"},
    {"MeditFewerElementsThanCount", "m.mesh", kMedit + "Tetrahedra\n2\n1 2 3 4 5\nEnd\n", "m.mesh",
     12, "expected entry 2 of 2 of Tetrahedra, found 'End': the section holds fewer entries"},
    {"MeditTruncated", "m.mesh", kMedit + "Tetrahedra\n2\n1 2 3 4 5\n", "m.mesh", 11,
     "unexpected end of file: expected Tetrahedra"},
    {"MeditIndexZero", "m.mesh", kMedit + "Tetrahedra\n1\n0 2 3 4 5\nEnd\n", "m.mesh", 11,
     "refers to node 0"},
    {"MeditNaN", "m.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n"
     "1 nan 0 0\n", "m.mesh", 6, "finite"},
    {"MeditAbsurdCount", "m.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n"
     "99999999999\n0 0 0 0\n", "m.mesh", 4, "more than coarsegrain supports"},
    {"MeditLargeCountInSmallFile", "m.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n"
     "2000000000\n0 0 0 0\n", "m.mesh", 5, "unexpected end of file: expected Vertices"},
    {"MeditGarbage", "m.mesh", kMedit + "@@ 3\n", "m.mesh", 9,
     "expected a keyword such as Vertices or Tetrahedra, found '@@'"},
    {"MeditNoVertices", "m.mesh", "MeshVersionFormatted 2\nDimension 3\nEnd\n", "m.mesh", 3,
     "no Vertices section"},
    {"MeditNoElements", "m.mesh", kMedit + "Edges\n1\n1 2 0\nEnd\n", "m.mesh", 12,
     "no triangles, quads, tetrahedra or hexahedra"},
    {"MeditUnparseable", "m.mesh", kMedit + "Tetrahedra\n1\n1 2 x 4 5\nEnd\n", "m.mesh", 11,
     "expected a vertex number (an integer), found 'x'"},
    {"MeditInverted", "m.mesh", kMedit + "Tetrahedra\n1\n1 3 2 4 5\nEnd\n", "m.mesh", 11,
     "is inverted"},
};
// clang-format on

class BadMeshInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadMeshInput, ThrowsMeshReadErrorNamingFileAndLine) {
    const BadInput& c = GetParam();
    const std::string dir = test::temp_dir(std::string("io_bad_") + c.name);
    std::ofstream(dir + "/" + c.file, std::ios::binary) << c.content;
    if (c.ele) std::ofstream(dir + "/t.ele", std::ios::binary) << c.ele;
    const std::string where = dir + "/" + c.reported + ":" + std::to_string(c.line) + ": ";
    try {
        io::read_mesh(dir + "/" + c.file);
        FAIL() << "no exception";
    } catch (const MeshReadError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(where), std::string::npos) << message << "\nexpected " << where;
        EXPECT_NE(message.find(c.what), std::string::npos) << message << "\nexpected " << c.what;
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, BadMeshInput, ::testing::ValuesIn(kCases),
                         [](const auto& param) { return std::string(param.param.name); });

TEST(ReadMesh, UnknownExtensionAndMissingFileNameTheFile) {
    const std::string dir = test::temp_dir("io_bad_extension");
    for (const std::string& file : {dir + "/a.stl", dir + "/missing.msh", dir}) {
        try {
            io::read_mesh(file);
            FAIL() << "no exception for " << file;
        } catch (const MeshReadError& e) {
            EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
        }
    }
}

}  // namespace
