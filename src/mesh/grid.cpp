#include "coarsegrain/mesh/grid.hpp"

#include <array>

#include "coarsegrain/common/error.hpp"
#include "reference_cell.hpp"

namespace coarsegrain::mesh {

using detail::kHexCorners;
using detail::kKuhnTets;
using detail::kQuadCorners;
using detail::kTriangles;

Mesh make_grid(ElementType type, const Eigen::VectorXd& min, const Eigen::VectorXd& max,
               const Eigen::VectorXi& cells) {
    const int dim = element_dim(type);
    CG_VERIFY(min.size() == dim && max.size() == dim && cells.size() == dim,
              "grid: a {} grid needs {} components in min, max and cells", element_name(type), dim);
    for (int d = 0; d < dim; ++d) {
        CG_VERIFY(max[d] > min[d], "grid: max[{}] = {} must exceed min[{}] = {}", d, max[d], d,
                  min[d]);
        CG_VERIFY(cells[d] >= 1, "grid: cells[{}] = {} must be at least 1", d, cells[d]);
    }
    GridInfo info;
    info.min.head(dim) = min;
    info.max.head(dim) = max;
    info.cells.head(dim) = cells;
    const Eigen::Vector3i n = info.cells;
    const Eigen::Vector3i nv(n[0] + 1, n[1] + 1, dim == 3 ? n[2] + 1 : 1);
    const Eigen::Vector3d h = info.spacing();

    Mesh mesh;
    mesh.type = type;
    mesh.grid = info;
    mesh.rest_positions.resize(static_cast<Index>(nv.prod()), dim);
    for (int k = 0; k < nv[2]; ++k)
        for (int j = 0; j < nv[1]; ++j)
            for (int i = 0; i < nv[0]; ++i) {
                const Index v = i + nv[0] * (j + nv[1] * k);
                const Eigen::Vector3d p(i, j, k);
                for (int d = 0; d < dim; ++d)
                    mesh.rest_positions(v, d) =
                        (i == n[0] && d == 0) || (j == n[1] && d == 1) || (k == n[2] && d == 2)
                            ? info.max[d]
                            : info.min[d] + p[d] * h[d];
            }

    const Index num_cells = static_cast<Index>(n[0]) * n[1] * (dim == 3 ? n[2] : 1);
    const int per_cell = type == ElementType::Tet4 ? 6 : type == ElementType::Tri3 ? 2 : 1;
    mesh.elements.resize(num_cells * per_cell, nodes_per_element(type));
    mesh.material_ids = IndexVector::Zero(num_cells * per_cell);
    const int nz = dim == 3 ? n[2] : 1;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const Index c = i + n[0] * (j + n[1] * k);
                std::array<Index, 8> corner{};
                for (int b = 0; b < (1 << dim); ++b)
                    corner[b] = (i + (b & 1)) +
                                nv[0] * ((j + ((b >> 1) & 1)) + nv[1] * (k + ((b >> 2) & 1)));
                switch (type) {
                    case ElementType::Hex8:
                        for (int a = 0; a < 8; ++a) mesh.elements(c, a) = corner[kHexCorners[a]];
                        break;
                    case ElementType::Quad4:
                        for (int a = 0; a < 4; ++a) mesh.elements(c, a) = corner[kQuadCorners[a]];
                        break;
                    case ElementType::Tet4:
                        for (int t = 0; t < 6; ++t)
                            for (int a = 0; a < 4; ++a)
                                mesh.elements(6 * c + t, a) = corner[kKuhnTets[t][a]];
                        break;
                    case ElementType::Tri3:
                        for (int t = 0; t < 2; ++t)
                            for (int a = 0; a < 3; ++a)
                                mesh.elements(2 * c + t, a) = corner[kTriangles[t][a]];
                        break;
                }
            }
    return mesh;
}

Matrix element_centroids(const Mesh& mesh) {
    Matrix centres(mesh.num_elements(), mesh.dim());
    const int npe = nodes_per_element(mesh.type);
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        Eigen::RowVectorXd s = Eigen::RowVectorXd::Zero(mesh.dim());
        for (int a = 0; a < npe; ++a) s += mesh.rest_positions.row(mesh.elements(e, a));
        centres.row(e) = s / npe;
    }
    return centres;
}

}  // namespace coarsegrain::mesh
