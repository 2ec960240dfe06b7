#include "coarsegrain/mesh/mesh.hpp"

#include <cmath>

#include <fmt/ranges.h>

#include <limits>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mesh {

int element_dim(ElementType type) {
    return (type == ElementType::Tri3 || type == ElementType::Quad4) ? 2 : 3;
}

int nodes_per_element(ElementType type) {
    switch (type) {
        case ElementType::Tri3: return 3;
        case ElementType::Quad4: return 4;
        case ElementType::Tet4: return 4;
        case ElementType::Hex8: return 8;
    }
    return 0;
}

std::string element_name(ElementType type) {
    switch (type) {
        case ElementType::Tri3: return "tri";
        case ElementType::Quad4: return "quad";
        case ElementType::Tet4: return "tet";
        case ElementType::Hex8: return "hex";
    }
    return "?";
}

bool is_simplex(ElementType type) {
    return type == ElementType::Tri3 || type == ElementType::Tet4;
}

Eigen::Vector3d GridInfo::spacing() const {
    return ((max - min).array() / cells.cast<double>().array()).matrix();
}

Matrix Mesh::element_positions(Index e) const {
    const int npe = nodes_per_element(type);
    Matrix X(npe, dim());
    for (int a = 0; a < npe; ++a) X.row(a) = rest_positions.row(elements(e, a));
    return X;
}

namespace {

double triangle_area(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    const Eigen::Vector2d u = b - a, v = c - a;
    return 0.5 * (u.x() * v.y() - u.y() * v.x());
}

double tet_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
    return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

// The trilinear map's volume is the exact integral of det J; the 2x2x2 Gauss rule integrates
// det J (a polynomial of degree <= 2 in each variable) exactly.
double hex_volume(const Matrix& X) {
    static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const double g[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    double vol = 0;
    for (int q = 0; q < 8; ++q) {
        const double xi[3] = {g[q & 1], g[(q >> 1) & 1], g[(q >> 2) & 1]};
        Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
        for (int a = 0; a < 8; ++a) {
            double dN[3];
            for (int d = 0; d < 3; ++d) {
                dN[d] = 1.0;
                for (int k = 0; k < 3; ++k) {
                    const double s = corner[a][k] ? xi[k] : 1.0 - xi[k];
                    const double ds = corner[a][k] ? 1.0 : -1.0;
                    dN[d] *= (k == d) ? ds : s;
                }
            }
            for (int d = 0; d < 3; ++d) J.col(d) += X.row(a).transpose() * dN[d];
        }
        vol += J.determinant() / 8.0;
    }
    return vol;
}

// Minimum corner Jacobian of a hex (each corner's three edges): positive for a valid,
// non-inverted hex. The integral alone can hide a locally inverted element.
double hex_min_corner_jacobian(const Matrix& X) {
    static const int nbr[8][3] = {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7},
                                  {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}};
    double m = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 8; ++a) {
        Eigen::Matrix3d J;
        for (int k = 0; k < 3; ++k) J.col(k) = (X.row(nbr[a][k]) - X.row(a)).transpose();
        m = std::min(m, J.determinant());
    }
    return m;
}

double quad_min_corner_jacobian(const Matrix& X) {
    double m = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 4; ++a) {
        const Eigen::Vector2d p = X.row(a), n = X.row((a + 1) % 4), pr = X.row((a + 3) % 4);
        m = std::min(m, 2.0 * triangle_area(p, n, pr));
    }
    return m;
}

}  // namespace

double element_measure(const Mesh& mesh, Index e) {
    const Matrix X = mesh.element_positions(e);
    switch (mesh.type) {
        case ElementType::Tri3: return triangle_area(X.row(0), X.row(1), X.row(2));
        case ElementType::Quad4:
            return triangle_area(X.row(0), X.row(1), X.row(2)) +
                   triangle_area(X.row(0), X.row(2), X.row(3));
        case ElementType::Tet4: return tet_volume(X.row(0), X.row(1), X.row(2), X.row(3));
        case ElementType::Hex8: return hex_volume(X);
    }
    return 0.0;
}

Matrix bounding_box(const Mesh& mesh) {
    Matrix box(2, mesh.dim());
    box.row(0) = mesh.rest_positions.colwise().minCoeff();
    box.row(1) = mesh.rest_positions.colwise().maxCoeff();
    return box;
}

Mesh element_subset(const Mesh& mesh, const std::vector<Index>& kept) {
    std::vector<Index> number(static_cast<std::size_t>(mesh.num_nodes()), -1);
    for (const Index e : kept) {
        CG_VERIFY(e >= 0 && e < mesh.num_elements(), "mesh: element {} out of range 0..{}", e,
                  mesh.num_elements() - 1);
        for (Index a = 0; a < mesh.elements.cols(); ++a) number[mesh.elements(e, a)] = 0;
    }
    Index nodes = 0;
    for (Index& n : number)
        if (n == 0) n = nodes++;
    Mesh out;
    out.type = mesh.type;
    out.rest_positions.resize(nodes, mesh.dim());
    for (Index v = 0; v < mesh.num_nodes(); ++v)
        if (number[v] >= 0) out.rest_positions.row(number[v]) = mesh.rest_positions.row(v);
    out.elements.resize(static_cast<Index>(kept.size()), mesh.elements.cols());
    for (Index r = 0; r < out.num_elements(); ++r)
        for (Index a = 0; a < mesh.elements.cols(); ++a)
            out.elements(r, a) = number[mesh.elements(kept[r], a)];
    out.material_ids = IndexVector::Zero(out.num_elements());
    return out;
}

void validate(const Mesh& mesh, const std::string& source) {
    const int npe = nodes_per_element(mesh.type);
    const int dim = mesh.dim();
    CG_VERIFY(mesh.rest_positions.cols() == dim,
              "{}: {} mesh needs {} coordinates per node, got {}", source,
              element_name(mesh.type), dim, mesh.rest_positions.cols());
    CG_VERIFY(mesh.num_nodes() > 0, "{}: the mesh has no nodes", source);
    CG_VERIFY(mesh.num_elements() > 0, "{}: the mesh has no {} elements", source,
              element_name(mesh.type));
    CG_VERIFY(mesh.elements.cols() == npe, "{}: {} elements need {} nodes, got {}", source,
              element_name(mesh.type), npe, mesh.elements.cols());
    CG_VERIFY(mesh.material_ids.size() == mesh.num_elements(),
              "{}: {} material ids for {} elements", source, mesh.material_ids.size(),
              mesh.num_elements());
    for (Index v = 0; v < mesh.num_nodes(); ++v)
        CG_VERIFY(mesh.rest_positions.row(v).allFinite(),
                  "{}: node {} has a non-finite coordinate", source, v);
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (int a = 0; a < npe; ++a)
            CG_VERIFY(mesh.elements(e, a) >= 0 && mesh.elements(e, a) < mesh.num_nodes(),
                      "{}: element {} refers to node {}, but nodes are numbered 0..{}", source,
                      e, mesh.elements(e, a), mesh.num_nodes() - 1);
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        const Matrix X = mesh.element_positions(e);
        const double h = (X.colwise().maxCoeff() - X.colwise().minCoeff()).maxCoeff();
        const double tol = 1e-12 * std::pow(h, dim);
        double m = element_measure(mesh, e);
        if (mesh.type == ElementType::Hex8) m = std::min(m, hex_min_corner_jacobian(X) / 6.0);
        if (mesh.type == ElementType::Quad4) m = std::min(m, quad_min_corner_jacobian(X) / 2.0);
        CG_VERIFY(m > tol,
                  "{}: element {} is {} (measure {:.3g}); check its node order ({} nodes: {})",
                  source, e, m < -tol ? "inverted" : "degenerate", m, element_name(mesh.type),
                  fmt::join(mesh.elements.row(e), " "));
    }
}

}  // namespace coarsegrain::mesh
