// Gmsh .msh ASCII 2.2 and 4.1 (https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format).
#include <algorithm>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "raw_mesh.hpp"
#include "text_reader.hpp"
#include "write_util.hpp"

namespace coarsegrain::io {

namespace {

using detail::quoted;
using mesh::ElementType;

/// A Gmsh element type: its dimension, node count and name, and the coarsegrain type if read.
struct GmshType {
    int dim;
    int nodes;
    const char* name;
    std::optional<ElementType> type;
};

/// The Gmsh element types (numbers 1-31, 92, 93), or nullptr for an unknown number.
const GmshType* gmsh_type(std::int64_t number) {
    static const std::map<std::int64_t, GmshType> kTypes = {
        {1, {1, 2, "2-node line", std::nullopt}},
        {2, {2, 3, "3-node triangle", ElementType::Tri3}},
        {3, {2, 4, "4-node quadrangle", ElementType::Quad4}},
        {4, {3, 4, "4-node tetrahedron", ElementType::Tet4}},
        {5, {3, 8, "8-node hexahedron", ElementType::Hex8}},
        {6, {3, 6, "6-node prism", std::nullopt}},
        {7, {3, 5, "5-node pyramid", std::nullopt}},
        {8, {1, 3, "3-node line", std::nullopt}},
        {9, {2, 6, "6-node triangle", std::nullopt}},
        {10, {2, 9, "9-node quadrangle", std::nullopt}},
        {11, {3, 10, "10-node tetrahedron", std::nullopt}},
        {12, {3, 27, "27-node hexahedron", std::nullopt}},
        {13, {3, 18, "18-node prism", std::nullopt}},
        {14, {3, 14, "14-node pyramid", std::nullopt}},
        {15, {0, 1, "point", std::nullopt}},
        {16, {2, 8, "8-node quadrangle", std::nullopt}},
        {17, {3, 20, "20-node hexahedron", std::nullopt}},
        {18, {3, 15, "15-node prism", std::nullopt}},
        {19, {3, 13, "13-node pyramid", std::nullopt}},
        {20, {2, 9, "9-node triangle", std::nullopt}},
        {21, {2, 10, "10-node triangle", std::nullopt}},
        {22, {2, 12, "12-node triangle", std::nullopt}},
        {23, {2, 15, "15-node triangle", std::nullopt}},
        {24, {2, 15, "15-node incomplete triangle", std::nullopt}},
        {25, {2, 21, "21-node triangle", std::nullopt}},
        {26, {1, 4, "4-node line", std::nullopt}},
        {27, {1, 5, "5-node line", std::nullopt}},
        {28, {1, 6, "6-node line", std::nullopt}},
        {29, {3, 20, "20-node tetrahedron", std::nullopt}},
        {30, {3, 35, "35-node tetrahedron", std::nullopt}},
        {31, {3, 56, "56-node tetrahedron", std::nullopt}},
        {92, {3, 64, "64-node hexahedron", std::nullopt}},
        {93, {3, 125, "125-node hexahedron", std::nullopt}},
    };
    const auto it = kTypes.find(number);
    return it == kTypes.end() ? nullptr : &it->second;
}

int gmsh_number(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return 2;
        case ElementType::Quad4:
            return 3;
        case ElementType::Tet4:
            return 4;
        case ElementType::Hex8:
            return 5;
    }
    return 0;
}

class GmshReader {
  public:
    explicit GmshReader(const std::string& file) : m_in(file, '\0') {}

    mesh::Mesh read() {
        if (m_in.empty())
            m_in.fail_at(1, "the file is empty; expected a Gmsh mesh starting with $MeshFormat");
        m_in.require_line("$MeshFormat");
        if (m_in.field(0) != "$MeshFormat")
            m_in.fail("expected $MeshFormat on the first line, found {}", quoted(m_in.line_text()));
        read_format();
        while (m_in.next_line()) {
            const std::string_view name = m_in.field(0);
            if (name.size() < 2 || name[0] != '$' || m_in.num_fields() != 1)
                m_in.fail("expected a section header such as $Nodes or $Elements, found {}",
                          quoted(m_in.line_text()));
            if (name == "$Nodes") {
                if (m_have_nodes) m_in.fail("a second $Nodes section; a mesh has one");
                m_have_nodes = true;
                m_version == 2 ? read_nodes_v2() : read_nodes_v4();
            } else if (name == "$Elements") {
                if (m_have_elements) m_in.fail("a second $Elements section; a mesh has one");
                m_have_elements = true;
                m_version == 2 ? read_elements_v2() : read_elements_v4();
            } else if (name == "$Entities" && m_version == 4) {
                if (m_have_entities) m_in.fail("a second $Entities section; a mesh has one");
                if (m_have_elements) m_in.fail("$Entities must come before $Elements");
                m_have_entities = true;
                read_entities_v4();
            } else if (name == "$MeshFormat") {
                m_in.fail("a second $MeshFormat section");
            } else if (name.starts_with("$End")) {
                m_in.fail("found {} without its opening section", quoted(name));
            } else {
                skip_section(name);
            }
        }
        const int end = m_in.line();
        if (!m_have_nodes)
            m_in.fail_at(end,
                         "end of file without a $Nodes section (a mesh needs $Nodes and "
                         "$Elements)");
        if (!m_have_elements)
            m_in.fail_at(end,
                         "end of file without an $Elements section (a mesh needs $Nodes "
                         "and $Elements)");
        return detail::build_mesh(m_raw, m_in, end);
    }

  private:
    /// The Gmsh element type `number` on the current line; an unknown number is a read error.
    const GmshType* known_type(std::int64_t number) {
        const GmshType* type = gmsh_type(number);
        if (!type)
            m_in.fail(
                "unknown Gmsh element type {} (coarsegrain reads 2 triangle, 3 quad, "
                "4 tetrahedron, 5 hexahedron)",
                number);
        return type;
    }

    void read_format() {
        m_in.require_line("the format line 'version file-type data-size'");
        if (m_in.num_fields() >= 2 && m_in.field(1) == "1")
            m_in.fail("binary Gmsh files are not supported; save as ASCII");
        m_in.expect_fields(3, "the format line 'version file-type data-size'");
        const std::string_view version = m_in.field(0);
        const double v = m_in.real(version, "the format version");
        if (v >= 2.0 && v < 3.0)
            m_version = 2;
        else if (version == "4.1")
            m_version = 4;
        else
            m_in.fail(
                "Gmsh format version {} is not supported; save the mesh as version 4.1 or "
                "2.2 (ASCII)",
                quoted(version));
        if (m_in.field(1) != "0")
            m_in.fail("expected file-type 0 (ASCII), found {}", quoted(m_in.field(1)));
        expect_end("$EndMeshFormat", "the format line");
    }

    /// Moves to the next record line of a section; a '$' line there means the section holds
    /// fewer records than its count announced.
    void record(const char* kind, std::int64_t i, std::int64_t n) {
        if (!m_in.next_line())
            m_in.fail("unexpected end of file: expected {} {} of {} (is the file truncated?)", kind,
                      i + 1, n);
        if (m_in.field(0).starts_with('$'))
            m_in.fail("expected {} {} of {}, found {}: the section holds fewer than announced",
                      kind, i + 1, n, quoted(m_in.line_text()));
    }

    void need_fields(std::size_t n, const char* what) const {
        if (m_in.num_fields() < n)
            m_in.fail("expected {} (at least {} fields), found {}", what, n,
                      quoted(m_in.line_text()));
    }

    void expect_end(const std::string& end, const std::string& after) {
        m_in.require_line(end);
        if (m_in.field(0) != end || m_in.num_fields() != 1)
            m_in.fail(
                "expected {} after {}, found {} (does the section hold more than its "
                "count announces?)",
                end, after, quoted(m_in.line_text()));
    }

    void skip_section(std::string_view name) {
        const std::string end = "$End" + std::string(name.substr(1));
        const int start = m_in.line();
        while (m_in.next_line())
            if (m_in.field(0) == end) return;
        m_in.fail_at(start, fmt::format("section {} has no {} (is the file truncated?)",
                                        std::string(name), end));
    }

    double coordinate(std::size_t i) const { return m_in.real(m_in.field(i), "a coordinate"); }

    void read_nodes_v2() {
        m_in.require_line("the number of nodes");
        m_in.expect_fields(1, "the number of nodes");
        const Index n = m_in.count(m_in.field(0), "the number of nodes");
        const std::size_t hint = detail::reserve_hint(n, m_in.bytes_left(), 8);
        m_raw.xyz.reserve(3 * hint);
        m_raw.tags.reserve(hint);
        for (Index i = 0; i < n; ++i) {
            record("node", i, n);
            m_in.expect_fields(4, "a node line 'number x y z'");
            m_raw.tags.push_back(m_in.integer(m_in.field(0), "a node number"));
            m_raw.add_node(coordinate(1), coordinate(2), coordinate(3), m_in.line());
        }
        expect_end("$EndNodes", fmt::format("{} nodes", n));
    }

    void read_elements_v2() {
        m_in.require_line("the number of elements");
        m_in.expect_fields(1, "the number of elements");
        const Index n = m_in.count(m_in.field(0), "the number of elements");
        std::vector<std::int64_t> nodes;
        for (Index i = 0; i < n; ++i) {
            record("element", i, n);
            need_fields(3, "an element line 'number type #tags tags... nodes...'");
            m_in.integer(m_in.field(0), "an element number");
            const std::int64_t number = m_in.integer(m_in.field(1), "an element type");
            const GmshType* type = known_type(number);
            const Index num_tags = m_in.count(m_in.field(2), "the number of tags");
            m_in.expect_fields(3 + static_cast<std::size_t>(num_tags) + type->nodes,
                               "an element line 'number type #tags tags... nodes...'");
            if (!type->type) {
                m_raw.add_other(type->dim, m_in.line(), type->name);
                continue;
            }
            const Index material = num_tags > 0 ? m_in.int32(m_in.field(3), "a physical tag") : 0;
            nodes.clear();
            for (int a = 0; a < type->nodes; ++a)
                nodes.push_back(m_in.integer(m_in.field(3 + num_tags + a), "a node number"));
            m_raw.add_element(*type->type, nodes.data(), material, m_in.line());
        }
        expect_end("$EndElements", fmt::format("{} elements", n));
    }

    void read_entities_v4() {
        const char* header = "the entity counts 'numPoints numCurves numSurfaces numVolumes'";
        m_in.require_line(header);
        m_in.expect_fields(4, header);
        Index counts[4];
        for (int d = 0; d < 4; ++d) counts[d] = m_in.count(m_in.field(d), "an entity count");
        for (int d = 0; d < 4; ++d) {
            for (Index i = 0; i < counts[d]; ++i) {
                record("entity", i, counts[d]);
                const std::int64_t tag = m_in.integer(m_in.field(0), "an entity tag");
                // Points: tag x y z #phys phys...; others: tag box(6) #phys phys... #bnd bnd...
                const std::size_t phys_at = d == 0 ? 4 : 7;
                need_fields(phys_at + 1, d == 0 ? "a point entity 'tag x y z numPhysicalTags...'"
                                                : "an entity 'tag minX minY minZ maxX maxY maxZ "
                                                  "numPhysicalTags...'");
                const Index num_phys = m_in.count(m_in.field(phys_at), "a physical tag count");
                std::size_t fields = phys_at + 1 + static_cast<std::size_t>(num_phys);
                if (d > 0) {
                    need_fields(fields + 1, "an entity with its bounding entity count");
                    fields += 1 + static_cast<std::size_t>(
                                      m_in.count(m_in.field(fields), "a bounding entity count"));
                }
                m_in.expect_fields(fields, "an entity line");
                const Index physical =
                    num_phys > 0 ? m_in.int32(m_in.field(phys_at + 1), "a physical tag") : 0;
                if (!m_physical.emplace(std::make_pair(d, tag), physical).second)
                    m_in.fail("entity {} of dimension {} is listed twice", tag, d);
            }
        }
        expect_end("$EndEntities", "the entities");
    }

    /// Reads an entity block header 'entityDim entityTag x count' (x: parametric or type).
    void block_header(const char* what, int& dim, std::int64_t& tag, std::int64_t& x,
                      Index& count) {
        m_in.expect_fields(4, what);
        const std::int64_t d = m_in.integer(m_in.field(0), "an entity dimension");
        if (d < 0 || d > 3) m_in.fail("expected an entity dimension 0..3, found {}", d);
        dim = static_cast<int>(d);
        tag = m_in.integer(m_in.field(1), "an entity tag");
        x = m_in.integer(m_in.field(2), what);
        count = m_in.count(m_in.field(3), "the number of entries in the block");
    }

    void read_nodes_v4() {
        const char* header = "the node header 'numEntityBlocks numNodes minNodeTag maxNodeTag'";
        m_in.require_line(header);
        m_in.expect_fields(4, header);
        const Index num_blocks = m_in.count(m_in.field(0), "the number of node blocks");
        const Index n = m_in.count(m_in.field(1), "the number of nodes");
        const std::size_t hint = detail::reserve_hint(n, m_in.bytes_left(), 8);
        m_raw.xyz.reserve(3 * hint);
        m_raw.tags.reserve(hint);
        Index read = 0;
        for (Index b = 0; b < num_blocks; ++b) {
            record("node block", b, num_blocks);
            int dim = 0;
            std::int64_t tag = 0, parametric = 0;
            Index count = 0;
            block_header("a node block header 'entityDim entityTag parametric numNodesInBlock'",
                         dim, tag, parametric, count);
            if (parametric != 0 && parametric != 1)
                m_in.fail("expected parametric 0 or 1, found {}", parametric);
            if (count > n - read)
                m_in.fail("the block holds {} nodes, but only {} of the {} announced remain", count,
                          n - read, n);
            for (Index j = 0; j < count; ++j) {
                record("node number", read + j, n);
                m_in.expect_fields(1, "a node number");
                m_raw.tags.push_back(m_in.integer(m_in.field(0), "a node number"));
            }
            const std::size_t fields = 3 + (parametric ? dim : 0);
            for (Index j = 0; j < count; ++j) {
                record("node coordinate line", read + j, n);
                m_in.expect_fields(fields, parametric ? "node coordinates 'x y z' and parametric "
                                                        "coordinates"
                                                      : "node coordinates 'x y z'");
                m_raw.add_node(coordinate(0), coordinate(1), coordinate(2), m_in.line());
            }
            read += count;
        }
        if (read != n)
            m_in.fail("the node blocks hold {} nodes, but the header announced {}", read, n);
        expect_end("$EndNodes", fmt::format("{} nodes", n));
    }

    void read_elements_v4() {
        const char* header =
            "the element header 'numEntityBlocks numElements minElementTag maxElementTag'";
        m_in.require_line(header);
        m_in.expect_fields(4, header);
        const Index num_blocks = m_in.count(m_in.field(0), "the number of element blocks");
        const Index n = m_in.count(m_in.field(1), "the number of elements");
        Index read = 0;
        std::vector<std::int64_t> nodes;
        for (Index b = 0; b < num_blocks; ++b) {
            record("element block", b, num_blocks);
            int dim = 0;
            std::int64_t tag = 0, number = 0;
            Index count = 0;
            block_header(
                "an element block header 'entityDim entityTag elementType "
                "numElementsInBlock'",
                dim, tag, number, count);
            const GmshType* type = known_type(number);
            if (count > n - read)
                m_in.fail("the block holds {} elements, but only {} of the {} announced remain",
                          count, n - read, n);
            Index material = 0;
            if (type->type && m_have_entities) {
                const auto it = m_physical.find({dim, tag});
                if (it == m_physical.end())
                    m_in.fail("the block's entity {} of dimension {} is not listed in $Entities",
                              tag, dim);
                material = it->second;
            }
            for (Index j = 0; j < count; ++j) {
                record("element", read + j, n);
                m_in.expect_fields(1 + static_cast<std::size_t>(type->nodes),
                                   "an element line 'number nodes...'");
                if (!type->type) {
                    if (j == 0) m_raw.add_other(type->dim, m_in.line(), type->name);
                    continue;
                }
                m_in.integer(m_in.field(0), "an element number");
                nodes.clear();
                for (int a = 0; a < type->nodes; ++a)
                    nodes.push_back(m_in.integer(m_in.field(1 + a), "a node number"));
                m_raw.add_element(*type->type, nodes.data(), material, m_in.line());
            }
            read += count;
        }
        if (read != n)
            m_in.fail("the element blocks hold {} elements, but the header announced {}", read, n);
        expect_end("$EndElements", fmt::format("{} elements", n));
    }

    detail::TextReader m_in;
    detail::RawMesh m_raw;
    int m_version = 0;
    bool m_have_nodes = false;
    bool m_have_elements = false;
    bool m_have_entities = false;
    std::map<std::pair<int, std::int64_t>, Index> m_physical;  ///< (dim, tag) -> first physical
};

/// Distinct material ids, sorted; entity k + 1 of the written file holds material ids[k].
std::vector<Index> distinct_materials(const mesh::Mesh& mesh) {
    std::vector<Index> ids(mesh.material_ids.begin(), mesh.material_ids.end());
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
}

Index entity_of(const std::vector<Index>& ids, Index material) {
    return static_cast<Index>(std::lower_bound(ids.begin(), ids.end(), material) - ids.begin()) + 1;
}

void write_nodes_and_coordinates(detail::BufferedWriter& w, const mesh::Mesh& mesh, bool tags) {
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
        const double z = mesh.dim() == 3 ? mesh.rest_positions(v, 2) : 0.0;
        if (tags)
            w.print("{} {} {} {}\n", v + 1, mesh.rest_positions(v, 0), mesh.rest_positions(v, 1),
                    z);
        else
            w.print("{} {} {}\n", mesh.rest_positions(v, 0), mesh.rest_positions(v, 1), z);
    }
}

void write_element_nodes(detail::BufferedWriter& w, const mesh::Mesh& mesh, Index e) {
    for (Index a = 0; a < mesh.elements.cols(); ++a) w.print(" {}", mesh.elements(e, a) + 1);
    w.print("\n");
}

void write_gmsh2(std::ostream& out, const mesh::Mesh& mesh) {
    detail::BufferedWriter w(out);
    const std::vector<Index> ids = distinct_materials(mesh);
    w.print("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{}\n", mesh.num_nodes());
    write_nodes_and_coordinates(w, mesh, true);
    w.print("$EndNodes\n$Elements\n{}\n", mesh.num_elements());
    const int type = gmsh_number(mesh.type);
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        // Tags: physical group (the material id), then elementary entity.
        w.print("{} {} 2 {} {}", e + 1, type, mesh.material_ids[e],
                entity_of(ids, mesh.material_ids[e]));
        write_element_nodes(w, mesh, e);
    }
    w.print("$EndElements\n");
    w.flush();
}

void write_gmsh4(std::ostream& out, const mesh::Mesh& mesh) {
    detail::BufferedWriter w(out);
    const std::vector<Index> ids = distinct_materials(mesh);
    const int dim = mesh.dim();
    const auto k = ids.size();
    w.print("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 {} {}\n", dim == 2 ? k : 0,
            dim == 3 ? k : 0);
    // One entity per material: its bounding box, the material id as its physical tag (none for
    // material 0, which reads back as 0) and no bounding entities.
    Matrix lo = Matrix::Constant(static_cast<Index>(k), 3, std::numeric_limits<double>::max());
    Matrix hi = Matrix::Constant(static_cast<Index>(k), 3, std::numeric_limits<double>::lowest());
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        const Index ent = entity_of(ids, mesh.material_ids[e]) - 1;
        for (Index a = 0; a < mesh.elements.cols(); ++a)
            for (int d = 0; d < 3; ++d) {
                const double x = d < dim ? mesh.rest_positions(mesh.elements(e, a), d) : 0.0;
                lo(ent, d) = std::min(lo(ent, d), x);
                hi(ent, d) = std::max(hi(ent, d), x);
            }
    }
    for (std::size_t i = 0; i < k; ++i) {
        const auto r = static_cast<Index>(i);
        w.print("{} {} {} {} {} {} {} ", i + 1, lo(r, 0), lo(r, 1), lo(r, 2), hi(r, 0), hi(r, 1),
                hi(r, 2));
        if (ids[i] != 0)
            w.print("1 {} 0\n", ids[i]);
        else
            w.print("0 0\n");
    }
    w.print("$EndEntities\n$Nodes\n1 {0} 1 {0}\n{1} 1 0 {0}\n", mesh.num_nodes(), dim);
    for (Index v = 0; v < mesh.num_nodes(); ++v) w.print("{}\n", v + 1);
    write_nodes_and_coordinates(w, mesh, false);
    // Elements in their order: one block per run of equal material ids.
    std::vector<std::pair<Index, Index>> runs;  // (first element, length)
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        if (e == 0 || mesh.material_ids[e] != mesh.material_ids[e - 1]) runs.emplace_back(e, 0);
        ++runs.back().second;
    }
    w.print("$EndNodes\n$Elements\n{} {} 1 {}\n", runs.size(), mesh.num_elements(),
            mesh.num_elements());
    const int type = gmsh_number(mesh.type);
    for (const auto& [first, length] : runs) {
        w.print("{} {} {} {}\n", dim, entity_of(ids, mesh.material_ids[first]), type, length);
        for (Index e = first; e < first + length; ++e) {
            w.print("{}", e + 1);
            write_element_nodes(w, mesh, e);
        }
    }
    w.print("$EndElements\n");
    w.flush();
}

}  // namespace

mesh::Mesh read_gmsh(const std::string& file) { return GmshReader(file).read(); }

void write_gmsh(const std::string& file, const mesh::Mesh& mesh, int version) {
    CG_VERIFY(version == 2 || version == 4,
              "cannot write {}: Gmsh version must be 2 (format 2.2) or 4 (format 4.1), got {}",
              file, version);
    detail::check_writable(mesh, file);
    write_atomically(file, [&](std::ostream& out) {
        version == 2 ? write_gmsh2(out, mesh) : write_gmsh4(out, mesh);
    });
}

}  // namespace coarsegrain::io
