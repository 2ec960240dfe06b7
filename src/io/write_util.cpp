#include "write_util.hpp"

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::io::detail {

void check_writable(const mesh::Mesh& mesh, const std::string& file) {
    const int npe = mesh::nodes_per_element(mesh.type);
    CG_VERIFY(mesh.rest_positions.cols() == mesh.dim(),
              "cannot write {}: a {} mesh needs {} coordinates per node, got {}", file,
              mesh::element_name(mesh.type), mesh.dim(), mesh.rest_positions.cols());
    CG_VERIFY(mesh.elements.cols() == npe, "cannot write {}: {} elements need {} nodes, got {}",
              file, mesh::element_name(mesh.type), npe, mesh.elements.cols());
    CG_VERIFY(mesh.material_ids.size() == mesh.num_elements(),
              "cannot write {}: {} material ids for {} elements", file, mesh.material_ids.size(),
              mesh.num_elements());
    if (mesh.num_elements() > 0)
        CG_VERIFY(mesh.elements.minCoeff() >= 0 && mesh.elements.maxCoeff() < mesh.num_nodes(),
                  "cannot write {}: element node indices span {}..{}, but nodes are numbered "
                  "0..{}",
                  file, mesh.elements.minCoeff(), mesh.elements.maxCoeff(), mesh.num_nodes() - 1);
}

}  // namespace coarsegrain::io::detail
