// VTK XML UnstructuredGrid (https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html).
#include "coarsegrain/io/vtu.hpp"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "raw_mesh.hpp"
#include "text_reader.hpp"
#include "write_util.hpp"
#include "xml.hpp"

namespace coarsegrain::io {

static_assert(std::endian::native == std::endian::little,
              "the VTU writer and reader assume a little-endian machine");

void VtuFields::add_point_vector(const std::string& name, const Vector& interleaved, int dim) {
    CG_VERIFY(dim == 2 || dim == 3, "point vector field {}: dim must be 2 or 3, got {}", name, dim);
    CG_VERIFY(interleaved.size() % dim == 0,
              "point vector field {}: {} values is not a multiple of dim = {}", name,
              interleaved.size(), dim);
    const Index n = static_cast<Index>(interleaved.size() / dim);
    Matrix values = Matrix::Zero(n, 3);
    for (Index i = 0; i < n; ++i)
        for (int d = 0; d < dim; ++d) values(i, d) = interleaved[dim * i + d];
    point_data.push_back({name, std::move(values)});
}

void VtuFields::add_point_scalar(const std::string& name, const Vector& values) {
    point_data.push_back({name, values});
}

void VtuFields::add_cell_scalar(const std::string& name, const Vector& values) {
    cell_data.push_back({name, values});
}

void VtuFields::add_cell(const std::string& name, const Matrix& values) {
    cell_data.push_back({name, values});
}

namespace {

using detail::quoted;
using detail::XmlDocument;
using detail::XmlElement;
using mesh::ElementType;

std::uint8_t vtk_cell_type(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return 5;
        case ElementType::Quad4:
            return 9;
        case ElementType::Tet4:
            return 10;
        case ElementType::Hex8:
            return 12;
    }
    return 0;
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Base64 of (UInt64 byte count, raw little-endian values): VTK's uncompressed binary block.
template <class T>
std::string binary_block(const std::vector<T>& values) {
    const std::uint64_t bytes = values.size() * sizeof(T);
    std::vector<std::uint8_t> block(sizeof(bytes) + bytes);
    std::memcpy(block.data(), &bytes, sizeof(bytes));
    if (bytes > 0) std::memcpy(block.data() + sizeof(bytes), values.data(), bytes);
    return detail::base64_encode(block.data(), block.size());
}

std::vector<double> row_major(const Matrix& m) {
    std::vector<double> out(static_cast<std::size_t>(m.size()));
    std::size_t k = 0;
    for (Index i = 0; i < m.rows(); ++i)
        for (Index j = 0; j < m.cols(); ++j) out[k++] = m(i, j);
    return out;
}

void write_array(std::ostream& out, const char* type, const std::string& name, Index components,
                 const std::string& data) {
    out << "        <DataArray type=\"" << type << "\"";
    if (!name.empty()) out << " Name=\"" << detail::xml_escape(name) << "\"";
    out << " NumberOfComponents=\"" << components << "\" format=\"binary\">\n          " << data
        << "\n        </DataArray>\n";
}

void check_fields(const std::vector<Field>& fields, Index rows, const char* kind,
                  const std::string& file) {
    std::set<std::string> names;
    for (const Field& f : fields) {
        CG_VERIFY(!f.name.empty(), "cannot write {}: a {} field has no name", file, kind);
        CG_VERIFY(names.insert(f.name).second, "cannot write {}: two {} fields are named {}", file,
                  kind, f.name);
        CG_VERIFY(f.values.rows() == rows && f.values.cols() >= 1,
                  "cannot write {}: {} field {} has {} by {} values, expected {} rows (one per "
                  "{}) and at least one column",
                  file, kind, f.name, f.values.rows(), f.values.cols(), rows,
                  std::string_view(kind) == "point" ? "node" : "element");
    }
}

// ---------------------------------------------------------------------------------------------
// Reading

class VtuReader {
  public:
    explicit VtuReader(const std::string& file) : m_file(file), m_doc(detail::parse_xml(file)) {}

    std::pair<mesh::Mesh, VtuFields> read() {
        const XmlElement& root = m_doc.elements[0];
        const std::string* type = root.attribute("type");
        if (root.name != "VTKFile" || !type || *type != "UnstructuredGrid")
            fail(root, fmt::format("expected <VTKFile type=\"UnstructuredGrid\">, found <{}{}>",
                                   root.name, type ? " type=\"" + *type + "\"" : ""));
        if (const std::string* order = root.attribute("byte_order");
            order && *order != "LittleEndian")
            fail(root, fmt::format("byte_order {} is not supported; save as LittleEndian",
                                   quoted(*order)));
        if (const std::string* c = root.attribute("compressor"); c && !c->empty())
            fail(root, fmt::format("compressed VTU files ({}) are not supported; save without "
                                   "compression",
                                   quoted(*c)));
        if (const std::string* h = root.attribute("header_type")) {
            if (*h == "UInt64")
                m_header_bytes = 8;
            else if (*h != "UInt32")
                fail(root,
                     fmt::format("expected header_type UInt32 or UInt64, found {}", quoted(*h)));
        }
        if (const auto appended = m_doc.children(root, "AppendedData"); !appended.empty()) {
            m_appended = appended.front();
            const std::string* encoding = m_appended->attribute("encoding");
            if (!encoding || (*encoding != "raw" && *encoding != "base64"))
                fail(*m_appended, "expected <AppendedData encoding=\"raw\"> or \"base64\"");
            m_appended_raw = *encoding == "raw";
        }
        const XmlElement& grid = only_child(root, "UnstructuredGrid");
        const auto pieces = m_doc.children(grid, "Piece");
        if (pieces.size() != 1)
            fail(grid, fmt::format("expected one <Piece>, found {} (multi-piece files are not "
                                   "supported)",
                                   pieces.size()));
        const XmlElement& piece = *pieces.front();
        const Index n = count_attribute(piece, "NumberOfPoints");
        const Index m = count_attribute(piece, "NumberOfCells");
        if (m == 0) fail(piece, "the file has no cells");

        const XmlElement& points_array = only_child(only_child(piece, "Points"), "DataArray");
        const std::vector<double> xyz = read_array(points_array, n, 3);
        const XmlElement& cells = only_child(piece, "Cells");
        const XmlElement& types_array = named_array(cells, "types");
        const XmlElement& offsets_array = named_array(cells, "offsets");
        const XmlElement& connectivity_array = named_array(cells, "connectivity");
        const std::vector<double> types = read_array(types_array, m, 1);
        const std::vector<double> offsets = read_array(offsets_array, m, 1);

        mesh::Mesh mesh;
        mesh.type = element_type(types_array, types[0], 0);
        for (Index c = 1; c < m; ++c)
            if (element_type(types_array, types[c], c) != mesh.type)
                fail(types_array, fmt::format("cell {} has VTK type {} but cell 0 has type {}; a "
                                              "mesh must have a single element type",
                                              c, types[c], types[0]));
        const int npe = mesh::nodes_per_element(mesh.type);
        for (Index c = 0; c < m; ++c)
            if (offsets[c] != static_cast<double>(npe) * (c + 1))
                fail(offsets_array, fmt::format("offset of cell {} is {}, expected {} ({} nodes "
                                                "per {})",
                                                c, offsets[c], npe * (c + 1.0), npe,
                                                mesh::element_name(mesh.type)));
        const std::vector<double> connectivity =
            read_array(connectivity_array, static_cast<std::size_t>(m) * npe, 1);
        mesh.elements.resize(m, npe);
        for (Index c = 0; c < m; ++c)
            for (int a = 0; a < npe; ++a) {
                const double v = connectivity[static_cast<std::size_t>(c) * npe + a];
                if (!(v >= 0 && v < n) || v != std::floor(v))
                    fail(connectivity_array, fmt::format("cell {} refers to point {}, but points "
                                                         "are numbered 0..{}",
                                                         c, v, n - 1));
                mesh.elements(c, a) = static_cast<Index>(v);
            }
        const int dim = mesh.dim();
        mesh.rest_positions.resize(n, dim);
        for (Index p = 0; p < n; ++p) {
            const double* x = &xyz[3 * static_cast<std::size_t>(p)];
            if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
                fail(points_array, fmt::format("point {} has a non-finite coordinate ({}, {}, {})",
                                               p, x[0], x[1], x[2]));
            if (dim == 2 && x[2] != 0.0)
                fail(points_array, fmt::format("point {} has z = {}, but a mesh of {}s must lie "
                                               "in the plane z = 0",
                                               p, x[2], mesh::element_name(mesh.type)));
            for (int d = 0; d < dim; ++d) mesh.rest_positions(p, d) = x[d];
        }
        mesh.material_ids = IndexVector::Zero(m);

        VtuFields fields;
        for (const XmlElement* data : m_doc.children(piece, "PointData"))
            read_fields(*data, n, fields.point_data);
        for (const XmlElement* data : m_doc.children(piece, "CellData"))
            read_fields(*data, m, fields.cell_data);
        for (auto it = fields.cell_data.begin(); it != fields.cell_data.end(); ++it) {
            if (it->name != "material_id") continue;
            if (it->values.cols() != 1)
                fail(piece, "cell field material_id must have one component");
            for (Index c = 0; c < m; ++c) {
                const double id = it->values(c, 0);
                if (id != std::floor(id) || std::abs(id) > std::numeric_limits<Index>::max())
                    fail(piece,
                         fmt::format("material_id of cell {} is {}, expected an integer", c, id));
                mesh.material_ids[c] = static_cast<Index>(id);
            }
            fields.cell_data.erase(it);
            break;
        }
        detail::validate_read_mesh(mesh, m_file, {}, connectivity_array.line);
        return {std::move(mesh), std::move(fields)};
    }

  private:
    [[noreturn]] void fail(const XmlElement& e, const std::string& message) const {
        throw MeshReadError(fmt::format("{}:{}: {}", m_file, e.line, message));
    }

    const XmlElement& only_child(const XmlElement& parent, std::string_view name) const {
        const auto found = m_doc.children(parent, name);
        if (found.size() != 1)
            fail(parent, fmt::format("expected one <{}> in <{}>, found {}", name, parent.name,
                                     found.size()));
        return *found.front();
    }

    const XmlElement& named_array(const XmlElement& parent, std::string_view name) const {
        const XmlElement* found = nullptr;
        for (const XmlElement* a : m_doc.children(parent, "DataArray")) {
            const std::string* n = a->attribute("Name");
            if (n && *n == name) found = a;
        }
        if (!found) fail(parent, fmt::format("<{}> has no DataArray named {}", parent.name, name));
        return *found;
    }

    Index count_attribute(const XmlElement& e, const char* key) const {
        const std::string* value = e.attribute(key);
        if (!value) fail(e, fmt::format("<{}> has no {} attribute", e.name, key));
        return parse_count(e, *value, key);
    }

    Index parse_count(const XmlElement& e, std::string_view text, const char* what) const {
        std::int64_t v = -1;
        const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || ptr != text.data() + text.size() || v < 0 ||
            v > std::numeric_limits<Index>::max())
            fail(e, fmt::format("expected {} to be a count in 0..{}, found {}", what,
                                std::numeric_limits<Index>::max(), quoted(text)));
        return static_cast<Index>(v);
    }

    ElementType element_type(const XmlElement& array, double t, Index cell) const {
        if (t == 5) return ElementType::Tri3;
        if (t == 9) return ElementType::Quad4;
        if (t == 10) return ElementType::Tet4;
        if (t == 12) return ElementType::Hex8;
        fail(array, fmt::format("cell {} has VTK cell type {}; coarsegrain reads 5 (triangle), "
                                "9 (quad), 10 (tetra) and 12 (hexahedron)",
                                cell, t));
    }

    void read_fields(const XmlElement& data, Index rows, std::vector<Field>& out) const {
        for (const XmlElement* a : m_doc.children(data, "DataArray")) {
            const std::string* name = a->attribute("Name");
            if (!name || name->empty()) fail(*a, "a field DataArray has no Name");
            for (const Field& f : out)
                if (f.name == *name) fail(*a, fmt::format("two fields are named {}", *name));
            Index components = 1;
            if (const std::string* c = a->attribute("NumberOfComponents"))
                components = parse_count(*a, *c, "NumberOfComponents");
            if (components < 1 || components > (1 << 16))
                fail(*a,
                     fmt::format("NumberOfComponents {} is out of the range 1..65536", components));
            const std::vector<double> values =
                read_array(*a, static_cast<std::size_t>(rows), components);
            Field f{*name, Matrix(rows, components)};
            for (Index i = 0; i < rows; ++i)
                for (Index j = 0; j < components; ++j)
                    f.values(i, j) = values[static_cast<std::size_t>(i) * components + j];
            out.push_back(std::move(f));
        }
    }

    /// Reads a DataArray of rows x components values (any VTK scalar type) as doubles;
    /// NumberOfComponents, if given, must equal `components`.
    std::vector<double> read_array(const XmlElement& a, std::size_t rows, Index components) const {
        if (const std::string* c = a.attribute("NumberOfComponents");
            c && parse_count(a, *c, "NumberOfComponents") != components)
            fail(a, fmt::format("expected NumberOfComponents=\"{}\", found {}", components,
                                quoted(*c)));
        const std::size_t count = rows * static_cast<std::size_t>(components);
        const std::string* type = a.attribute("type");
        if (!type) fail(a, "<DataArray> has no type attribute");
        int size = 0;
        for (const auto& [name, bytes] : {std::pair<const char*, int>{"Float32", 4},
                                          {"Float64", 8},
                                          {"Int8", 1},
                                          {"UInt8", 1},
                                          {"Int16", 2},
                                          {"UInt16", 2},
                                          {"Int32", 4},
                                          {"UInt32", 4},
                                          {"Int64", 8},
                                          {"UInt64", 8}})
            if (*type == name) size = bytes;
        if (size == 0) fail(a, fmt::format("unsupported DataArray type {}", quoted(*type)));
        const std::string* format = a.attribute("format");
        if (!format) fail(a, "<DataArray> has no format attribute");
        if (*format == "ascii") return read_ascii(a, count);

        std::string_view text;
        bool raw = false;
        if (*format == "binary") {
            text = m_doc.content(a);
        } else if (*format == "appended") {
            if (!m_appended) fail(a, "format=\"appended\" but the file has no <AppendedData>");
            const std::string* offset = a.attribute("offset");
            if (!offset) fail(a, "an appended DataArray needs an offset attribute");
            std::uint64_t at = 0;
            const auto [ptr, ec] =
                std::from_chars(offset->data(), offset->data() + offset->size(), at);
            const std::string_view appended = m_doc.content(*m_appended);
            if (ec != std::errc() || ptr != offset->data() + offset->size() || at > appended.size())
                fail(a, fmt::format("offset {} is not within the {} bytes of appended data",
                                    quoted(*offset), appended.size()));
            text = appended.substr(at);
            raw = m_appended_raw;
        } else {
            fail(a, fmt::format("expected format ascii, binary or appended, found {}",
                                quoted(*format)));
        }

        std::vector<std::uint8_t> bytes;
        const std::uint64_t expected = static_cast<std::uint64_t>(count) * size;
        std::uint64_t declared = 0;
        if (raw) {
            if (text.size() < m_header_bytes) fail(a, "appended data ends inside a block header");
            std::memcpy(&declared, text.data(), m_header_bytes);
            check_block_size(a, declared, expected);
            if (text.size() - m_header_bytes < expected)
                fail(a, fmt::format("appended data ends after {} of the {} bytes of the array",
                                    text.size() - m_header_bytes, expected));
            bytes.assign(text.begin() + m_header_bytes,
                         text.begin() + static_cast<std::ptrdiff_t>(m_header_bytes + expected));
        } else {
            detail::Base64Reader base64(text);
            std::uint8_t header[8] = {0, 0, 0, 0, 0, 0, 0, 0};
            if (!base64.read(header, m_header_bytes))
                fail(a, "invalid or truncated base64 data in the block header");
            std::memcpy(&declared, header, m_header_bytes);
            check_block_size(a, declared, expected);
            if (base64.bytes_left() < expected)
                fail(a, fmt::format("the base64 data holds fewer than the {} bytes of the array",
                                    expected));
            bytes.resize(expected);
            if (!base64.read(bytes.data(), expected)) fail(a, "invalid or truncated base64 data");
        }
        return decode(*type, bytes.data(), count);
    }

    void check_block_size(const XmlElement& a, std::uint64_t declared,
                          std::uint64_t expected) const {
        if (declared != expected)
            fail(a, fmt::format("the block header declares {} bytes, but the array needs {}",
                                declared, expected));
    }

    template <class T>
    static std::vector<double> decode_as(const std::uint8_t* p, std::size_t count) {
        std::vector<double> values(count);
        for (std::size_t i = 0; i < count; ++i) {
            T v;
            std::memcpy(&v, p + i * sizeof(T), sizeof(T));
            values[i] = static_cast<double>(v);
        }
        return values;
    }

    static std::vector<double> decode(const std::string& type, const std::uint8_t* p,
                                      std::size_t count) {
        if (type == "Float64") return decode_as<double>(p, count);
        if (type == "Float32") return decode_as<float>(p, count);
        if (type == "Int8") return decode_as<std::int8_t>(p, count);
        if (type == "UInt8") return decode_as<std::uint8_t>(p, count);
        if (type == "Int16") return decode_as<std::int16_t>(p, count);
        if (type == "UInt16") return decode_as<std::uint16_t>(p, count);
        if (type == "Int32") return decode_as<std::int32_t>(p, count);
        if (type == "UInt32") return decode_as<std::uint32_t>(p, count);
        if (type == "Int64") return decode_as<std::int64_t>(p, count);
        return decode_as<std::uint64_t>(p, count);
    }

    std::vector<double> read_ascii(const XmlElement& a, std::size_t count) const {
        const std::string_view text = m_doc.content(a);
        std::vector<double> values;
        values.reserve(std::min(count, text.size() / 2 + 1));
        std::size_t i = 0;
        while (true) {
            while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
            if (i >= text.size()) break;
            const std::size_t start = i;
            while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
            const std::string_view token = text.substr(start, i - start);
            if (values.size() == count)
                fail(a, fmt::format("the array holds more than the {} values expected", count));
            double v = 0;
            const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
            if (ec != std::errc() || ptr != token.data() + token.size())
                fail(a, fmt::format("expected a number, found {}", quoted(token)));
            values.push_back(v);
        }
        if (values.size() != count)
            fail(a, fmt::format("the array holds {} values, expected {}", values.size(), count));
        return values;
    }

    std::string m_file;
    XmlDocument m_doc;
    std::size_t m_header_bytes = 4;
    const XmlElement* m_appended = nullptr;
    bool m_appended_raw = false;
};

}  // namespace

void write_vtu(const std::string& file, const mesh::Mesh& mesh, const VtuFields& fields) {
    detail::check_writable(mesh, file);
    check_fields(fields.point_data, mesh.num_nodes(), "point", file);
    check_fields(fields.cell_data, mesh.num_elements(), "cell", file);
    for (const Field& f : fields.cell_data)
        CG_VERIFY(f.name != "material_id",
                  "cannot write {}: the cell field name material_id is reserved (it is written "
                  "from the mesh's material ids)",
                  file);
    const Index n = mesh.num_nodes(), m = mesh.num_elements();
    const int npe = mesh::nodes_per_element(mesh.type);

    write_atomically(file, [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
               "header_type=\"UInt64\">\n"
               "  <UnstructuredGrid>\n"
            << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << m << "\">\n";
        out << "      <PointData>\n";
        for (const Field& f : fields.point_data)
            write_array(out, "Float64", f.name, static_cast<Index>(f.values.cols()),
                        binary_block(row_major(f.values)));
        out << "      </PointData>\n      <CellData>\n";
        write_array(out, "Int32", "material_id", 1,
                    binary_block(std::vector<std::int32_t>(mesh.material_ids.begin(),
                                                           mesh.material_ids.end())));
        for (const Field& f : fields.cell_data)
            write_array(out, "Float64", f.name, static_cast<Index>(f.values.cols()),
                        binary_block(row_major(f.values)));
        out << "      </CellData>\n      <Points>\n";
        std::vector<double> xyz(3 * static_cast<std::size_t>(n), 0.0);
        for (Index v = 0; v < n; ++v)
            for (int d = 0; d < mesh.dim(); ++d) xyz[3 * v + d] = mesh.rest_positions(v, d);
        write_array(out, "Float64", "", 3, binary_block(xyz));
        out << "      </Points>\n      <Cells>\n";
        std::vector<std::int32_t> connectivity(static_cast<std::size_t>(m) * npe);
        std::vector<std::int32_t> offsets(m);
        for (Index e = 0; e < m; ++e) {
            for (int a = 0; a < npe; ++a) connectivity[e * npe + a] = mesh.elements(e, a);
            offsets[e] = (e + 1) * npe;
        }
        write_array(out, "Int32", "connectivity", 1, binary_block(connectivity));
        write_array(out, "Int32", "offsets", 1, binary_block(offsets));
        write_array(out, "UInt8", "types", 1,
                    binary_block(std::vector<std::uint8_t>(m, vtk_cell_type(mesh.type))));
        out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    });
}

std::pair<mesh::Mesh, VtuFields> read_vtu(const std::string& file) {
    return VtuReader(file).read();
}

void write_pvd(const std::string& file, const std::vector<std::pair<double, std::string>>& steps) {
    for (const auto& [time, name] : steps)
        CG_VERIFY(std::isfinite(time), "cannot write {}: time {} of {} is not finite", file, time,
                  name);
    write_atomically(file, [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
               "  <Collection>\n";
        for (const auto& [time, name] : steps)
            out << fmt::format("    <DataSet timestep=\"{}\" part=\"0\" file=\"{}\"/>\n", time,
                               detail::xml_escape(name));
        out << "  </Collection>\n</VTKFile>\n";
    });
}

}  // namespace coarsegrain::io
