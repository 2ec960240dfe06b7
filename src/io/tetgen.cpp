// TetGen .node/.ele (https://wias-berlin.de/software/tetgen/fformats.html) and Triangle's 2D
// variant (https://www.cs.cmu.edu/~quake/triangle.node.html).
#include <cmath>
#include <filesystem>
#include <limits>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "raw_mesh.hpp"
#include "text_reader.hpp"
#include "write_util.hpp"

namespace coarsegrain::io {

namespace {

using detail::quoted;
using detail::TextReader;
using mesh::ElementType;

std::string strip_extension(const std::string& path) {
    for (const char* ext : {".node", ".ele"}) {
        const std::string e(ext);
        if (path.size() > e.size() && path.ends_with(e))
            return path.substr(0, path.size() - e.size());
    }
    return path;
}

/// Reads a record number: the first sets the base (0 or 1), the others must follow it.
std::int64_t record_number(const TextReader& in, Index i, std::int64_t base, const char* kind) {
    const std::int64_t number = in.integer(in.field(0), kind);
    if (i == 0) {
        if (number != 0 && number != 1)
            in.fail("expected the first {} to be 0 or 1 (it sets the numbering base), found {}",
                    kind, number);
    } else if (number != base + i) {
        in.fail("expected {} {} (records are numbered consecutively), found {}", kind, base + i,
                number);
    }
    return number;
}

void expect_end_of_file(TextReader& in, Index n, const char* kind) {
    if (in.next_line())
        in.fail(
            "expected the end of the file after {} {}, found {} (does the file hold more than "
            "its header announces?)",
            n, kind, quoted(in.line_text()));
}

}  // namespace

mesh::Mesh read_tetgen(const std::string& base_in) {
    const std::string base = strip_extension(base_in);
    const std::string node_file = base + ".node", ele_file = base + ".ele";
    TextReader nodes(node_file, '#');
    if (nodes.empty())
        nodes.fail_at(1,
                      "the file is empty; expected the header '#nodes dimension #attributes "
                      "#boundary-markers'");
    std::error_code ec;
    if (!std::filesystem::exists(ele_file, ec))
        nodes.fail_at(1, fmt::format("there is no element file {} beside this node file (a "
                                     "TetGen mesh is base.node plus base.ele)",
                                     ele_file));

    const char* header = "the header '#nodes dimension #attributes #boundary-markers'";
    nodes.require_line(header);
    if (nodes.num_fields() > 4) nodes.expect_fields(4, header);
    const Index n = nodes.count(nodes.field(0), "the number of nodes");
    const std::int64_t dim =
        nodes.num_fields() > 1 ? nodes.integer(nodes.field(1), "the dimension") : 3;
    if (dim != 2 && dim != 3) nodes.fail("expected dimension 2 or 3, found {}", dim);
    const Index num_attributes =
        nodes.num_fields() > 2 ? nodes.count(nodes.field(2), "the number of attributes") : 0;
    const Index num_markers =
        nodes.num_fields() > 3 ? nodes.count(nodes.field(3), "the number of boundary markers") : 0;
    if (num_markers > 1) nodes.fail("expected 0 or 1 boundary markers, found {}", num_markers);
    if (n == 0)
        nodes.fail(
            "the file has no nodes (TetGen writes 0 when the nodes are in a .poly or "
            ".smesh file, which coarsegrain does not read)");

    detail::RawMesh raw;
    const std::size_t hint = detail::reserve_hint(n, nodes.bytes_left(), 6);
    raw.xyz.reserve(3 * hint);
    raw.node_line.reserve(hint);
    const std::size_t fields = 1 + static_cast<std::size_t>(dim) +
                               static_cast<std::size_t>(num_attributes) +
                               static_cast<std::size_t>(num_markers);
    const char* node_line = dim == 3 ? "a node line 'number x y z [attributes] [marker]'"
                                     : "a node line 'number x y [attributes] [marker]'";
    for (Index i = 0; i < n; ++i) {
        if (!nodes.next_line())
            nodes.fail("unexpected end of file: expected node {} of {} (is the file truncated?)",
                       i + 1, n);
        nodes.expect_fields(fields, node_line);
        const std::int64_t number = record_number(nodes, i, raw.tag_base, "node number");
        if (i == 0) raw.tag_base = number;
        double x[3] = {0, 0, 0};
        for (int d = 0; d < dim; ++d) x[d] = nodes.real(nodes.field(1 + d), "a coordinate");
        raw.add_node(x[0], x[1], x[2], nodes.line());
    }
    expect_end_of_file(nodes, n, "nodes");

    TextReader elements(ele_file, '#');
    if (elements.empty())
        elements.fail_at(1,
                         "the file is empty; expected the header '#elements "
                         "nodes-per-element #attributes'");
    const char* ele_header = "the header '#elements nodes-per-element #attributes'";
    elements.require_line(ele_header);
    if (elements.num_fields() < 2 || elements.num_fields() > 3)
        elements.expect_fields(3, ele_header);
    const Index m = elements.count(elements.field(0), "the number of elements");
    const std::int64_t npe = elements.integer(elements.field(1), "the number of nodes per element");
    const Index num_element_attributes =
        elements.num_fields() > 2 ? elements.count(elements.field(2), "the number of attributes")
                                  : 0;
    const int expected_npe = dim == 3 ? 4 : 3;
    if (npe == 2 * expected_npe + (dim == 3 ? 2 : 0))
        elements.fail(
            "second-order elements ({} nodes) are not supported; mesh with linear "
            "elements",
            npe);
    if (npe != expected_npe)
        elements.fail("expected {} nodes per element for the {}D nodes of {}, found {}",
                      expected_npe, dim, node_file, npe);
    if (m == 0) elements.fail("the file has no elements");
    const ElementType type = dim == 3 ? ElementType::Tet4 : ElementType::Tri3;
    const std::size_t ele_fields =
        1 + static_cast<std::size_t>(npe) + static_cast<std::size_t>(num_element_attributes);
    std::int64_t element_base = 0;
    std::int64_t corners[4];
    for (Index e = 0; e < m; ++e) {
        if (!elements.next_line())
            elements.fail(
                "unexpected end of file: expected element {} of {} (is the file "
                "truncated?)",
                e + 1, m);
        elements.expect_fields(ele_fields, "an element line 'number nodes... [attributes]'");
        const std::int64_t number = record_number(elements, e, element_base, "element number");
        if (e == 0) element_base = number;
        for (int a = 0; a < npe; ++a)
            corners[a] = elements.integer(elements.field(1 + a), "a node number");
        Index material = 0;
        if (num_element_attributes > 0) {
            const double attribute = elements.real(elements.field(1 + npe), "a region attribute");
            if (attribute != std::floor(attribute) ||
                std::abs(attribute) > std::numeric_limits<Index>::max())
                elements.fail("expected an integer region attribute (the material id), found {}",
                              quoted(elements.field(1 + npe)));
            material = static_cast<Index>(attribute);
        }
        raw.add_element(type, corners, material, elements.line());
    }
    expect_end_of_file(elements, m, "elements");
    return detail::build_mesh(raw, elements, elements.line());
}

void write_tetgen(const std::string& base_in, const mesh::Mesh& mesh) {
    const std::string base = strip_extension(base_in);
    CG_VERIFY(mesh.type == ElementType::Tet4 || mesh.type == ElementType::Tri3,
              "cannot write {}.node/.ele: TetGen and Triangle files hold tetrahedra and "
              "triangles only, not {}; write .msh, .mesh or .vtu instead",
              base, mesh::element_name(mesh.type));
    detail::check_writable(mesh, base + ".node");
    const int dim = mesh.dim();
    write_atomically(base + ".node", [&](std::ostream& out) {
        detail::BufferedWriter w(out);
        w.print("# written by coarsegrain\n{} {} 0 0\n", mesh.num_nodes(), dim);
        for (Index v = 0; v < mesh.num_nodes(); ++v) {
            w.print("{}", v + 1);
            for (int d = 0; d < dim; ++d) w.print(" {}", mesh.rest_positions(v, d));
            w.print("\n");
        }
        w.flush();
    });
    write_atomically(base + ".ele", [&](std::ostream& out) {
        detail::BufferedWriter w(out);
        w.print("# written by coarsegrain; the attribute is the material id\n{} {} 1\n",
                mesh.num_elements(), mesh.elements.cols());
        for (Index e = 0; e < mesh.num_elements(); ++e) {
            w.print("{}", e + 1);
            for (Index a = 0; a < mesh.elements.cols(); ++a)
                w.print(" {}", mesh.elements(e, a) + 1);
            w.print(" {}\n", mesh.material_ids[e]);
        }
        w.flush();
    });
}

}  // namespace coarsegrain::io
