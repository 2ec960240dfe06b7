"""The fine model: stiffness, mass and load as SciPy / NumPy, and its static solve."""
import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

import coarsegrain as cg
from conftest import cli_error, write_scene


@pytest.fixture(scope="module")
def beam():
    d = cg.demo_scene(0.25)  # 16 x 4 x 4 hexes on [0,4] x [0,1] x [0,1]
    return d, cg.scene_from_dict(d), cg.build_fine_model(cg.scene_from_dict(d))


def test_shapes_and_views(beam):
    _, scene, fine = beam
    n = 3 * 17 * 5 * 5
    assert fine.num_dofs == n and fine.dim == 3
    assert isinstance(fine.stiffness, scipy.sparse.csc_matrix)
    assert fine.stiffness.shape == fine.mass.shape == (n, n)
    assert fine.load.shape == (n,)
    # views of the model's storage, not copies
    assert np.shares_memory(fine.stiffness.data, fine.stiffness.data)
    assert np.shares_memory(fine.load, fine.load)
    assert not fine.load.flags.writeable and not fine.stiffness.data.flags.writeable
    np.testing.assert_array_equal(fine.nodes, scene.nodes)
    np.testing.assert_array_equal(fine.elements, scene.elements)
    assert fine.elements.shape == (16 * 4 * 4, 8) and fine.warnings == []
    assert fine.scene.source == scene.source


def test_stiffness_is_symmetric_with_rigid_motions_in_its_kernel(beam):
    _, _, fine = beam
    K = fine.stiffness
    assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
    x = fine.nodes
    translations = [np.tile(np.eye(3)[d], len(x)) for d in range(3)]
    rotation_z = np.column_stack([-x[:, 1], x[:, 0], np.zeros(len(x))]).ravel()
    for u in translations + [rotation_z]:
        # K u = 0 up to the round-off of sums of entries of size |K|
        assert abs(K @ u).max() <= 1e-10 * abs(K).max() * abs(u).max()


def test_gravity_load_is_mass_times_gravity(beam):
    """The demo's only load is gravity: f = M g with g repeated on every node (consistent mass),
    and each component block of M sums to the total mass, the sum of density x volume over the
    16 x 4 x 4 hexes of the 4 x 1 x 1 beam."""
    d, _, fine = beam
    g = np.asarray(d["loads"]["gravity"], float)
    n = fine.num_dofs // 3
    np.testing.assert_allclose(fine.mass @ np.tile(g, n), fine.load, rtol=0,
                               atol=1e-12 * abs(fine.load).max())
    total = fine.element_densities().sum() * (4 / 16) * (1 / 4) * (1 / 4)
    ex = np.tile([1.0, 0, 0], n)
    assert ex @ fine.mass @ ex == pytest.approx(total, rel=1e-12)


def test_solve_static_against_scipy(beam):
    """The static solve against SciPy's sparse LU on K restricted to the free DOFs."""
    _, _, fine = beam
    solution = cg.solve_static(fine)
    u = solution.u
    fixed = fine.dirichlet_dofs
    assert len(fixed) > 0
    np.testing.assert_array_equal(u[fixed], fine.dirichlet_values)
    free = np.setdiff1d(np.arange(fine.num_dofs), fixed)
    K = fine.stiffness.tocsr()
    rhs = fine.load[free] - K[free][:, fixed] @ fine.dirichlet_values
    reference = scipy.sparse.linalg.spsolve(K[free][:, free].tocsc(), rhs)
    # two direct solvers on a system of condition ~1e6 (stiffness contrast 1e3, 20x4 aspect):
    # they agree to ~1e-10 relative; 1e-8 leaves margin
    np.testing.assert_allclose(u[free], reference, rtol=0, atol=1e-8 * abs(reference).max())
    assert solution.strain_energy == pytest.approx(0.5 * u @ (fine.stiffness @ u), rel=1e-12)
    assert solution.displacements.shape == (fine.num_dofs // 3, 3)
    assert np.shares_memory(solution.displacements, solution.u)


def test_solve_static_with_the_iterative_fine_solver(beam):
    """solver.backend "mra-pcg" (conjugate gradients with the hierarchy's V-cycle) at a 1e-10
    residual: the scene's fine solver, equal to the direct solve to 1e-8 of its largest entry."""
    d, _, fine = beam
    direct = cg.solve_static(fine).u
    iterative = cg.solve_static(cg.build_fine_model(cg.scene_from_dict(
        dict(d, solver={"backend": "mra-pcg", "tolerance": 1e-10})))).u
    np.testing.assert_allclose(iterative, direct, rtol=0, atol=1e-8 * abs(direct).max())


def test_singular_model_raises_the_cli_message(tmp_path):
    d = cg.demo_scene(0.25)
    del d["dirichlet"]
    path = write_scene(tmp_path / "free.json", d)
    expected = cli_error("solve", path, "--out", tmp_path / "out")
    scene = cg.load_scene(str(path))
    fine = cg.build_fine_model(scene)
    with pytest.raises(cg.NotPositiveDefinite) as e:
        fine.solve_static()
    assert str(e.value) == expected
    # coarsen's fine solve fails the same way and leaves the model as it was
    nnz = fine.stiffness.nnz
    with pytest.raises(cg.NotPositiveDefinite) as e:
        cg.coarsen(scene, "naive", fine=fine)
    assert str(e.value) == expected
    assert fine.stiffness.nnz == nnz > 0 and fine.load.shape == (fine.num_dofs,)


def test_lumped_mass_when_the_scene_asks():
    d = cg.demo_scene(0.25)
    d["dynamics"]["mass"] = "lumped"
    lumped = cg.build_fine_model(cg.scene_from_dict(d)).mass
    assert lumped.nnz == lumped.shape[0]  # diagonal
    consistent = cg.build_fine_model(cg.scene_from_dict(cg.demo_scene(0.25))).mass
    # lumping keeps the row sums
    np.testing.assert_allclose(lumped.diagonal(), np.asarray(consistent.sum(axis=1)).ravel(),
                               rtol=1e-12)


def test_directional_young_of_an_isotropic_tensor(beam):
    """An isotropic tensor's directional Young's modulus is its E along every direction."""
    d, scene, fine = beam
    C = fine.element_tensors()
    for e in (0, len(C) - 1):
        E = d["materials"][str(scene.material_ids[e])]["E"]
        for direction in ([1, 0, 0], [1, 1, 0], [0.3, -2, 1]):
            assert cg.directional_young(C[e], direction) == pytest.approx(E, rel=1e-12)
    with pytest.raises(cg.Error):
        cg.directional_young(C[0], [0, 0, 0])
