#include "coarsegrain/mra/automatic_levels.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/mra/hierarchy.hpp"

namespace coarsegrain::mra {

namespace {

/// Containment tolerance in barycentric coordinates (and in cells when finding a point's cells),
/// as PointLocator's.
constexpr double kInside = 1e-10;

/// Corner support below the finest automatic level. The grids are nested, so a node of level
/// k+1 < q is a corner (support 1) or an edge midpoint (1/2) of level k's elements; more than
/// 1/2 keeps the elements whose corners are all nodes of level k+1.
constexpr double kNestedSupport = 0.75;

/// The fine mesh's mean node spacing h = (V / N)^{1/d}.
double mean_spacing(const mesh::Mesh& fine) {
    double measure = 0;
    for (Index e = 0; e < fine.num_elements(); ++e) measure += mesh::element_measure(fine, e);
    CG_VERIFY(measure > 0 && fine.num_nodes() > 0,
              "mra: automatic level meshes need a fine mesh of positive measure");
    return std::pow(measure / static_cast<double>(fine.num_nodes()), 1.0 / fine.dim());
}

/// Cells per axis of the coarsest automatic level: max(1, round(extent / h_1)) (dim entries).
Eigen::VectorXi coarsest_cells(const Matrix& box, double h_1) {
    Eigen::VectorXi cells(box.cols());
    for (Index a = 0; a < box.cols(); ++a)
        cells[a] = std::max(1, static_cast<int>(std::lround((box(1, a) - box(0, a)) / h_1)));
    return cells;
}

/// Per element of a simplex grid made by make_grid, each corner's largest barycentric coordinate
/// at the points the element contains (#E by dim + 1; -1 in the rows of elements that contain
/// none). A point on a cell's face is looked up in every cell that holds it.
/// @param[in] points  #points by dim
Matrix corner_support(const mesh::Mesh& grid, const Matrix& points) {
    const mesh::GridInfo& g = *grid.grid;
    const int dim = grid.dim();
    const int per_cell = dim == 2 ? 2 : 6;  // make_grid's triangles or Kuhn tetrahedra per cell
    const Eigen::Vector3d h = g.spacing();
    Matrix support = Matrix::Constant(grid.num_elements(), dim + 1, -1.0);
    for (Index p = 0; p < points.rows(); ++p) {
        const Eigen::VectorXd x = points.row(p).transpose();
        std::array<int, 3> first{0, 0, 0}, last{0, 0, 0};  // the cells holding x, per axis
        for (int a = 0; a < dim; ++a) {
            const double t = (x[a] - g.min[a]) / h[a];
            first[a] = std::clamp(static_cast<int>(std::floor(t - kInside)), 0, g.cells[a] - 1);
            last[a] = std::clamp(static_cast<int>(std::floor(t + kInside)), 0, g.cells[a] - 1);
        }
        for (int k = first[2]; k <= last[2]; ++k)
            for (int j = first[1]; j <= last[1]; ++j)
                for (int i = first[0]; i <= last[0]; ++i) {
                    const Index cell = i + static_cast<Index>(g.cells[0]) * (j + g.cells[1] * k);
                    for (Index e = per_cell * cell; e < per_cell * (cell + 1); ++e) {
                        const Eigen::VectorXd l = mesh::barycentric_coordinates(grid, e, x);
                        if (l.minCoeff() >= -kInside)
                            support.row(e) =
                                support.row(e).cwiseMax(l.cwiseMax(0.0).cwiseMin(1.0).transpose());
                    }
                }
    }
    return support;
}

/// The elements of `grid` whose every corner has a support of at least `min_support`, with the
/// nodes they use (mesh::element_subset).
mesh::Mesh carve(const mesh::Mesh& grid, const Matrix& support, double min_support) {
    std::vector<Index> kept;
    for (Index e = 0; e < grid.num_elements(); ++e)
        if (support.row(e).minCoeff() >= min_support) kept.push_back(e);
    return mesh::element_subset(grid, kept);
}

void verify_simplicial(const mesh::Mesh& fine) {
    CG_VERIFY(mesh::is_simplex(fine.type),
              "mra: automatic level meshes need a simplicial fine mesh (triangles or tetrahedra), "
              "got {} elements",
              mesh::element_name(fine.type));
}

void verify_levels(const mesh::Mesh& fine, int levels) {
    CG_VERIFY(levels >= 2, "mra: automatic level meshes need levels >= 2, got {}", levels);
    const int most = max_automatic_levels(fine);
    CG_VERIFY(levels <= most,
              "mra: {} levels are too many for automatic level meshes on a fine mesh of {} "
              "nodes (the coarsest level would have about {:.3g} nodes, fewer than {}): use at "
              "most {} levels or give the level meshes",
              levels, fine.num_nodes(),
              std::ldexp(static_cast<double>(fine.num_nodes()), -fine.dim() * (levels - 1)),
              fine.dim() + 1, most);
}

}  // namespace

int max_automatic_levels(const mesh::Mesh& fine) {
    const int dim = fine.dim();
    const double nodes = static_cast<double>(fine.num_nodes());
    int q = 1;
    while (q < kMaxLevels && std::ldexp(nodes, -dim * q) >= dim + 1) ++q;
    return q;
}

void validate_automatic_levels(const mesh::Mesh& fine, const Options& options) {
    verify_simplicial(fine);
    verify_levels(fine, options.levels);
    validate_level_mesh_options(options);
}

std::vector<mesh::Mesh> automatic_level_meshes(const mesh::Mesh& fine, int levels) {
    verify_simplicial(fine);
    verify_levels(fine, levels);
    const Matrix box = mesh::bounding_box(fine);
    const Eigen::VectorXi cells = coarsest_cells(box, std::ldexp(mean_spacing(fine), levels - 1));
    std::vector<mesh::Mesh> meshes(static_cast<std::size_t>(levels - 1));
    const Matrix* finer = &fine.rest_positions;
    for (int k = levels - 1; k >= 1; --k) {
        const mesh::Mesh grid = mesh::make_grid(fine.type, box.row(0).transpose(),
                                                box.row(1).transpose(), cells * (1 << (k - 1)));
        const double min_support = k == levels - 1 ? kMinCornerSupport : kNestedSupport;
        mesh::Mesh level = carve(grid, corner_support(grid, *finer), min_support);
        CG_VERIFY(level.num_nodes() > fine.dim() && level.num_nodes() < finer->rows(),
                  "mra: automatic level {} of {} has {} nodes for the {} of the next finer "
                  "level: use fewer levels or give the level meshes",
                  k, levels, level.num_nodes(), finer->rows());
        meshes[static_cast<std::size_t>(k - 1)] = std::move(level);
        finer = &meshes[static_cast<std::size_t>(k - 1)].rest_positions;
    }
    return meshes;
}

}  // namespace coarsegrain::mra
