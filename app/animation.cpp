#include "animation.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"

namespace coarsegrain::app {

namespace {

const char* axis_letter(int d) { return d == 0 ? "x" : d == 1 ? "y" : "z"; }

/// The axis along which the frames move least (ties: the later axis).
int quietest_axis(const std::vector<Vector>& frames, int dim) {
    Eigen::Vector3d most = Eigen::Vector3d::Zero();
    for (const Vector& u : frames)
        for (int d = 0; d < dim; ++d)
            for (Index i = d; i < u.size(); i += dim) most[d] = std::max(most[d], std::abs(u[i]));
    int quietest = 0;
    for (int d = 1; d < dim; ++d)
        if (most[d] <= most[quietest]) quietest = d;
    return quietest;
}

double largest_magnitude(const std::vector<Vector>& frames, int dim) {
    double largest = 0;
    for (const Vector& u : frames)
        largest = std::max(
            largest,
            Eigen::Map<const Matrix>(u.data(), dim, u.size() / dim).colwise().norm().maxCoeff());
    return largest;
}

/// +1 if the plane's axes (a, b) and the dropped axis d are a cyclic order of (x, y, z), so
/// that e_a x e_b = +e_d points to the viewer; -1 otherwise.
double viewer_side(int a, int b, int d) {
    return (b - a + 3) % 3 == 1 && (d - b + 3) % 3 == 1 ? 1 : -1;
}

/// The polygons seen and their depth towards the viewer (larger is nearer): 3D the boundary
/// facets whose outward normal faces the viewer, 2D every element (all at depth 0).
void seen_polygons(const mesh::Mesh& mesh, const mesh::Boundary& boundary, const AnimationView& v,
                   std::vector<Index>& polygons, std::vector<double>& depth) {
    if (v.dim == 2) {
        polygons.resize(static_cast<std::size_t>(mesh.num_elements()));
        std::iota(polygons.begin(), polygons.end(), 0);
        depth.assign(polygons.size(), 0.0);
        return;
    }
    const double side = viewer_side(v.axes[0], v.axes[1], v.dropped);
    for (Index f = 0; f < boundary.size(); ++f) {
        if (side * boundary.normals(f, v.dropped) <= 1e-6) continue;  // away or edge-on
        double centre = 0;
        for (Index j = 0; j < boundary.facets.cols(); ++j)
            centre += mesh.rest_positions(boundary.facets(f, j), v.dropped);
        polygons.push_back(f);
        depth.push_back(side * centre / static_cast<double>(boundary.facets.cols()));
    }
}

/// Indices 0..n-1 sorted by increasing key (stable).
std::vector<std::size_t> order_by(const std::vector<double>& key) {
    std::vector<std::size_t> order(key.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t i, std::size_t j) { return key[i] < key[j]; });
    return order;
}

/// Fills view.points and view.faces from the polygons seen, back to front.
void choose_drawing(const mesh::Mesh& mesh, const mesh::Boundary& boundary, AnimationView& v) {
    std::vector<Index> polygons;
    std::vector<double> depth;
    seen_polygons(mesh, boundary, v, polygons, depth);
    const IndexMatrix& cells = v.dim == 3 ? boundary.facets : mesh.elements;
    const std::vector<std::size_t> order = order_by(depth);
    std::map<Index, Index> number;  // fine node -> point
    const auto point = [&](Index node) {
        const auto [it, added] = number.emplace(node, static_cast<Index>(v.points.size()));
        if (added) v.points.push_back(node);
        return it->second;
    };
    if (static_cast<Index>(polygons.size()) <= kAnimationFaces) {
        v.faces.resize(static_cast<Index>(polygons.size()), cells.cols());
        for (std::size_t k = 0; k < order.size(); ++k)
            for (Index j = 0; j < cells.cols(); ++j)
                v.faces(static_cast<Index>(k), j) = point(cells(polygons[order[k]], j));
        return;
    }
    // Points alone: the polygons' nodes back to front, every stride-th of them.
    for (const std::size_t k : order)
        for (Index j = 0; j < cells.cols(); ++j) point(cells(polygons[k], j));
    const std::size_t stride =
        (v.points.size() + kAnimationPoints - 1) / static_cast<std::size_t>(kAnimationPoints);
    std::vector<Index> kept;
    for (std::size_t i = 0; i < v.points.size(); i += stride) kept.push_back(v.points[i]);
    v.points = std::move(kept);
    v.faces.resize(0, cells.cols());
}

}  // namespace

std::vector<std::size_t> animation_frames(std::size_t saved, std::size_t max) {
    CG_VERIFY(saved > 0 && max >= 2, "animation_frames: {} saved frames, at most {} shown", saved,
              max);
    std::vector<std::size_t> shown;
    if (saved <= max) {
        shown.resize(saved);
        std::iota(shown.begin(), shown.end(), 0);
        return shown;
    }
    for (std::size_t k = 0; k < max; ++k)
        shown.push_back(static_cast<std::size_t>(
            std::llround(static_cast<double>(k) * static_cast<double>(saved - 1) /
                         static_cast<double>(max - 1))));
    return shown;
}

AnimationView animation_view(const mesh::Mesh& mesh, const mesh::Boundary& boundary,
                             const std::vector<Vector>& frames) {
    AnimationView v;
    v.dim = mesh.dim();
    CG_VERIFY(!frames.empty(), "animation: no frame to show");
    for (const Vector& u : frames)
        CG_VERIFY(u.size() == mesh.num_dofs(), "animation: a frame of {} values for {} DOFs",
                  u.size(), mesh.num_dofs());
    if (v.dim == 3) {
        v.dropped = quietest_axis(frames, 3);
        v.axes = v.dropped == 0   ? std::array<int, 2>{1, 2}
                 : v.dropped == 1 ? std::array<int, 2>{0, 2}
                                  : std::array<int, 2>{0, 1};
    }
    const Matrix box = mesh::bounding_box(mesh);
    v.body_size = (box.row(1) - box.row(0)).maxCoeff();
    v.max_displacement = largest_magnitude(frames, v.dim);
    if (v.max_displacement > 0 && v.max_displacement < 0.02 * v.body_size)
        v.scale = 0.1 * v.body_size / v.max_displacement;
    choose_drawing(mesh, boundary, v);
    return v;
}

void append_animation_frame(const AnimationView& v, const Vector& u, std::vector<float>& out) {
    for (const Index n : v.points) {
        const auto un = u.segment(static_cast<Index>(v.dim) * n, v.dim);
        out.push_back(static_cast<float>(un[v.axes[0]]));
        out.push_back(static_cast<float>(un[v.axes[1]]));
        out.push_back(static_cast<float>(un.norm()));
    }
}

void write_animation_data(const std::string& file, const std::string& scene, const mesh::Mesh& mesh,
                          const AnimationView& v, const std::vector<double>& times,
                          const std::vector<AnimationModel>& models) {
    static_assert(std::endian::native == std::endian::little,
                  "animation_data.bin is little-endian: write it byte-swapped on this machine");
    const std::size_t per_model = times.size() * v.points.size() * 3;
    nlohmann::json names = nlohmann::json::array();
    for (const AnimationModel& m : models) {
        CG_VERIFY(m.frames->size() == per_model,
                  "animation: model {} has {} values, expected {} ({} frames of {} points)", m.name,
                  m.frames->size(), per_model, times.size(), v.points.size());
        names.push_back(m.name);
    }
    const nlohmann::json header = {
        {"format", "coarsegrain-animation"},
        {"version", 1},
        {"scene", scene},
        {"dimension", v.dim},
        {"axes", {axis_letter(v.axes[0]), axis_letter(v.axes[1])}},
        {"dropped", v.dropped < 0 ? nlohmann::json() : nlohmann::json(axis_letter(v.dropped))},
        {"scale", v.scale},
        {"body_size", v.body_size},
        {"max_displacement", v.max_displacement},
        {"models", names},
        {"times", times},
        {"points", v.points.size()},
        {"faces", v.faces.rows()},
        {"face_size", v.faces.cols()},
    };
    std::vector<float> rest;
    for (const Index n : v.points)
        for (const int a : v.axes) rest.push_back(static_cast<float>(mesh.rest_positions(n, a)));
    const std::vector<std::int32_t> faces(v.faces.data(), v.faces.data() + v.faces.size());
    const auto bytes = [](std::ostream& os, const auto& values) {
        os.write(reinterpret_cast<const char*>(values.data()),
                 static_cast<std::streamsize>(values.size() * sizeof(values[0])));
    };
    io::write_atomically(file, [&](std::ostream& os) {
        os << header.dump() << '\n';
        bytes(os, rest);
        bytes(os, faces);  // IndexMatrix is row-major: face by face
        for (const AnimationModel& m : models) bytes(os, *m.frames);
    });
}

}  // namespace coarsegrain::app
