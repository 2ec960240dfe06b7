#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/intersection.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

double factorial(int d) { return d <= 1 ? 1.0 : d * factorial(d - 1); }

/// Measure of a simplex (D+1 by D corners) from the determinant of its edges, either sign.
double measure_of(const Matrix& X) {
    const int D = static_cast<int>(X.cols());
    Matrix T(D, D);
    for (int k = 0; k < D; ++k) T.col(k) = (X.row(k + 1) - X.row(0)).transpose();
    return std::abs(T.determinant()) / factorial(D);
}

/// The reference simplex: origin and the unit vectors (measure 1/D!).
Matrix unit_simplex(int D) {
    Matrix X = Matrix::Zero(D + 1, D);
    X.bottomRows(D).setIdentity();
    return X;
}

Matrix translated(const Matrix& X, const Eigen::RowVectorXd& t) { return X.rowwise() + t; }

/// A random simplex with corners in [-1, 1]^D around `centre`, of reasonable shape
/// (measure at least 2% of the unit simplex's).
Matrix random_simplex(std::mt19937& rng, int D, const Eigen::RowVectorXd& centre) {
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (;;) {
        Matrix X(D + 1, D);
        for (int k = 0; k <= D; ++k)
            for (int d = 0; d < D; ++d) X(k, d) = centre[d] + U(rng);
        if (measure_of(X) > 0.02 / factorial(D)) return X;
    }
}

/// Barycentric coordinates of p in simplex X.
Eigen::VectorXd barycentric(const Matrix& X, const Eigen::VectorXd& p) {
    const int D = static_cast<int>(X.cols());
    Matrix T(D, D);
    for (int k = 0; k < D; ++k) T.col(k) = (X.row(k + 1) - X.row(0)).transpose();
    const Eigen::VectorXd l = T.partialPivLu().solve(p - X.row(0).transpose());
    Eigen::VectorXd b(D + 1);
    b[0] = 1.0 - l.sum();
    b.tail(D) = l;
    return b;
}

/// Grid over [lo, hi] with `cells`, interior nodes moved by up to a quarter of the spacing
/// (more can invert Kuhn tets); validated, so that its elements tile the box.
mesh::Mesh jittered_grid(ElementType type, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                         const Eigen::VectorXi& cells, unsigned seed) {
    mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    test::distort_interior(m, 0.25, seed);
    mesh::validate(m, "jittered grid");
    return m;
}

/// Sums of the overlap measures per fine and per coarse element.
struct Sums {
    Eigen::VectorXd fine, coarse;
};
Sums sums(const std::vector<mesh::Overlap>& overlaps, Index nf, Index nc) {
    Sums s{Eigen::VectorXd::Zero(nf), Eigen::VectorXd::Zero(nc)};
    for (const auto& o : overlaps) {
        s.fine[o.fine] += o.measure;
        s.coarse[o.coarse] += o.measure;
    }
    return s;
}

/// Largest relative deviation of `sum` from the element measures of `m`.
double max_rel_defect(const Eigen::VectorXd& sum, const mesh::Mesh& m) {
    double worst = 0;
    for (Index e = 0; e < m.num_elements(); ++e) {
        const double ref = mesh::element_measure(m, e);
        worst = std::max(worst, std::abs(sum[e] - ref) / ref);
    }
    return worst;
}

/// Sorted by coarse, then fine, with no repeated pair and positive measures.
void expect_sorted_and_positive(const std::vector<mesh::Overlap>& overlaps) {
    for (std::size_t i = 0; i < overlaps.size(); ++i) {
        EXPECT_GT(overlaps[i].measure, 0.0);
        if (i > 0) {
            const auto& p = overlaps[i - 1];
            const auto& q = overlaps[i];
            EXPECT_TRUE(p.coarse < q.coarse || (p.coarse == q.coarse && p.fine < q.fine))
                << "pair " << i << " out of order";
        }
    }
}

const std::vector<int> kDims = {2, 3};

}  // namespace

// ---------------------------------------------------------------------------------------------
// One pair of simplices.

// A simplex with itself is its own measure: every corner lies on a clipping plane or inside,
// so nothing is clipped and the measure is the determinant's (4 ulps: the corners may be
// reordered to positive orientation before the determinant). Both orientations are accepted.
TEST(IntersectionSimplex, SelfIntersectionIsTheMeasure) {
    std::mt19937 rng(3);
    for (int D : kDims)
        for (int trial = 0; trial < 20; ++trial) {
            Matrix X = random_simplex(rng, D, Eigen::RowVectorXd::Zero(D));
            if (trial % 2) X.row(0).swap(X.row(1));  // other orientation
            EXPECT_DOUBLE_EQ(mesh::simplex_intersection_measure(X, X), measure_of(X));
        }
}

// Disjoint simplices and simplices that only touch (along a facet, an edge or a vertex) give
// exactly 0: the shared plane holds the touching corners to within the 1e-14 H tolerance.
TEST(IntersectionSimplex, DisjointAndTouchingGiveZero) {
    for (int D : kDims) {
        const Matrix T = unit_simplex(D);
        EXPECT_EQ(mesh::simplex_intersection_measure(
                      T, translated(T, Eigen::RowVectorXd::Constant(D, 1.01))),
                  0.0);
        // Mirror image across the facet x0 = 0: shares that facet.
        Matrix M = T;
        M.col(0) *= -1.0;
        EXPECT_EQ(mesh::simplex_intersection_measure(T, M), 0.0);
        // Point reflection through corner 0: shares that vertex.
        EXPECT_EQ(mesh::simplex_intersection_measure(T, -T), 0.0);
        // The neighbour across the slanted facet (sum x = 1), reflected through its centroid:
        // shares the whole facet, with a slanted plane.
        const Eigen::RowVectorXd c = Eigen::RowVectorXd::Constant(D, 1.0 / D);
        Matrix R = T;
        for (int k = 0; k <= D; ++k) R.row(k) = 2 * c - T.row(k);
        EXPECT_EQ(mesh::simplex_intersection_measure(T, R), 0.0);
        // A larger neighbour that shares part of the facet x0 = 0 only.
        Matrix N = 2.0 * T;
        N.col(0) *= -1.0;
        N = translated(
            N, Eigen::RowVectorXd::Constant(D, -0.25).cwiseProduct(Eigen::RowVectorXd::Unit(D, 1)));
        EXPECT_EQ(mesh::simplex_intersection_measure(T, N), 0.0);
    }
    // 3D: sharing only the edge from 0 to e1 (the other simplex lies in y <= 0, z <= 0).
    Matrix E = unit_simplex(3);
    E.rightCols(2) *= -1.0;
    EXPECT_EQ(mesh::simplex_intersection_measure(unit_simplex(3), E), 0.0);
}

// The unit simplex T = {x >= 0, sum x <= 1} and its translate by s: for s >= 0 the intersection
// is {x >= s, sum x <= 1}, a simplex of side 1 - sum s; for s = (a, -b, 0...) it is
// {x0 >= a, x >= 0, sum x <= min(1, 1 + a - b)}, of side 1 - max(a, b). Measure side^D / D!.
// 1e-14 relative: a few dozen floating-point operations on O(1) numbers per vertex.
TEST(IntersectionSimplex, TranslatedUnitSimplicesMatchClosedForm) {
    for (int D : kDims) {
        const Matrix T = unit_simplex(D);
        const std::vector<std::vector<double>> shifts = {
            {0.1, 0.2, 0.3}, {0.5, 0.0, 0.0}, {0.05, 0.01, 0.7}, {0.0, 0.3, 0.1}};
        for (const auto& s : shifts) {
            Eigen::RowVectorXd t(D);
            for (int d = 0; d < D; ++d) t[d] = s[d];
            const double side = 1.0 - t.sum();
            const double exact = std::pow(side, D) / factorial(D);
            EXPECT_NEAR(mesh::simplex_intersection_measure(T, translated(T, t)), exact,
                        1e-14 * exact);
            EXPECT_NEAR(mesh::simplex_intersection_measure(translated(T, -t), T), exact,
                        1e-14 * exact);
        }
        for (const auto& [a, b] :
             std::vector<std::pair<double, double>>{{0.2, 0.5}, {0.6, 0.1}, {0.3, 0.3}}) {
            Eigen::RowVectorXd t = Eigen::RowVectorXd::Zero(D);
            t[0] = a;
            t[1] = -b;
            const double exact = std::pow(1.0 - std::max(a, b), D) / factorial(D);
            EXPECT_NEAR(mesh::simplex_intersection_measure(T, translated(T, t)), exact,
                        1e-14 * exact);
        }
    }
}

// The two triangulations of the unit square: the halves below the diagonal y = x and below
// x + y = 1 meet in the triangle (0,0) (1,0) (1/2,1/2) of area 1/4; the two halves of one
// diagonal only share it.
TEST(IntersectionSimplex, HalvesOfTheSquare) {
    Matrix lower_right(3, 2), lower_left(3, 2), upper_left(3, 2);
    lower_right << 0, 0, 1, 0, 1, 1;
    lower_left << 0, 0, 1, 0, 0, 1;
    upper_left << 0, 0, 1, 1, 0, 1;
    EXPECT_NEAR(mesh::simplex_intersection_measure(lower_right, lower_left), 0.25, 1e-16);
    EXPECT_NEAR(mesh::simplex_intersection_measure(upper_left, lower_left), 0.25, 1e-16);
    EXPECT_EQ(mesh::simplex_intersection_measure(lower_right, upper_left), 0.0);
}

// A small simplex inside a large one gives the small one's measure, exactly (nothing is
// clipped), also when it shares the large one's corner and facets (coplanar faces).
TEST(IntersectionSimplex, SmallInsideLargeGivesTheSmallMeasure) {
    std::mt19937 rng(5);
    for (int D : kDims) {
        const Matrix T = unit_simplex(D);
        const Matrix S = translated(0.01 * random_simplex(rng, D, Eigen::RowVectorXd::Zero(D)),
                                    Eigen::RowVectorXd::Constant(D, 0.2));
        ASSERT_GT(barycentric(T, S.row(0).transpose()).minCoeff(), 0.0);
        EXPECT_DOUBLE_EQ(mesh::simplex_intersection_measure(T, S), measure_of(S));
        EXPECT_DOUBLE_EQ(mesh::simplex_intersection_measure(S, T), measure_of(S));
        const Matrix corner = 0.5 * T;  // shares corner 0 and D facets with T
        EXPECT_DOUBLE_EQ(mesh::simplex_intersection_measure(T, corner), measure_of(corner));
        // The corner simplex at e0 shares the slanted facet too.
        const Matrix far = translated(0.5 * T, 0.5 * Eigen::RowVectorXd::Unit(D, 0));
        EXPECT_DOUBLE_EQ(mesh::simplex_intersection_measure(far, T), measure_of(far));
    }
}

// measure(a, b) == measure(b, a) to the last bit (the smaller simplex is always the one
// clipped), and the result does not depend on the corner order (1e-14 relative: a different
// order clips in a different sequence, equal up to round-off), nor exceeds either measure.
TEST(IntersectionSimplex, SymmetricAndIndependentOfCornerOrder) {
    std::mt19937 rng(11);
    for (int D : kDims)
        for (int trial = 0; trial < 50; ++trial) {
            const Matrix A = random_simplex(rng, D, Eigen::RowVectorXd::Zero(D));
            const Matrix B = random_simplex(rng, D, Eigen::RowVectorXd::Constant(D, 0.3));
            const double m = mesh::simplex_intersection_measure(A, B);
            EXPECT_EQ(m, mesh::simplex_intersection_measure(B, A));
            Matrix Ap = A, Bp = B;
            Ap.row(0).swap(Ap.row(D));
            Bp.row(1).swap(Bp.row(2));
            Bp.row(0).swap(Bp.row(1));
            const double scale = std::min(measure_of(A), measure_of(B));
            EXPECT_NEAR(mesh::simplex_intersection_measure(Ap, Bp), m, 1e-14 * scale);
            EXPECT_LE(m, scale * (1 + 1e-14));
        }
}

// Monte Carlo: N points uniform in a (Dirichlet(1,...,1) barycentric weights), the fraction p
// inside b estimates |a ∩ b| / |a| with standard deviation sqrt(p (1 - p) / N). We ask for
// agreement within 5 standard deviations (a false alarm has probability < 1e-6 per pair; the
// seed is fixed, so the test is deterministic).
TEST(IntersectionSimplex, AgreesWithMonteCarlo) {
    std::mt19937 rng(17);
    std::exponential_distribution<double> Exp(1.0);
    constexpr int N = 100000;
    for (int D : kDims)
        for (int trial = 0; trial < 4; ++trial) {
            const Matrix A = random_simplex(rng, D, Eigen::RowVectorXd::Zero(D));
            const Matrix B = random_simplex(rng, D, Eigen::RowVectorXd::Constant(D, 0.25));
            const double m = mesh::simplex_intersection_measure(A, B);
            const double area = measure_of(A);
            int inside = 0;
            Eigen::VectorXd w(D + 1);
            for (int i = 0; i < N; ++i) {
                for (int k = 0; k <= D; ++k) w[k] = Exp(rng);
                const Eigen::VectorXd p = A.transpose() * (w / w.sum());
                inside += barycentric(B, p).minCoeff() >= 0 ? 1 : 0;
            }
            const double p = m / area;
            const double sigma = std::sqrt(std::max(p * (1 - p), 1.0 / N) / N);
            EXPECT_NEAR(static_cast<double>(inside) / N, p, 5 * sigma)
                << "D = " << D << ", trial " << trial << ", exact fraction " << p;
        }
}

TEST(IntersectionSimplex, BadInputIsRejected) {
    const Matrix T2 = unit_simplex(2), T3 = unit_simplex(3);
    test::expect_error([&] { mesh::simplex_intersection_measure(T2, T3); }, "3x2 and 4x3");
    test::expect_error([&] { mesh::simplex_intersection_measure(Matrix::Zero(4, 2), T2); },
                       "got 4x2");
    Matrix flat = T3;
    flat(3, 2) = 0.0;  // all four corners in the plane z = 0
    test::expect_error([&] { mesh::simplex_intersection_measure(T3, flat); },
                       "simplex b is degenerate");
    Matrix nan = T2;
    nan(1, 1) = std::nan("");
    test::expect_error([&] { mesh::simplex_intersection_measure(nan, T2); }, "not finite");
}

// ---------------------------------------------------------------------------------------------
// Two meshes.

class IntersectionMesh : public ::testing::TestWithParam<ElementType> {
  protected:
    int dim() const { return mesh::element_dim(GetParam()); }
    Eigen::VectorXd vec(std::initializer_list<double> v) const {
        return Eigen::Map<const Eigen::VectorXd>(v.begin(), static_cast<Eigen::Index>(v.size()))
            .head(dim());
    }
    Eigen::VectorXi cells(std::initializer_list<int> v) const {
        return Eigen::Map<const Eigen::VectorXi>(v.begin(), static_cast<Eigen::Index>(v.size()))
            .head(dim());
    }
};

// Two unrelated jittered meshes of the same box: the coarse elements partition each fine
// element and vice versa, so the overlaps of a fine element sum to its measure and those of a
// coarse element to its measure. 1e-12 relative: each sum adds O(10) measures computed to
// O(1e-15) relative of the larger element (the tolerances of the clipping are 1e-14).
// Swapping the roles builds the tree over the other mesh and must give the same pairs with
// bit-identical measures.
TEST_P(IntersectionMesh, JitteredMeshesPartitionEachOther) {
    const Eigen::VectorXd lo = vec({0.0, -0.5, 0.25}), hi = vec({1.0, 0.75, 1.0});
    const bool tri = dim() == 2;
    const mesh::Mesh fine =
        jittered_grid(GetParam(), lo, hi, tri ? cells({17, 19, 1}) : cells({7, 8, 6}), 2);
    const mesh::Mesh coarse = jittered_grid(GetParam(), lo, hi, cells({3, 4, 2}), 9);
    const auto overlaps = mesh::intersect(fine, coarse);
    expect_sorted_and_positive(overlaps);
    const Sums s = sums(overlaps, fine.num_elements(), coarse.num_elements());
    EXPECT_LT(max_rel_defect(s.fine, fine), 1e-12);
    EXPECT_LT(max_rel_defect(s.coarse, coarse), 1e-12);
    EXPECT_NEAR(s.fine.sum(), (hi - lo).prod(), 1e-12);

    const auto swapped = mesh::intersect(coarse, fine);
    ASSERT_EQ(swapped.size(), overlaps.size());
    std::vector<mesh::Overlap> back;
    for (const auto& o : swapped) back.push_back({o.coarse, o.fine, o.measure});
    std::sort(back.begin(), back.end(), [](const auto& x, const auto& y) {
        return std::tie(x.coarse, x.fine) < std::tie(y.coarse, y.fine);
    });
    for (std::size_t i = 0; i < back.size(); ++i) {
        EXPECT_EQ(back[i].fine, overlaps[i].fine);
        EXPECT_EQ(back[i].coarse, overlaps[i].coarse);
        EXPECT_EQ(back[i].measure, overlaps[i].measure);
    }
}

// A grid refined twice is nested in the coarse one (the Kuhn split refines the Kuhn split):
// every fine element lies in exactly one coarse element and only touches the others. The
// touching pairs share facets, edges and vertices exactly and must all be reported as 0, and
// each containing pair returns the fine measure unclipped (4 ulps, the determinant's).
TEST_P(IntersectionMesh, NestedGridsGiveOneOverlapPerFineElement) {
    const Eigen::VectorXd lo = vec({-1.0, 0.0, 2.0}), hi = vec({1.0, 1.5, 3.0});
    const mesh::Mesh coarse = mesh::make_grid(GetParam(), lo, hi, cells({3, 2, 2}));
    const mesh::Mesh fine = mesh::make_grid(GetParam(), lo, hi, cells({6, 4, 4}));
    const auto overlaps = mesh::intersect(fine, coarse);
    ASSERT_EQ(static_cast<Index>(overlaps.size()), fine.num_elements());
    std::vector<int> seen(static_cast<std::size_t>(fine.num_elements()), 0);
    for (const auto& o : overlaps) {
        ++seen[o.fine];
        EXPECT_DOUBLE_EQ(o.measure, mesh::element_measure(fine, o.fine));
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), fine.num_elements());
    const Sums s = sums(overlaps, fine.num_elements(), coarse.num_elements());
    EXPECT_LT(max_rel_defect(s.coarse, coarse), 1e-13);
}

// Aligned but not nested: 6 and 4 cells per axis share the planes at the ends and the middle
// (and diagonal planes in part), so many pairs touch exactly or overlap with coplanar faces.
// Tolerances as in JitteredMeshesPartitionEachOther.
TEST_P(IntersectionMesh, AlignedGridsPartitionEachOther) {
    const Eigen::VectorXd lo = vec({0.0, 0.0, 0.0}), hi = vec({1.0, 1.0, 1.0});
    const mesh::Mesh fine = mesh::make_grid(GetParam(), lo, hi, cells({6, 6, 6}));
    const mesh::Mesh coarse = mesh::make_grid(GetParam(), lo, hi, cells({4, 4, 4}));
    const auto overlaps = mesh::intersect(fine, coarse);
    expect_sorted_and_positive(overlaps);
    const Sums s = sums(overlaps, fine.num_elements(), coarse.num_elements());
    EXPECT_LT(max_rel_defect(s.fine, fine), 1e-12);
    EXPECT_LT(max_rel_defect(s.coarse, coarse), 1e-12);
}

// The bounding-box search misses no pair: all pairs, tested one by one, give exactly the
// reported overlaps (same measures to the bit) and 0 for the rest.
TEST_P(IntersectionMesh, CandidateSearchMissesNoPair) {
    const Eigen::VectorXd lo = vec({0.0, 0.0, 0.0}), hi = vec({2.0, 1.0, 1.0});
    const mesh::Mesh fine = jittered_grid(GetParam(), lo, hi, cells({6, 3, 3}), 4);
    const mesh::Mesh coarse = jittered_grid(GetParam(), lo, hi, cells({3, 2, 2}), 5);
    const auto overlaps = mesh::intersect(fine, coarse);
    std::vector<mesh::Overlap> brute;
    for (Index c = 0; c < coarse.num_elements(); ++c)
        for (Index f = 0; f < fine.num_elements(); ++f) {
            const double m = mesh::simplex_intersection_measure(fine.element_positions(f),
                                                                coarse.element_positions(c));
            if (m > 0) brute.push_back({f, c, m});
        }
    ASSERT_EQ(overlaps.size(), brute.size());
    for (std::size_t i = 0; i < brute.size(); ++i) {
        EXPECT_EQ(overlaps[i].fine, brute[i].fine);
        EXPECT_EQ(overlaps[i].coarse, brute[i].coarse);
        EXPECT_EQ(overlaps[i].measure, brute[i].measure);
    }
}

// A coarse mesh that sticks out of the fine domain Ω = [0,1]^D: each coarse element's
// overlaps sum to |𝕋_q ∩ Ω|. Known cases: one cell [0,2]^D split into D! Kuhn simplices
// {2 >= x_σ1 >= ... >= x_σD >= 0}; with Ω each becomes {1 >= x_σ1 >= ... >= 0}, of measure
// 1/D!. One cell [1/2, 3/2]^D: in local coordinates u = x - 1/2, Ω cuts each Kuhn simplex to
// {1/2 >= u_σ1 >= ... >= 0}, of measure 2^-D / D!. Fine mesh jittered; 1e-12 as above.
TEST_P(IntersectionMesh, CoarseMeshStickingOutOfTheFineDomain) {
    const int D = dim();
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(D), one = Eigen::VectorXd::Ones(D);
    const mesh::Mesh fine = jittered_grid(GetParam(), zero, one, cells({9, 8, 7}), 6);
    const Eigen::VectorXi single = Eigen::VectorXi::Ones(D);
    struct Case {
        mesh::Mesh coarse;
        double expected;
    };
    const std::vector<Case> cases = {
        {mesh::make_grid(GetParam(), zero, 2 * one, single), 1.0 / factorial(D)},
        {mesh::make_grid(GetParam(), 0.5 * one, 1.5 * one, single),
         std::pow(0.5, D) / factorial(D)}};
    for (const auto& [coarse, expected] : cases) {
        const auto overlaps = mesh::intersect(fine, coarse);
        expect_sorted_and_positive(overlaps);
        const Sums s = sums(overlaps, fine.num_elements(), coarse.num_elements());
        ASSERT_EQ(s.coarse.size(), static_cast<Index>(factorial(D)));
        for (Index c = 0; c < coarse.num_elements(); ++c)
            EXPECT_NEAR(s.coarse[c], expected, 1e-12 * expected) << "coarse element " << c;
    }
    // Covering Ω entirely, the sum over fine is each fine measure; a jittered coarse mesh of
    // the larger box [-0.3, 1.2]^D sticks out on every side.
    const mesh::Mesh cover = jittered_grid(GetParam(), -0.3 * one, 1.2 * one, cells({3, 4, 3}), 8);
    const Sums s = sums(mesh::intersect(fine, cover), fine.num_elements(), cover.num_elements());
    EXPECT_LT(max_rel_defect(s.fine, fine), 1e-12);
    EXPECT_NEAR(s.coarse.sum(), 1.0, 1e-12);
}

TEST_P(IntersectionMesh, BadInputIsRejected) {
    const Eigen::VectorXd lo = vec({0.0, 0.0, 0.0}), hi = vec({1.0, 1.0, 1.0});
    const mesh::Mesh simplices = mesh::make_grid(GetParam(), lo, hi, cells({2, 2, 2}));
    const ElementType cube_type = dim() == 2 ? ElementType::Quad4 : ElementType::Hex8;
    const mesh::Mesh cubes = mesh::make_grid(cube_type, lo, hi, cells({2, 2, 2}));
    test::expect_error([&] { mesh::intersect(cubes, simplices); },
                       "the fine mesh has " + mesh::element_name(cube_type) + " elements");
    test::expect_error([&] { mesh::intersect(simplices, cubes); },
                       "the coarse mesh has " + mesh::element_name(cube_type) + " elements");
    const ElementType other = dim() == 2 ? ElementType::Tet4 : ElementType::Tri3;
    const mesh::Mesh other_dim =
        mesh::make_grid(other, Eigen::VectorXd::Zero(5 - dim()), Eigen::VectorXd::Ones(5 - dim()),
                        Eigen::VectorXi::Ones(5 - dim()));
    test::expect_error([&] { mesh::intersect(simplices, other_dim); }, "but the coarse mesh is");
    mesh::Mesh flat = simplices;
    flat.elements(3, 1) = flat.elements(3, 0);  // a repeated node: zero measure
    test::expect_error([&] { mesh::intersect(flat, simplices); },
                       "element 3 of the fine mesh is degenerate");
    test::expect_error([&] { mesh::intersect(simplices, flat); },
                       "element 3 of the coarse mesh is degenerate");
}

INSTANTIATE_TEST_SUITE_P(Intersection, IntersectionMesh,
                         ::testing::Values(ElementType::Tri3, ElementType::Tet4),
                         [](const auto& p) { return mesh::element_name(p.param); });
