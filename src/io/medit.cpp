// Medit .mesh, ASCII (the keyword format of libMeshb: https://github.com/LoicMarechal/libMeshb).
#include <algorithm>
#include <cctype>
#include <optional>

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

bool iequals(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) ==
                      std::tolower(static_cast<unsigned char>(y));
           });
}

/// Keywords start with a letter; "nan" and "inf" are (bad) numbers, not keywords.
bool is_keyword(std::string_view token) {
    if (token.empty() || !std::isalpha(static_cast<unsigned char>(token[0]))) return false;
    return !iequals(token, "nan") && !iequals(token, "inf") && !iequals(token, "infinity");
}

/// Section keywords of the Medit format (libMeshb's list, the ones seen in practice): inside a
/// section, one of these means the section ended early; any other word is a bad number.
bool is_section_keyword(std::string_view token) {
    // clang-format off
    static const char* const kKeywords[] = {
        "MeshVersionFormatted", "Dimension", "Vertices", "Edges", "Triangles", "Quadrilaterals",
        "Tetrahedra", "Prisms", "Hexahedra", "Pyramids", "Corners", "Ridges", "RequiredVertices",
        "RequiredEdges", "RequiredTriangles", "RequiredQuadrilaterals", "Normals", "Tangents",
        "NormalAtVertices", "NormalAtTriangleVertices", "TangentAtEdges", "TangentAtVertices",
        "Identifier", "Geometry", "End"};
    // clang-format on
    return std::any_of(std::begin(kKeywords), std::end(kKeywords),
                       [&](const char* k) { return iequals(token, k); });
}

const char* medit_keyword(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return "Triangles";
        case ElementType::Quad4:
            return "Quadrilaterals";
        case ElementType::Tet4:
            return "Tetrahedra";
        case ElementType::Hex8:
            return "Hexahedra";
    }
    return "?";
}

class MeditReader {
  public:
    explicit MeditReader(const std::string& file) : m_in(file, '#') {}

    mesh::Mesh read() {
        if (m_in.empty())
            m_in.fail_at(1,
                         "the file is empty; expected a Medit mesh starting with "
                         "MeshVersionFormatted");
        const std::string_view first = m_in.require_token("MeshVersionFormatted");
        if (!iequals(first, "MeshVersionFormatted"))
            m_in.fail("expected MeshVersionFormatted at the start, found {}", quoted(first));
        const std::int64_t version = m_in.integer(m_in.require_token("the version"), "the version");
        if (version < 1 || version > 4)
            m_in.fail("expected MeshVersionFormatted 1 to 4, found {}", version);
        m_raw.tag_base = 1;
        bool ended = false;
        std::string_view keyword;
        while (!ended && next_keyword(keyword)) {
            if (iequals(keyword, "Dimension")) {
                if (m_dim != 0) m_in.fail("a second Dimension keyword");
                const std::int64_t dim =
                    m_in.integer(m_in.require_token("the dimension"), "the dimension");
                if (dim != 2 && dim != 3) m_in.fail("expected Dimension 2 or 3, found {}", dim);
                m_dim = static_cast<int>(dim);
            } else if (iequals(keyword, "Vertices")) {
                read_vertices();
            } else if (iequals(keyword, "Triangles")) {
                read_elements(ElementType::Tri3);
            } else if (iequals(keyword, "Quadrilaterals")) {
                read_elements(ElementType::Quad4);
            } else if (iequals(keyword, "Tetrahedra")) {
                read_elements(ElementType::Tet4);
            } else if (iequals(keyword, "Hexahedra")) {
                read_elements(ElementType::Hex8);
            } else if (iequals(keyword, "End")) {
                ended = true;
            } else if (iequals(keyword, "MeshVersionFormatted")) {
                m_in.fail("a second MeshVersionFormatted keyword");
            } else {
                skip_numbers();  // Edges, Corners, Ridges, Normals, ...: not needed
            }
        }
        const int end = m_in.line();
        if (!m_have_vertices) m_in.fail_at(end, "the file has no Vertices section");
        return detail::build_mesh(m_raw, m_in, end);
    }

  private:
    bool next_keyword(std::string_view& keyword) {
        if (m_pending) {
            keyword = *m_pending;
            m_pending.reset();
            return true;
        }
        if (!m_in.next_token(keyword)) return false;
        if (!is_keyword(keyword))
            m_in.fail(
                "expected a keyword such as Vertices or Tetrahedra, found {} (does a "
                "section hold more entries than its count announces?)",
                quoted(keyword));
        return true;
    }

    void skip_numbers() {
        std::string_view token;
        while (m_in.next_token(token))
            if (is_keyword(token)) {
                m_pending = token;
                return;
            }
    }

    /// The next number of a section; a keyword there means the section is shorter than its
    /// count (a truncated or miscounted file).
    std::string_view entry_token(const char* section, Index i, Index n) {
        const std::string_view token = m_in.require_token(section);
        if (is_section_keyword(token))
            m_in.fail(
                "expected entry {} of {} of {}, found {}: the section holds fewer entries "
                "than announced",
                i + 1, n, section, quoted(token));
        return token;
    }

    void read_vertices() {
        if (m_dim == 0) m_in.fail("Vertices before Dimension; the dimension must come first");
        if (m_have_vertices) m_in.fail("a second Vertices section");
        m_have_vertices = true;
        const Index n =
            m_in.count(m_in.require_token("the number of vertices"), "the number of vertices");
        const std::size_t hint = detail::reserve_hint(n, m_in.bytes_left(), 8);
        m_raw.xyz.reserve(3 * hint);
        m_raw.node_line.reserve(hint);
        for (Index i = 0; i < n; ++i) {
            double x[3] = {0, 0, 0};
            for (int d = 0; d < m_dim; ++d)
                x[d] = m_in.real(entry_token("Vertices", i, n), "a coordinate");
            const int line = m_in.line();
            m_in.integer(entry_token("Vertices", i, n), "a vertex reference");
            m_raw.add_node(x[0], x[1], x[2], line);
        }
    }

    void read_elements(ElementType type) {
        const char* section = medit_keyword(type);
        const Index n =
            m_in.count(m_in.require_token("the number of elements"), "the number of elements");
        const int npe = mesh::nodes_per_element(type);
        std::int64_t nodes[8];
        for (Index e = 0; e < n; ++e) {
            int line = 0;
            for (int a = 0; a < npe; ++a) {
                nodes[a] = m_in.integer(entry_token(section, e, n), "a vertex number");
                if (a == 0) line = m_in.line();
            }
            const Index ref = m_in.int32(entry_token(section, e, n), "an element reference");
            m_raw.add_element(type, nodes, ref, line);
        }
    }

    detail::TextReader m_in;
    detail::RawMesh m_raw;
    int m_dim = 0;
    bool m_have_vertices = false;
    std::optional<std::string_view> m_pending;  ///< a keyword found while skipping a section
};

}  // namespace

mesh::Mesh read_medit(const std::string& file) { return MeditReader(file).read(); }

void write_medit(const std::string& file, const mesh::Mesh& mesh) {
    detail::check_writable(mesh, file);
    write_atomically(file, [&](std::ostream& out) {
        detail::BufferedWriter w(out);
        const int dim = mesh.dim();
        w.print("MeshVersionFormatted 2\n\nDimension {}\n\nVertices\n{}\n", dim, mesh.num_nodes());
        for (Index v = 0; v < mesh.num_nodes(); ++v) {
            for (int d = 0; d < dim; ++d) w.print("{} ", mesh.rest_positions(v, d));
            w.print("0\n");
        }
        w.print("\n{}\n{}\n", medit_keyword(mesh.type), mesh.num_elements());
        for (Index e = 0; e < mesh.num_elements(); ++e) {
            for (Index a = 0; a < mesh.elements.cols(); ++a)
                w.print("{} ", mesh.elements(e, a) + 1);
            w.print("{}\n", mesh.material_ids[e]);
        }
        w.print("\nEnd\n");
        w.flush();
    });
}

}  // namespace coarsegrain::io
