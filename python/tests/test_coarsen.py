"""coarsen() against the command-line tool: the same scene through `coarsegrain coarsen` and
through the module gives the same errors, coarse operators and tensors."""
import json

import numpy as np
import pytest
import scipy.io
import scipy.sparse

import coarsegrain as cg
from conftest import EXAMPLES, cli_error, example_scene, run_cli, write_scene

# The module and the tool run the same library functions (coarsen::solve_fine, run_method) on
# the same scene, single-threaded BLAS; what may differ is the order of OpenMP reductions and
# of the threads' sums, i.e. round-off: relative 1e-9 leaves six orders of magnitude above it
# and is far below any difference a changed computation makes (the methods' errors differ from
# one another by more than 1e-3).
RTOL = 1e-9

ERROR_KEYS = {"energy_rel", "energy_over_load", "l2_rel", "max_displacement_rel",
              "compliance_ratio", "stress_rel"}


def demo(scale=0.25, **changes):
    d = cg.demo_scene(scale)
    d.update(changes)
    return d


# (scene name, scene dict factory, method, coarse options): each runs through the tool and the
# module. The 2D checkerboard square (32x32 quads) and the demo beam at scale 0.25 (16x4x4
# hexes) keep every run under a second.
CASES = [
    ("square", lambda: example_scene("bimaterial_square"), "effective-tensor", {}),
    ("square", lambda: example_scene("bimaterial_square"), "naive", {}),
    ("square", lambda: example_scene("bimaterial_square"), "voigt", {}),
    ("square", lambda: example_scene("bimaterial_square"), "reuss", {"boundary": "mixed"}),
    ("square", lambda: example_scene("bimaterial_square"), "mra-linear", {"levels": 3}),
    ("beam", demo, "effective-tensor", {}),
    ("beam", demo, "mra-dirac", {"levels": 2}),
    ("beam-corotated", lambda: demo(kinematics="corotational"), "effective-tensor", {}),
    ("beam-warped", lambda: demo(warp="rs"), "mra-linear", {}),
    ("beam-locking", lambda: locking_demo(), "reuss", {}),
]


def locking_demo():
    """The demo beam with a nearly incompressible soft material: a locking warning."""
    d = demo()
    d["materials"]["2"]["nu"] = 0.499
    return d


def cli_run(tmp_path, scene, method, options, export=False):
    """Runs `coarsegrain coarsen` on the scene with `options` written into its coarse block;
    returns its output folder and summary."""
    scene = json.loads(json.dumps(scene))
    scene.setdefault("coarse", {}).update(options)
    path = write_scene(tmp_path / "scene.json", scene)
    out = tmp_path / "out"
    run_cli("coarsen", path, "--method", method, "--out", out, *(["--export", "inp"] if export
                                                                 else []))
    return out, json.loads((out / "summary.json").read_text())


def module_scene(tmp_path, scene):
    # relative file names (none in these scenes) would resolve against the CLI's folder
    return cg.scene_from_dict(scene, base_dir=tmp_path, source=str(tmp_path / "scene.json"))


@pytest.mark.parametrize("name,make,method,options", CASES,
                         ids=[f"{c[0]}-{c[2]}" for c in CASES])
def test_errors_equal_the_cli(tmp_path, name, make, method, options):
    scene = make()
    out, summary = cli_run(tmp_path, scene, method, options)
    result = cg.coarsen(module_scene(tmp_path, scene), method, **options)
    assert set(result.errors) == ERROR_KEYS == set(summary["errors"])
    for key in ERROR_KEYS:
        assert result.errors[key] == pytest.approx(summary["errors"][key], rel=RTOL), key
    assert result.method == method
    assert result.coarse_model.num_dofs == summary["coarse"]["dofs"]
    assert result.coarse_model.stiffness.nnz == summary["coarse"]["nonzeros"]
    assert result.strain_energy == pytest.approx(summary["strain_energy"], rel=RTOL)
    assert result.fine_strain_energy == pytest.approx(summary["fine_strain_energy"], rel=RTOL)
    model, coarse = result.coarse_model, summary["coarse"]
    assert model.method == method
    assert (model.num_nodes, model.num_elements) == (coarse["nodes"], coarse["elements"])
    assert result.fine_model.warnings == summary["warnings"]
    # the phases the module times are phases the CLI reports
    assert set(model.timings) <= set(coarse["timings"])
    assert {"factorize", "solve"} <= set(result.timings) <= set(coarse["timings"])
    assert {"assemble", "factorize", "solve"} <= set(result.fine_timings) \
        <= set(summary["fine"]["timings"])
        # the fine solution the errors are measured against is the CLI's fine solution
    fine_max = np.linalg.norm(np.reshape(result.fine_u, (-1, scene_dim(scene))), axis=1).max()
    assert fine_max == pytest.approx(summary["fine_max_displacement"], rel=RTOL)


def scene_dim(scene):
    return 2 if scene.get("dimension") == 2 else 3


def test_hierarchy_operators_equal_the_cli_export(tmp_path):
    """The hierarchy's K, M, f and to_fine against the Matrix Market files of --export inp."""
    scene = example_scene("bimaterial_square")
    out, _ = cli_run(tmp_path, scene, "mra-dirac", {"levels": 3}, export=True)
    result = cg.coarsen(module_scene(tmp_path, scene), "mra-dirac", levels=3)
    model = result.coarse_model

    def close(a, b):
        a, b = scipy.sparse.csc_matrix(a), scipy.sparse.csc_matrix(b)
        assert a.shape == b.shape
        assert abs(a - b).max() <= RTOL * abs(b).max()

    # the files hold 17 significant digits: the values themselves
    close(model.stiffness, scipy.io.mmread(str(out / "coarse_K.mtx")))
    close(model.mass, scipy.io.mmread(str(out / "coarse_M.mtx")))
    f = np.ravel(scipy.io.mmread(str(out / "coarse_f.mtx")))
    np.testing.assert_allclose(model.load, f, rtol=0, atol=RTOL * abs(f).max())
    T = scipy.io.mmread(str(out / "to_fine.mtx")).toarray()
    # the operator, applied to every coarse unit vector, is the formed map
    applied = model.to_fine @ np.eye(model.num_dofs)
    np.testing.assert_allclose(applied, T, rtol=0, atol=RTOL * abs(T).max())
    np.testing.assert_array_equal(model.to_fine.dot(result.u), model.to_fine @ result.u)
    assert model.to_fine @ np.zeros((model.num_dofs, 0)) is not None
    assert "not formed" in repr(model.to_fine)
    with pytest.raises(cg.Error, match="to_fine: expected a vector of"):
        model.to_fine @ np.zeros(model.num_dofs + 1)


def test_effective_tensors_equal_the_cli_coarse_model(tmp_path):
    """Per-element effective tensors against coarse_model.vtu, read back as a scene mesh that
    carries one tensor per element (binary VTU: the doubles themselves)."""
    scene = example_scene("bimaterial_square")
    out, _ = cli_run(tmp_path, scene, "effective-tensor", {})
    result = cg.coarsen(module_scene(tmp_path, scene), "effective-tensor")
    model = result.coarse_model
    written = cg.scene_from_dict({
        "mesh": {"file": str(out / "coarse_model.vtu")},
        "dirichlet": scene["dirichlet"],
    })
    fine_of_written = cg.build_fine_model(written)
    C = model.element_tensors()
    assert C.shape == (model.num_elements, 3, 3)
    # the file holds Voigt values; reading converts them to Mandel (a factor 2 or sqrt 2 on
    # shear entries): round-off
    np.testing.assert_allclose(fine_of_written.element_tensors(), C, rtol=1e-14,
                               atol=1e-14 * abs(C).max())
    np.testing.assert_allclose(fine_of_written.element_densities(), model.element_densities(),
                               rtol=1e-15)
    np.testing.assert_array_equal(written.elements, model.elements)
    np.testing.assert_allclose(written.nodes, model.nodes, rtol=0, atol=0)


def test_voigt_is_mandel_with_unscaled_shears():
    """element_tensors("voigt") = D⁻¹ C_mandel D⁻¹ with D = diag(1, 1, 1, √2, √2, √2)."""
    model = cg.coarsen(cg.scene_from_dict(demo()), "effective-tensor").coarse_model
    mandel, voigt = model.element_tensors(), model.element_tensors(notation="voigt")
    Dinv = np.diag([1, 1, 1, 2 ** -0.5, 2 ** -0.5, 2 ** -0.5])
    np.testing.assert_allclose(voigt, Dinv @ mandel @ Dinv, rtol=1e-14)
    with pytest.raises(cg.Error, match='notation "kelvin"'):
        model.element_tensors(notation="kelvin")


def test_coarse_model_maps_its_solution_to_the_fine_one():
    """to_fine @ u is the coarse solution on the fine DOFs (linear kinematics, no warp), both as a
    sparse matrix (effective tensors) and as an operator never formed (mra); the coarse
    solution solves the coarse system on its free DOFs."""
    scene = cg.scene_from_dict(demo())
    for method, sparse in (("effective-tensor", True), ("mra-linear", False)):
        r = cg.coarsen(scene, method, levels=2)
        model = r.coarse_model
        T = model.to_fine
        assert scipy.sparse.issparse(T) == sparse
        assert T.shape == (r.fine_model.num_dofs, model.num_dofs)
        np.testing.assert_allclose(T @ r.u, r.u_fine, rtol=0, atol=1e-12 * abs(r.u_fine).max())
        free = np.setdiff1d(np.arange(model.num_dofs), model.dirichlet_dofs)
        K = model.stiffness.toarray()
        residual = (K @ r.u - model.load)[free]
        assert abs(residual).max() <= 1e-9 * abs(model.load).max()
        np.testing.assert_array_equal(r.u[model.dirichlet_dofs], model.dirichlet_values)
        # K is symmetric; its mass symmetric positive semi-definite
        assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
        M = model.mass.toarray()
        assert abs(M - M.T).max() <= 1e-12 * abs(M).max()
        assert np.linalg.eigvalsh(M).min() >= -1e-10 * abs(M).max()


def test_options_override_the_coarse_block():
    """levels=2 as a keyword is the scene with coarse.levels 2."""
    d = demo()
    direct = cg.coarsen(cg.scene_from_dict(d), "mra-linear", levels=2)
    d["coarse"]["levels"] = 2
    written = cg.coarsen(cg.scene_from_dict(d), "mra-linear")
    assert direct.errors == written.errors
    scene = cg.scene_from_dict(demo())
    assert scene.with_coarse(levels=2).coarse_options["levels"] == 2
    assert scene.coarse_options["levels"] == 3


def test_fine_model_is_reused():
    scene = cg.scene_from_dict(demo())
    fine = cg.build_fine_model(scene)
    first = cg.coarsen(scene, "naive", fine=fine)
    again = cg.coarsen(scene, "effective-tensor", fine=fine)
    fresh = cg.coarsen(scene, "effective-tensor")
    assert first.fine_model is fine and again.fine_model is fine
    for key in ERROR_KEYS:
        assert again.errors[key] == pytest.approx(fresh.errors[key], rel=RTOL)
    other = cg.scene_from_dict(example_scene("bimaterial_square"))
    with pytest.raises(cg.Error, match="the fine model was built from another scene"):
        cg.coarsen(other, "naive", fine=fine)


def test_bad_options_raise_the_cli_message(tmp_path):
    scene = example_scene("bimaterial_square")
    bad = json.loads(json.dumps(scene))
    bad["coarse"]["levels"] = 0
    path = write_scene(tmp_path / "scene.json", bad)
    expected = cli_error("coarsen", path, "--method", "mra-linear", "--out", tmp_path / "out")
    with pytest.raises(cg.InvalidScene) as e:
        cg.coarsen(cg.load_scene(str(path)), "mra-linear")
    assert str(e.value) == expected
    # the same key as a keyword option: the same message, the scene named as given
    with pytest.raises(cg.InvalidScene, match="coarse.levels") as e:
        cg.coarsen(cg.load_scene(str(EXAMPLES / "bimaterial_square" / "bimaterial_square.json")),
                   "mra-linear", levels=0)
    assert str(e.value).split(": ", 1)[1] == expected.split(": ", 1)[1]
    with pytest.raises(cg.InvalidScene, match="unknown key"):
        cg.coarsen(cg.scene_from_dict(scene), "mra-linear", level=2)


def test_method_the_scene_cannot_run_raises_the_cli_message(tmp_path):
    scene = example_scene("bimaterial_square")
    del scene["coarse"]["mesh"]
    path = write_scene(tmp_path / "scene.json", scene)
    expected = cli_error("coarsen", path, "--method", "effective-tensor", "--out", tmp_path / "o")
    with pytest.raises(cg.InvalidScene) as e:
        cg.coarsen(cg.load_scene(str(path)), "effective-tensor")
    assert str(e.value) == expected


def test_unknown_method():
    scene = cg.scene_from_dict(demo())
    with pytest.raises(cg.Error, match="bogus"):
        cg.coarsen(scene, "bogus")
    with pytest.raises(TypeError):
        cg.coarsen(scene, ["naive", "voigt"])
    assert "effective-tensor" in cg.method_names() and "mra-dirac" in cg.method_names()


def test_methods_without_elements_have_no_tensors():
    r = cg.coarsen(cg.scene_from_dict(demo()), "mra-linear", levels=2)
    assert r.coarse_model.nodes is None and r.coarse_model.elements is None
    with pytest.raises(cg.Error, match="no elements"):
        r.coarse_model.element_tensors()
