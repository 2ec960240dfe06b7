#include "coarsegrain/mesh/simplex_split.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "reference_cell.hpp"

namespace coarsegrain::mesh {

namespace {

using detail::kHexCorners;
using detail::kKuhnTets;
using detail::kQuadCorners;
using detail::kTriangles;

// Every hex face with the diagonal the Kuhn split cuts it along (both as global nodes, sorted)
// must be cut alike by the two hexes that share it.
void verify_conforming(const Mesh& mesh) {
    struct FaceCut {
        std::array<Index, 4> face;
        std::array<Index, 2> diagonal;
        Index element;
    };
    std::vector<FaceCut> cuts;
    cuts.reserve(6 * static_cast<std::size_t>(mesh.num_elements()));
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                FaceCut c{};
                int n = 0;
                for (int b = 0; b < 8; ++b)
                    if (((b >> axis) & 1) == side) c.face[n++] = mesh.elements(e, kHexCorners[b]);
                const int lo = side << axis, hi = (7 & ~(1 << axis)) | lo;
                c.diagonal = {mesh.elements(e, kHexCorners[lo]), mesh.elements(e, kHexCorners[hi])};
                std::sort(c.face.begin(), c.face.end());
                std::sort(c.diagonal.begin(), c.diagonal.end());
                c.element = e;
                cuts.push_back(c);
            }
    std::sort(cuts.begin(), cuts.end(),
              [](const FaceCut& a, const FaceCut& b) { return a.face < b.face; });
    for (std::size_t i = 1; i < cuts.size(); ++i)
        CG_VERIFY(cuts[i].face != cuts[i - 1].face || cuts[i].diagonal == cuts[i - 1].diagonal,
                  "simplex split: hexes {} and {} share a face but their local axes differ, so "
                  "the 6-tet split would cut it along different diagonals (not conforming); "
                  "give a tet mesh instead",
                  cuts[i - 1].element, cuts[i].element);
}

}  // namespace

int simplices_per_element(ElementType type) {
    return type == ElementType::Hex8 ? 6 : type == ElementType::Quad4 ? 2 : 1;
}

Mesh simplex_split(const Mesh& mesh) {
    if (is_simplex(mesh.type)) return mesh;
    const bool hex = mesh.type == ElementType::Hex8;
    if (hex) verify_conforming(mesh);
    const int per = simplices_per_element(mesh.type);
    Mesh out;
    out.type = hex ? ElementType::Tet4 : ElementType::Tri3;
    out.rest_positions = mesh.rest_positions;
    out.elements.resize(mesh.num_elements() * per, hex ? 4 : 3);
    out.material_ids.resize(mesh.num_elements() * per);
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (int s = 0; s < per; ++s) {
            const Index t = per * e + s;
            for (int a = 0; a < (hex ? 4 : 3); ++a)
                out.elements(t, a) = hex ? mesh.elements(e, kHexCorners[kKuhnTets[s][a]])
                                         : mesh.elements(e, kQuadCorners[kTriangles[s][a]]);
            out.material_ids[t] = mesh.material_ids.size() > 0 ? mesh.material_ids[e] : 0;
        }
    try {
        validate(out, "split");
    } catch (const Error& err) {
        CG_VERIFY(false, "simplex split of a {} mesh: {} (simplex s comes from element s / {})",
                  element_name(mesh.type), err.what(), per);
    }
    return out;
}

}  // namespace coarsegrain::mesh
