#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/boundary.hpp"

namespace coarsegrain::mesh {

namespace {
bool in_box(const Eigen::Ref<const Eigen::RowVectorXd>& x, const Eigen::VectorXd& lo,
            const Eigen::VectorXd& hi) {
    return (x.transpose().array() >= lo.array()).all() && (x.transpose().array() <= hi.array()).all();
}
}  // namespace

std::vector<Index> nodes_in_box(const Mesh& mesh, const Eigen::VectorXd& lo,
                                const Eigen::VectorXd& hi) {
    CG_VERIFY(lo.size() == mesh.dim() && hi.size() == mesh.dim(),
              "box: min and max need {} components", mesh.dim());
    std::vector<Index> nodes;
    for (Index v = 0; v < mesh.num_nodes(); ++v)
        if (in_box(mesh.rest_positions.row(v), lo, hi)) nodes.push_back(v);
    return nodes;
}

std::vector<Index> facets_in_box(const Mesh& mesh, const Boundary& b, const Eigen::VectorXd& lo,
                                 const Eigen::VectorXd& hi) {
    CG_VERIFY(lo.size() == mesh.dim() && hi.size() == mesh.dim(),
              "box: min and max need {} components", mesh.dim());
    std::vector<Index> facets;
    for (Index f = 0; f < b.size(); ++f) {
        bool inside = true;
        for (Index a = 0; a < b.facets.cols() && inside; ++a)
            inside = in_box(mesh.rest_positions.row(b.facets(f, a)), lo, hi);
        if (inside) facets.push_back(f);
    }
    return facets;
}

}  // namespace coarsegrain::mesh
