"""The hierarchy of the mra methods (Hierarchy, Level): the identities of Chen et al. 2019 on
its levels, and its multilevel solves against the fine solve; CoarseModel.to_fine on a batch."""
import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

import coarsegrain as cg
from conftest import example_scene

# The exact construction: global solves (what no radius gives on these small models), no
# truncation, no invariance correction; the wavelets are then A-orthogonal to the basis (Eq. 12)
# and the multilevel solve is the fine solve.
EXACT = {"truncation": 0, "invariance": False}


def square(levels=3):
    """Chen 2019 Fig. 2's checkerboard square, 32x32 quads, contrast 2000."""
    d = example_scene("bimaterial_square")
    d["coarse"]["levels"] = levels
    return cg.scene_from_dict(d)


def beam():
    """The demo beam at scale 0.25: 16x4x4 hexes, 3 levels."""
    return cg.scene_from_dict(cg.demo_scene(0.25))


SCENES = [("square", square), ("beam", beam)]


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.fixture(scope="module", params=SCENES, ids=[s[0] for s in SCENES])
def exact(request):
    return cg.coarsen(request.param[1](), "mra-linear", **EXACT)


def test_levels_have_the_documented_shapes(exact):
    h = exact.hierarchy
    assert h is exact.coarse_model.hierarchy  # one object: its factorizations are kept
    q = h.num_levels
    assert q == 3 and [L.k for L in h.levels] == [1, 2]
    assert h.num_fine_dofs == exact.fine_model.num_dofs
    n = [len(L.dofs) for L in h.levels] + [len(h.fine_dofs)]
    for L in h.levels:
        nk, nk1, w = n[L.k - 1], n[L.k], L.num_wavelets
        assert L.C_adapted.shape == L.C.shape == L.C_dagger.shape == (nk, nk1)
        assert L.A.shape == (nk, nk) and L.B.shape == (w, w) and L.W.shape == (w, nk1)
        # the wavelets complete the refinement: n_k + w_k = n_{k+1}
        assert nk + w == nk1
    assert h.A_fine.shape == (n[-1], n[-1])
    # the coarse model's DOFs are those of the coarsest grid
    assert exact.coarse_model.num_dofs == h.dim * np.prod(np.asarray(h.levels[0].cells) + 1)


def test_levels_satisfy_the_papers_identities(exact):
    h = exact.hierarchy
    A_next = h.A_fine
    for L in reversed(h.levels):
        C, Ct, W, Cd = L.C, L.C_adapted, L.W, L.C_dagger
        I = np.eye(C.shape[0])
        # W C^T = 0 and C† C^T = I hold exactly up to round-off (sums of a few exact products)
        assert abs(W @ C.T).max() < 1e-12 * abs(W).max() * abs(C).max()
        np.testing.assert_allclose((Cd @ C.T).toarray(), I, atol=1e-12)
        # Eq. 9: C̃ C^T = I (C̃ = C† + Z W): the round-off of Z W C^T, 1e-12 (C++ tests alike)
        np.testing.assert_allclose((Ct @ C.T).toarray(), I, atol=1e-12)
        # Eq. 12: C̃ A^{k+1} W^T = 0 relative to |C̃| |A| |W|: the round-off of the global solve
        # with B (condition number below ~1e6): 1e-10
        scale = (scipy.sparse.linalg.norm(Ct) * scipy.sparse.linalg.norm(A_next)
                 * scipy.sparse.linalg.norm(W))
        assert scipy.sparse.linalg.norm(Ct @ A_next @ W.T) < 1e-10 * scale, L.k
        # Alg. 1: B^k = W A^{k+1} W^T and A^k = C̃ A^{k+1} C̃^T (Galerkin products, round-off)
        B = W @ A_next @ W.T
        assert scipy.sparse.linalg.norm(L.B - B) < 1e-12 * scipy.sparse.linalg.norm(B), L.k
        A = Ct @ A_next @ Ct.T
        assert scipy.sparse.linalg.norm(L.A - A) < 1e-12 * scipy.sparse.linalg.norm(A), L.k
        A_next = L.A


def test_multilevel_solve_is_the_fine_solve(exact):
    h, f, u = exact.hierarchy, exact.fine_model.load, exact.fine_u
    # the hierarchy block-diagonalizes A^q: exact up to the round-off of q + 1 Cholesky solves
    # of well-conditioned blocks, 1e-9 relative (tests/mra/test_hierarchy.cpp)
    assert rel(h.solve(f), u) < 1e-9
    assert rel(h.solve_level(f, h.num_levels), u) < 1e-9
    # the coarsest single-level solve is the coarse model's solution on the fine mesh, and the
    # multilevel solve with the wavelets of no level (levels=1)
    assert rel(h.solve_level(f, 1), exact.u_fine) < 1e-9
    assert rel(h.solve(f, levels=1), exact.u_fine) < 1e-9
    # each level adds its wavelets: the error falls level by level to the fine solve
    errors = [rel(h.solve(f, levels=m), u) for m in range(1, h.num_levels + 1)]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 1e-9


def test_default_construction_is_close_to_the_fine_solve():
    """With truncation 1e-7 and the invariance correction (the defaults) the wavelets are
    A-orthogonal only up to the truncation: the multilevel solve is close, not exact."""
    r = cg.coarsen(beam(), "mra-linear")
    h = r.hierarchy
    e = rel(h.solve(r.fine_model.load), r.fine_u)
    assert 1e-12 < e < 1e-3, e


def test_basis_reconstruct_and_coarse_grain_agree(exact):
    h = exact.hierarchy
    rng = np.random.default_rng(0)
    for k in range(1, h.num_levels + 1):
        Phi = h.basis(k)
        n = len(h.levels[k - 1].dofs) if k < h.num_levels else len(h.fine_dofs)
        assert Phi.shape == (n, h.num_fine_dofs)
        v = rng.standard_normal(n)
        # the same products, formed once or level by level: round-off, 1e-12
        u = h.reconstruct(v, k)
        np.testing.assert_allclose(u, Phi.T @ v, rtol=0, atol=1e-12 * np.abs(u).max())
        g = rng.standard_normal(h.num_fine_dofs)
        gk = h.coarse_grain(g, k)
        np.testing.assert_allclose(gk, Phi @ g, rtol=0, atol=1e-12 * np.abs(gk).max())


def test_to_fine_applies_to_a_batch():
    scene = beam()
    rng = np.random.default_rng(1)
    for method in ("mra", "effective-tensor"):
        m = cg.coarsen(scene, method).coarse_model
        U = rng.standard_normal((m.num_dofs, 4))
        F = m.to_fine @ U
        assert F.shape == (m.to_fine.shape[0], 4)
        for j in range(4):
            # one column at a time: the same products
            np.testing.assert_allclose(F[:, j], m.to_fine @ U[:, j], rtol=0,
                                       atol=1e-14 * np.abs(F).max())
        assert (m.to_fine @ np.zeros((m.num_dofs, 0))).shape == (m.to_fine.shape[0], 0)
    with pytest.raises(cg.Error, match=f"expected a {m.num_dofs} x k array"):
        cg.coarsen(scene, "mra").coarse_model.to_fine @ np.ones((3, 2))


def test_hierarchy_errors():
    r = cg.coarsen(beam(), "mra")
    h = r.hierarchy
    assert cg.coarsen(beam(), "naive").hierarchy is None
    with pytest.raises(cg.Error, match="level"):
        h.level(h.num_levels)
    with pytest.raises(cg.Error, match="expected a vector of"):
        h.solve(np.ones(5))
    with pytest.raises(cg.Error):
        h.solve(r.fine_model.load, levels=h.num_levels + 1)
