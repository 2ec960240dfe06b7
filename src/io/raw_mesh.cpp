#include "raw_mesh.hpp"

#include <algorithm>
#include <utility>

#include "coarsegrain/common/error.hpp"
#include "text_reader.hpp"

namespace coarsegrain::io::detail {

using mesh::ElementType;

void RawMesh::add_node(double x, double y, double z, int line) {
    xyz.insert(xyz.end(), {x, y, z});
    node_line.push_back(line);
}

void RawMesh::add_element(ElementType type, const std::int64_t* nodes, Index material, int line) {
    RawElements& block = blocks[static_cast<int>(type)];
    block.nodes.insert(block.nodes.end(), nodes, nodes + mesh::nodes_per_element(type));
    block.material.push_back(material);
    block.line.push_back(line);
}

void RawMesh::add_other(int dim, int line, const std::string& name) {
    if (dim > other_dim) {
        other_dim = dim;
        other_line = line;
        other_name = name;
    }
}

namespace {

/// Maps the file's node numbers to positions in RawMesh: a dense table when the numbers are
/// not too sparse, a sorted table otherwise (never an allocation sized by the largest number).
class NodeLookup {
  public:
    NodeLookup(const RawMesh& raw, const TextReader& reader)
        : m_count(static_cast<Index>(raw.node_line.size())), m_base(raw.tag_base) {
        if (raw.tags.empty()) return;
        m_implicit = false;
        const auto [lo, hi] = std::minmax_element(raw.tags.begin(), raw.tags.end());
        m_base = *lo;
        const auto span = static_cast<std::uint64_t>(*hi) - static_cast<std::uint64_t>(*lo);
        if (span <= 4 * static_cast<std::uint64_t>(m_count) + 1024) {
            m_dense.assign(span + 1, -1);
            for (Index i = 0; i < m_count; ++i) {
                Index& slot = m_dense[static_cast<std::size_t>(
                    static_cast<std::uint64_t>(raw.tags[i]) - static_cast<std::uint64_t>(m_base))];
                if (slot >= 0) duplicate(raw, reader, slot, i);
                slot = i;
            }
        } else {
            m_sorted.reserve(raw.tags.size());
            for (Index i = 0; i < m_count; ++i) m_sorted.emplace_back(raw.tags[i], i);
            std::sort(m_sorted.begin(), m_sorted.end());
            for (std::size_t k = 1; k < m_sorted.size(); ++k)
                if (m_sorted[k].first == m_sorted[k - 1].first) {
                    const Index a = std::min(m_sorted[k - 1].second, m_sorted[k].second);
                    const Index b = std::max(m_sorted[k - 1].second, m_sorted[k].second);
                    duplicate(raw, reader, a, b);
                }
        }
    }

    /// Position of node number `tag`, or -1.
    Index find(std::int64_t tag) const {
        if (m_implicit) {
            if (tag < m_base || tag - m_base >= m_count) return -1;
            return static_cast<Index>(tag - m_base);
        }
        if (!m_dense.empty()) {
            if (tag < m_base) return -1;
            const auto offset =
                static_cast<std::uint64_t>(tag) - static_cast<std::uint64_t>(m_base);
            return offset < m_dense.size() ? m_dense[offset] : -1;
        }
        const auto it = std::lower_bound(m_sorted.begin(), m_sorted.end(),
                                         std::pair<std::int64_t, Index>(tag, -1));
        return (it != m_sorted.end() && it->first == tag) ? it->second : -1;
    }

  private:
    [[noreturn]] static void duplicate(const RawMesh& raw, const TextReader& reader, Index first,
                                       Index second) {
        reader.fail_at(raw.node_line[second],
                       fmt::format("node {} is defined twice (first on line {})", raw.tags[second],
                                   raw.node_line[first]));
    }

    Index m_count;
    std::int64_t m_base;
    bool m_implicit = true;
    std::vector<Index> m_dense;
    std::vector<std::pair<std::int64_t, Index>> m_sorted;
};

std::string plural(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return "triangles";
        case ElementType::Quad4:
            return "quads";
        case ElementType::Tet4:
            return "tetrahedra";
        case ElementType::Hex8:
            return "hexahedra";
    }
    return "?";
}

}  // namespace

mesh::Mesh build_mesh(const RawMesh& raw, const TextReader& reader, int end_line) {
    constexpr ElementType kTypes[] = {ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                      ElementType::Hex8};
    int dim = -1;
    for (ElementType t : kTypes)
        if (!raw.blocks[static_cast<int>(t)].line.empty())
            dim = std::max(dim, mesh::element_dim(t));
    if (dim < 0 && raw.other_dim < 0)
        reader.fail_at(end_line, "the file has no triangles, quads, tetrahedra or hexahedra");
    if (raw.other_dim >= dim)
        reader.fail_at(raw.other_line,
                       fmt::format("{} elements are not supported (coarsegrain reads linear "
                                   "triangles, quads, tetrahedra and hexahedra)",
                                   raw.other_name));

    std::vector<ElementType> present;
    for (ElementType t : kTypes)
        if (mesh::element_dim(t) == dim && !raw.blocks[static_cast<int>(t)].line.empty())
            present.push_back(t);
    if (present.size() > 1) {
        const RawElements& a = raw.blocks[static_cast<int>(present[0])];
        const RawElements& b = raw.blocks[static_cast<int>(present[1])];
        const bool a_first = a.line.front() < b.line.front();
        reader.fail_at(
            a_first ? b.line.front() : a.line.front(),
            fmt::format("the file mixes {} (first on line {}) and {} (first on line "
                        "{}); a mesh must have a single element type",
                        plural(present[0]), a.line.front(), plural(present[1]), b.line.front()));
    }
    const ElementType type = present.front();
    const RawElements& block = raw.blocks[static_cast<int>(type)];
    const int npe = mesh::nodes_per_element(type);
    const auto num_elements = static_cast<Index>(block.line.size());
    const auto num_raw_nodes = static_cast<Index>(raw.node_line.size());

    const NodeLookup lookup(raw, reader);
    std::vector<Index> position(block.nodes.size());
    std::vector<Index> new_index(num_raw_nodes, -1);
    for (Index e = 0; e < num_elements; ++e)
        for (int a = 0; a < npe; ++a) {
            const std::int64_t tag = block.nodes[static_cast<std::size_t>(e) * npe + a];
            const Index p = lookup.find(tag);
            if (p < 0)
                reader.fail_at(block.line[e],
                               fmt::format("element refers to node {}, which the file does not "
                                           "define",
                                           tag));
            position[static_cast<std::size_t>(e) * npe + a] = p;
            new_index[p] = 0;
        }
    Index num_nodes = 0;
    for (Index& v : new_index)
        if (v == 0) v = num_nodes++;

    mesh::Mesh result;
    result.type = type;
    result.rest_positions.resize(num_nodes, dim);
    for (Index p = 0; p < num_raw_nodes; ++p) {
        if (new_index[p] < 0) continue;
        const double* x = &raw.xyz[3 * static_cast<std::size_t>(p)];
        if (dim == 2 && x[2] != 0.0)
            reader.fail_at(
                raw.node_line[p],
                fmt::format("node {} has z = {}, but a mesh of {} must lie in the "
                            "plane z = 0",
                            raw.tags.empty() ? raw.tag_base + p : raw.tags[p], x[2], plural(type)));
        for (int d = 0; d < dim; ++d) result.rest_positions(new_index[p], d) = x[d];
    }
    result.elements.resize(num_elements, npe);
    for (Index e = 0; e < num_elements; ++e)
        for (int a = 0; a < npe; ++a)
            result.elements(e, a) = new_index[position[static_cast<std::size_t>(e) * npe + a]];
    result.material_ids = Eigen::Map<const IndexVector>(block.material.data(), num_elements);
    validate_read_mesh(result, reader.file(), block.line, end_line);
    return result;
}

void validate_read_mesh(const mesh::Mesh& mesh, const std::string& file,
                        const std::vector<int>& element_line, int fallback_line) {
    try {
        mesh::validate(mesh, file);
    } catch (const MeshReadError&) {
        throw;
    } catch (const Error& error) {
        std::string message = error.what();
        const std::string prefix = file + ": ";
        if (message.starts_with(prefix)) message.erase(0, prefix.size());
        int line = fallback_line;
        // Find the first element that fails on its own: its line is the one to report.
        const int npe = mesh::nodes_per_element(mesh.type);
        const bool per_element =
            mesh.elements.cols() == npe && mesh.rest_positions.cols() == mesh.dim() &&
            element_line.size() == static_cast<std::size_t>(mesh.num_elements());
        for (Index e = 0; per_element && e < mesh.num_elements(); ++e) {
            mesh::Mesh single;
            single.type = mesh.type;
            single.rest_positions.resize(npe, mesh.dim());
            bool in_range = true;
            for (int a = 0; a < npe; ++a) {
                const Index v = mesh.elements(e, a);
                in_range = in_range && v >= 0 && v < mesh.num_nodes();
                if (in_range) single.rest_positions.row(a) = mesh.rest_positions.row(v);
            }
            if (!in_range) {
                line = element_line[e];
                break;
            }
            single.elements.resize(1, npe);
            for (int a = 0; a < npe; ++a) single.elements(0, a) = a;
            single.material_ids = IndexVector::Zero(1);
            try {
                mesh::validate(single, file);
            } catch (const Error&) {
                line = element_line[e];
                break;
            }
        }
        throw MeshReadError(fmt::format("{}:{}: {}", file, std::max(line, 1), message));
    }
}

}  // namespace coarsegrain::io::detail
