"""simulate() and modes() against the command-line tool: the same scene through `coarsegrain
simulate` / `coarsegrain modes` and through the module gives the same summary.json figures, and
the arrays the module returns hold what the summary reports."""
import json

import numpy as np
import pytest

import coarsegrain as cg
from conftest import cli_error, run_cli, write_scene

# The module and the tool run the same library functions (coarsen::simulate_models,
# modes_models) on the same scene, single-threaded BLAS; what may differ is the order of OpenMP
# reductions, i.e. round-off: relative 1e-9 (as test_coarsen.py) is six orders above it and far
# below any difference a changed computation makes. Numbers that are differences of nearly equal
# ones (a probe's component across the beam, the energy drift) are compared against the largest
# value of their series, or with an absolute 1e-12 for dimensionless ones.
RTOL = 1e-9
ATOL_DIMENSIONLESS = 1e-12

# Keys whose values are wall times or machine figures (compared by their keys only) and the keys
# of the tool's files, which the module does not write.
VOLATILE = {"timings", "speedup", "step_seconds", "peak_memory_mb"}
FILE_KEYS = {"plots", "animation_frames", "pvd", "files"}


def dynamic_demo(**changes):
    """The demo beam at scale 0.25 (16x4x4 hexes, 1275 DOFs) stepped 20 times, a frame every
    other step: every run below is under a few seconds."""
    d = cg.demo_scene(0.25)
    d["dynamics"] = {"integrator": "midpoint", "dt": 0.01, "steps": 20, "output_every": 2,
                     "start": "rest"}
    d.update(changes)
    return d


def scene_files(tmp_path, scene):
    path = write_scene(tmp_path / "scene.json", scene)
    return path, cg.scene_from_dict(scene, base_dir=tmp_path, source=str(path))


def assert_same(py, cli, path=""):
    """The module's summary equals the tool's: same keys (but the tool's file keys), the same
    values to round-off; the volatile values by their keys only."""
    if isinstance(cli, dict):
        assert set(py) == set(cli) - FILE_KEYS, (path, set(py) ^ (set(cli) - FILE_KEYS))
        for key in py:
            if key in VOLATILE:
                assert_same_keys(py[key], cli[key], f"{path}/{key}")
            else:
                assert_same(py[key], cli[key], f"{path}/{key}")
    elif isinstance(cli, list) and cli and all(isinstance(x, (int, float)) and
                                               not isinstance(x, bool) for x in cli):
        a, b = np.asarray(py, dtype=float), np.asarray(cli, dtype=float)
        assert a.shape == b.shape, path
        np.testing.assert_allclose(a, b, rtol=RTOL, atol=RTOL * np.abs(b).max(), err_msg=path)
    elif isinstance(cli, list):
        assert isinstance(py, list) and len(py) == len(cli), path
        for i, (x, y) in enumerate(zip(py, cli)):
            assert_same(x, y, f"{path}[{i}]")
    elif isinstance(cli, float):
        assert py == pytest.approx(cli, rel=RTOL, abs=ATOL_DIMENSIONLESS), path
    else:
        assert py == cli, path


def assert_same_keys(py, cli, path):
    """Timings and speedups: the tool's keys, but the phases of its files ("read" of the scene
    file; simulate's "animation", modes' "write") in the fine model's timings."""
    if not isinstance(cli, dict):
        return
    files = {"read", "animation", "write"} if "mass" in cli and "assemble" in cli else set()
    assert set(py) == set(cli) - files, (path, set(py) ^ (set(cli) - files))
    for key in py:
        assert_same_keys(py[key], cli[key], f"{path}/{key}")


CASES = [
    ("linear", dynamic_demo, "effective-tensor"),
    ("warped", lambda: dynamic_demo(warp="rs"), "mra"),
    ("corotated", lambda: dynamic_demo(kinematics="corotational"), "naive"),
    ("fine-only", dynamic_demo, None),
]


@pytest.mark.parametrize("name,make,method", CASES, ids=[c[0] for c in CASES])
def test_simulate_equals_the_cli(tmp_path, name, make, method):
    path, scene = scene_files(tmp_path, make())
    out = tmp_path / "out"
    run_cli("simulate", path, *(["--method", method] if method else []), "--out", out)
    cli = json.loads((out / "summary.json").read_text())
    sim = cg.simulate(scene, method)
    assert_same(sim.summary, cli)
    assert sim.timings == sim.summary["timings"]
    if method:
        assert sim.errors == sim.summary["errors"] and sim.speedup == sim.summary["speedup"]
        assert set(sim.errors) == {"trajectory_l2_rel", "probe_max_rel", "phase"}
        assert sim.coarse.coarse_model.num_dofs == cli["coarse"]["dofs"]
    else:
        assert sim.errors is None and sim.coarse is None
    assert (sim.fine_linear is not None) == (name == "corotated")


def test_simulate_arrays_hold_what_the_summary_reports():
    scene = cg.scene_from_dict(dynamic_demo())
    sim = cg.simulate(scene, "effective-tensor")
    fine, coarse = sim.fine_model, sim.coarse.coarse_model
    T, P = len(sim.times), len(sim.summary["probes"])
    assert T == 11 and P == 3  # 20 steps, a frame every other step and at t = 0
    np.testing.assert_array_equal(sim.times, sim.summary["times"])
    assert sim.fine.frames.shape == (T, fine.num_dofs)
    assert sim.coarse.frames.shape == (T, fine.num_dofs)
    assert sim.coarse.coarse_frames.shape == (T, coarse.num_dofs)
    assert sim.fine.probes.shape == sim.coarse.probes.shape == (T, P, 3)
    # the probe series are the very numbers of the summary
    for p, probe in enumerate(sim.summary["probes"]):
        np.testing.assert_array_equal(sim.fine.probes[:, p, :], probe["u_fine"])
        np.testing.assert_array_equal(sim.coarse.probes[:, p, :], probe["u"])
    # released from rest: the first frame is zero, and the load moves the beam
    assert not sim.fine.frames[0].any() and np.abs(sim.fine.frames[-1]).max() > 0
    # linear kinematics without a warp: the carried frames are to_fine of the coarse ones (the
    # same sparse products, batched here)
    np.testing.assert_allclose(sim.coarse.frames, (coarse.to_fine @ sim.coarse.coarse_frames.T).T,
                               rtol=1e-12, atol=1e-12 * np.abs(sim.coarse.frames).max())
    # the trajectory error of the summary, recomputed from the frames (summation order only)
    d, f = sim.coarse.frames - sim.fine.frames, sim.fine.frames
    assert np.sqrt((d ** 2).sum() / (f ** 2).sum()) == pytest.approx(
        sim.errors["trajectory_l2_rel"], rel=1e-10)
    # the Dirichlet DOFs stay at their prescribed zero in every frame
    assert not sim.fine.frames[:, fine.dirichlet_dofs].any()


def test_simulate_without_frames_keeps_the_probes():
    scene = cg.scene_from_dict(dynamic_demo())
    with_frames = cg.simulate(scene, "naive")
    without = cg.simulate(scene, "naive", frames=False)
    assert without.fine.frames is None and without.coarse.frames is None
    np.testing.assert_allclose(without.coarse.probes, with_frames.coarse.probes, rtol=RTOL,
                               atol=RTOL * np.abs(with_frames.coarse.probes).max())


def test_corotated_simulation_has_the_linear_fine_run():
    scene = cg.scene_from_dict(dynamic_demo(kinematics="corotational"))
    sim = cg.simulate(scene)
    lin = sim.fine_linear
    assert lin.entry is sim.summary["fine"]["linear"]
    assert lin.frames.shape == sim.fine.frames.shape
    d, f = lin.frames - sim.fine.frames, sim.fine.frames
    assert np.sqrt((d ** 2).sum() / (f ** 2).sum()) == pytest.approx(
        lin.entry["errors"]["trajectory_l2_rel"], rel=1e-10)


@pytest.mark.parametrize("method", ["effective-tensor", "mra"])
def test_modes_equal_the_cli(tmp_path, method):
    path, scene = scene_files(tmp_path, dynamic_demo())
    out = tmp_path / "out"
    run_cli("modes", path, "--method", method, "--count", 6, "--out", out)
    cli = json.loads((out / "summary.json").read_text())
    m = cg.modes(scene, method, count=6)
    assert_same(m.summary, cli)
    np.testing.assert_allclose(m.frequencies_hz, cli["fine"]["frequencies_hz"], rtol=RTOL)
    np.testing.assert_allclose(m.coarse.frequencies_hz, cli["coarse"]["frequencies_hz"],
                               rtol=RTOL)
    np.testing.assert_array_equal(m.coarse.pairs, cli["mac_pairs"])
    np.testing.assert_allclose(m.coarse.mac, cli["mac"], rtol=RTOL)
    np.testing.assert_allclose(m.coarse.frequency_rel, cli["errors"]["frequency_rel"],
                               rtol=RTOL)
    assert m.errors == m.summary["errors"]


def mac(a, b):
    return (a @ b) ** 2 / ((a @ a) * (b @ b))


def test_modes_are_mass_normalized_eigenpairs_paired_by_mac():
    scene = cg.scene_from_dict(dynamic_demo())
    m = cg.modes(scene, "effective-tensor", count=5)
    fine = m.fine_model
    K, M, Phi = fine.stiffness, fine.mass, m.shapes
    free = np.setdiff1d(np.arange(fine.num_dofs), fine.dirichlet_dofs)
    assert Phi.shape == (fine.num_dofs, 5) and not Phi[fine.dirichlet_dofs].any()
    # Lanczos vectors M-orthonormal to round-off of the eigensolver: 1e-8
    np.testing.assert_allclose(Phi.T @ (M @ Phi), np.eye(5), atol=1e-8)
    # residual of K φ = ω² M φ on the free DOFs, relative to |K φ|: eigenvalues converge to
    # 1e-10 relative, their vectors to about its square root
    R = (K @ Phi - (M @ Phi) * m.eigenvalues)[free]
    assert np.linalg.norm(R, axis=0).max() < 1e-5 * np.linalg.norm((K @ Phi)[free], axis=0).min()
    np.testing.assert_allclose(m.frequencies_hz, np.sqrt(m.eigenvalues) / (2 * np.pi), rtol=1e-12)
    c = m.coarse
    np.testing.assert_allclose(c.frequencies_hz, np.sqrt(c.eigenvalues) / (2 * np.pi), rtol=1e-12)
    np.testing.assert_allclose(c.shapes_fine, c.coarse_model.to_fine @ c.shapes, rtol=1e-12,
                               atol=1e-12 * np.abs(c.shapes_fine).max())
    for i in range(5):
        macs = [mac(Phi[:, i], c.shapes_fine[:, j]) for j in range(c.shapes_fine.shape[1])]
        assert c.pairs[i] == int(np.argmax(macs))
        assert c.mac[i] == pytest.approx(macs[c.pairs[i]], rel=1e-10)
        f_c = c.frequencies_hz[c.pairs[i]]
        assert c.frequency_rel[i] == pytest.approx(abs(f_c - m.frequencies_hz[i]) /
                                                   m.frequencies_hz[i], rel=1e-12)
    fine_only = cg.modes(scene, count=5)
    assert fine_only.coarse is None and fine_only.errors is None
    np.testing.assert_allclose(fine_only.frequencies_hz, m.frequencies_hz, rtol=RTOL)


def test_simulate_without_dynamics_raises_the_cli_error(tmp_path):
    d = dynamic_demo()
    del d["dynamics"]
    path, scene = scene_files(tmp_path, d)
    with pytest.raises(cg.InvalidScene) as e:
        cg.simulate(scene, "naive")
    assert str(e.value) == cli_error("simulate", path, "--method", "naive", "--out",
                                     tmp_path / "out")


@pytest.mark.parametrize("command", ["simulate", "modes"])
def test_a_method_the_scene_cannot_run_raises_the_cli_error(tmp_path, command):
    d = dynamic_demo()
    d["coarse"]["levels"] = 4  # 4 cells across: not divisible by 2^3
    path, scene = scene_files(tmp_path, d)
    with pytest.raises(cg.InvalidScene) as e:
        getattr(cg, command)(scene, "mra")
    assert str(e.value) == cli_error(command, path, "--method", "mra", "--out", tmp_path / "out")
    # the options override the coarse block: 2 levels run
    assert getattr(cg, command)(scene, "mra", levels=2).coarse is not None


def test_bad_arguments_raise():
    scene = cg.scene_from_dict(dynamic_demo())
    with pytest.raises(ValueError, match="1..1000"):
        cg.modes(scene, count=0)
    with pytest.raises(TypeError, match="one method at a time"):
        cg.simulate(scene, ["naive", "reuss"])
    with pytest.raises(cg.Error, match="unknown method"):
        cg.simulate(scene, "none-such")
