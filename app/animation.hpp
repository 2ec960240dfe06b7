#pragma once
/// @file The data of `simulate`'s animation.gif: the fine mesh's visible surface in a view
/// plane, and each model's displacement on it at a subsample of the saved frames, written as
/// animation_data.bin for scripts/plot_animation.py.
#include <array>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::app {

/// The most frames the animation shows.
constexpr std::size_t kAnimationFrames = 60;
/// The most polygons a panel draws; a larger visible surface is drawn as at most
/// kAnimationPoints of its nodes.
constexpr Index kAnimationFaces = 4000;
constexpr Index kAnimationPoints = 4000;

/// The saved frames the animation shows: every one if there are at most `max`, else `max`
/// evenly spaced ones (the first and the last among them), ascending.
/// @throws Error if saved is 0 or max < 2
std::vector<std::size_t> animation_frames(std::size_t saved, std::size_t max = kAnimationFrames);

/// How the bodies are drawn: what is seen of the fine mesh, in which plane, at which scale.
struct AnimationView {
    int dim = 0;
    std::array<int, 2> axes{0, 1};  ///< the view plane's axes (increasing)
    int dropped = -1;               ///< the axis looked along in 3D; -1 in 2D
    /// The factor the displacement is drawn with: 1, unless the largest fine displacement is
    /// below 2% of the body's size (its largest extent); then the factor that makes it 10%.
    double scale = 1;
    double body_size = 0;         ///< largest extent of the rest bounding box
    double max_displacement = 0;  ///< largest fine |u| over the frames
    std::vector<Index> points;    ///< the fine nodes drawn
    /// #F by nodes per facet: polygons by position in `points`, back to front (painter's
    /// order). 3D: the boundary facets facing the viewer; 2D: every element. No rows: more
    /// than kAnimationFaces polygons would be seen, and `points` (at most kAnimationPoints of
    /// their nodes, back to front) are drawn alone.
    IndexMatrix faces;
};

/// The view of a run from its fine frames. In 2D the plane is (x, y); in 3D the axis dropped is
/// the one along which the fine run moves least (the smallest max |u_d| over nodes and frames;
/// a tie drops the later axis), and the viewer looks along it from the side where the plane's
/// axes appear right-handed (x right and z up for a dropped y).
/// @param mesh      the fine mesh
/// @param boundary  its boundary facets (3D: outward normals used to find the facing ones)
/// @param frames    fine displacements, dim * #V each, at least one
/// @throws Error if frames is empty or a frame has the wrong size
AnimationView animation_view(const mesh::Mesh& mesh, const mesh::Boundary& boundary,
                             const std::vector<Vector>& frames);

/// Appends one frame of a model to `out`: for each point of the view, its displacement along
/// the two plane axes and its |u| (the full displacement's magnitude), as float32.
void append_animation_frame(const AnimationView& view, const Vector& u, std::vector<float>& out);

/// One model's frames for the file: its name and the values append_animation_frame gave for
/// each frame shown.
struct AnimationModel {
    std::string name;
    const std::vector<float>* frames;
};

/// Writes animation_data.bin (format in scripts/plot_animation.py): one line of JSON (format,
/// version, scene, dimension, axes, dropped, scale, body_size, max_displacement, models,
/// times, points, faces, face_size), then little-endian float32 rest positions in the plane
/// (#points x 2), int32 faces, float32 frames (models x frames x points x 3).
/// @param times  the time of each frame shown
/// @throws Error if a model has the wrong number of values, or the file cannot be written
void write_animation_data(const std::string& file, const std::string& scene, const mesh::Mesh& mesh,
                          const AnimationView& view, const std::vector<double>& times,
                          const std::vector<AnimationModel>& models);

}  // namespace coarsegrain::app
