#include "coarsegrain/fem/assembly.hpp"

#include <omp.h>

#include <algorithm>
#include <exception>
#include <mutex>
#include <optional>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/element.hpp"
#include "element_kernels.hpp"
#include "gather.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

using detail::Skeleton;
using mesh::ElementType;

/// True when every element is a congruent, equally oriented copy of the grid cell (make_grid).
bool congruent_grid(const mesh::Mesh& mesh) {
    return mesh.grid && (mesh.type == ElementType::Quad4 || mesh.type == ElementType::Hex8);
}

/// Adds the columns of node b (local index) of element matrix K of element e.
template <class S, bool Full, class ElementMatrixType>
void add_columns(const mesh::Mesh& mesh, Skeleton& s, Index e, const ElementMatrixType& K, int b) {
    constexpr int dim = S::dim;
    constexpr int per_block = Full ? dim : 1;
    const Index vb = mesh.elements(e, b);
    const Index* adj = s.graph.adj.data() + s.graph.ptr[vb];
    const Index deg = s.graph.ptr[vb + 1] - s.graph.ptr[vb];
    const Index* outer = s.A.outerIndexPtr();
    double* values = s.A.valuePtr();
    for (int a = 0; a < S::npe; ++a) {
        const Index p =
            static_cast<Index>(std::lower_bound(adj, adj + deg, mesh.elements(e, a)) - adj);
        for (int j = 0; j < dim; ++j) {
            double* col = values + outer[dim * vb + j] + per_block * p;
            if constexpr (Full) {
                for (int r = 0; r < dim; ++r) col[r] += K(dim * a + r, dim * b + j);
            } else {
                col[0] += K(a, b);
            }
        }
    }
}

/// Scatters element matrices computed on the fly (compute(e)), race free.
///
/// Default scheme, owner computes: the nodes are cut into 2 x threads contiguous ranges of
/// about equal nonzeros; each range is one task that walks the elements in index order, computes
/// those with a node in its range and adds only its own nodes' columns. Writes stay inside one
/// contiguous slab of the matrix and advance with the element index, so they hit the cache;
/// an element with nodes in several ranges is computed once per range, a thin layer when the
/// numbering has locality (a 64^3 grid with 4 ranges recomputes ~1% of its elements).
/// Measured on 64^3 distorted grids, 1 thread, side by side on a busy machine: 0.97 s against
/// 2.73 s for 1.57M tets and 2.09 s against 2.40 s for 262k hexes compared with the coloured
/// scatter, whose passes over the colours (31 for the tets) each sweep the whole matrix.
///
/// Fallback when the numbering has no locality (recomputation above 25%): greedy element
/// colouring, one parallel pass per colour (elements of one colour share no node).
template <class S, bool Full, class ComputeElementMatrix>
void scatter(const mesh::Mesh& mesh, Skeleton& s, ComputeElementMatrix&& compute) {
    const Index ne = mesh.num_elements(), nv = mesh.num_nodes();
    const int threads = ne >= detail::kMinParallel ? omp_get_max_threads() : 1;
    const int parts = threads > 1 ? 2 * threads : 1;
    // first[t] = first node of range t, balanced by the adjacency count (nonzeros per column).
    std::vector<Index> first(static_cast<std::size_t>(parts) + 1, nv);
    first[0] = 0;
    for (int t = 1; t < parts; ++t) {
        const Index target =
            static_cast<Index>(static_cast<long long>(s.graph.ptr[nv]) * t / parts);
        first[t] = static_cast<Index>(
            std::lower_bound(s.graph.ptr.begin(), s.graph.ptr.end() - 1, target) -
            s.graph.ptr.begin());
    }
    const auto part_of = [&](Index v) {
        return static_cast<int>(std::upper_bound(first.begin(), first.end(), v) - first.begin()) -
               1;
    };
    // Elements computed in total by the owner scheme: one per (element, range touched).
    long long work = 0;
    if (parts > 1) {
#pragma omp parallel for schedule(static) reduction(+ : work)
        for (Index e = 0; e < ne; ++e) {
            int lo = parts, hi = -1;
            for (int a = 0; a < S::npe; ++a) {
                const int t = part_of(mesh.elements(e, a));
                lo = std::min(lo, t);
                hi = std::max(hi, t);
            }
            // Ranges are contiguous in node index, so an element spans at most hi - lo + 1.
            work += hi - lo + 1;
        }
    }
    if (work > 1.25 * static_cast<double>(ne)) {
        const detail::Colouring colouring = detail::colour_elements(mesh, s.incidence);
        for (Index c = 0; c < colouring.num_colours(); ++c) {
            const Index begin = colouring.ptr[c];
            detail::parallel_for(colouring.ptr[c + 1] - begin, [&](Index i) {
                const Index e = colouring.element[begin + i];
                const auto K = detail::for_element(e, [&] { return compute(e); });
                for (int b = 0; b < S::npe; ++b) add_columns<S, Full>(mesh, s, e, K, b);
            });
        }
        return;
    }
    std::exception_ptr error;
    std::mutex mutex;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int t = 0; t < parts; ++t) {
        try {
            const Index lo = first[t], hi = first[t + 1];
            for (Index e = 0; e < ne; ++e) {
                bool mine = false;
                for (int a = 0; a < S::npe && !mine; ++a) {
                    const Index v = mesh.elements(e, a);
                    mine = v >= lo && v < hi;
                }
                if (!mine) continue;
                const auto K = detail::for_element(e, [&] { return compute(e); });
                for (int b = 0; b < S::npe; ++b) {
                    const Index v = mesh.elements(e, b);
                    if (v >= lo && v < hi) add_columns<S, Full>(mesh, s, e, K, b);
                }
            }
        } catch (...) {
            const std::lock_guard<std::mutex> lock(mutex);
            if (!error) error = std::current_exception();
        }
    }
    if (error) std::rethrow_exception(error);
}

}  // namespace

SparseMatrix stiffness_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                              Formulation formulation) {
    detail::verify_materials(mesh, mats, "stiffness_matrix");
    verify_formulation(formulation, mesh.type);
    return kernels::dispatch(mesh.type, [&](auto shape) {
        using S = decltype(shape);
        constexpr int n = mandel_size(S::dim);
        const auto element_matrix = [formulation](const kernels::Coords<S>& X,
                                                  const kernels::Tensor<S>& C) {
            if constexpr (!S::simplex) {
                if (formulation == Formulation::Incompatible)
                    return kernels::incompatible_stiffness<S>(X, C);
            } else {
                static_cast<void>(formulation);  // simplices have one formulation
            }
            return kernels::stiffness<S>(X, C);
        };
        SparseMatrix K;
        const bool cached = congruent_grid(mesh);
        Skeleton s = detail::skeleton(mesh, true, !cached, K);
        if constexpr (!S::simplex) {
            if (cached) {
                const kernels::Coords<S> X = kernels::grid_cell<S>(*mesh.grid);
                std::vector<kernels::ElementMatrix<S>> cache;
                for (const material::Material& m : mats.table)
                    cache.push_back(element_matrix(X, m.C.topLeftCorner<n, n>()));
                detail::gather<S, true>(mesh, s, [&](Index e, int b) {
                    return cache[static_cast<std::size_t>(mats.index[e])]
                        .template middleCols<S::dim>(S::dim * b);
                });
                return K;
            }
        }
        scatter<S, true>(mesh, s, [&](Index e) {
            return element_matrix(kernels::element_coords<S>(mesh, e),
                                  mats.of(e).C.template topLeftCorner<n, n>());
        });
        return K;
    });
}

SparseMatrix mass_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                         MassType type) {
    detail::verify_materials(mesh, mats, "mass_matrix");
    return kernels::dispatch(mesh.type, [&](auto shape) {
        using S = decltype(shape);
        using Scalar = Eigen::Matrix<double, S::npe, S::npe>;
        using Weights = Eigen::Matrix<double, S::npe, 1>;
        const Index nv = mesh.num_nodes();
        SparseMatrix M;  // the one returned variable (NRVO: no copy of a large matrix)
        if (type == MassType::Lumped) {
            // Row sums of the consistent mass: m_v = sum over incident elements of rho ∫ N_v.
            std::vector<Weights> w(static_cast<std::size_t>(mesh.num_elements()));
            std::optional<Weights> cell;
            if constexpr (!S::simplex)
                if (congruent_grid(mesh))
                    cell = kernels::load_weights<S>(kernels::grid_cell<S>(*mesh.grid));
            detail::parallel_for(mesh.num_elements(), [&](Index e) {
                w[e] = mats.of(e).density * (cell ? *cell : detail::for_element(e, [&] {
                           return kernels::load_weights<S>(kernels::element_coords<S>(mesh, e));
                       }));
            });
            const detail::NodeElements inc = detail::node_elements(mesh);
            Vector diag(S::dim * nv);
#pragma omp parallel for schedule(static) if (nv >= detail::kMinParallel)
            for (Index v = 0; v < nv; ++v) {
                double m = 0;
                for (Index k = inc.ptr[v]; k < inc.ptr[v + 1]; ++k)
                    m += w[inc.element[k]][inc.local[k]];
                diag.segment<S::dim>(S::dim * v).setConstant(m);
            }
            M.resize(S::dim * nv, S::dim * nv);
            M.resizeNonZeros(S::dim * nv);
            for (Index i = 0; i < S::dim * nv; ++i) {
                M.outerIndexPtr()[i] = i;
                M.innerIndexPtr()[i] = i;
                M.valuePtr()[i] = diag[i];
            }
            M.outerIndexPtr()[S::dim * nv] = S::dim * nv;
            return M;
        }
        const bool cached = congruent_grid(mesh);
        Skeleton s = detail::skeleton(mesh, false, !cached, M);
        if constexpr (!S::simplex) {
            if (cached) {
                const Scalar cell = kernels::scalar_mass<S>(kernels::grid_cell<S>(*mesh.grid), 1.0);
                std::vector<Scalar> cache;
                for (const material::Material& m : mats.table) cache.push_back(m.density * cell);
                detail::gather<S, false>(mesh, s, [&](Index e, int b) {
                    return cache[static_cast<std::size_t>(mats.index[e])].col(b);
                });
                return M;
            }
        }
        scatter<S, false>(mesh, s, [&](Index e) {
            return kernels::scalar_mass<S>(kernels::element_coords<S>(mesh, e), mats.of(e).density);
        });
        return M;
    });
}

}  // namespace coarsegrain::fem
