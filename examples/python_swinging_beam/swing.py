#!/usr/bin/python3
"""The swinging beam (examples/swinging_beam) from Python: simulate() and modes() of the fine
model and of the effective tensors' coarse model, plotted from the arrays they return.

The beam, 4 x 1 x 1 of stiff and soft layers across its axis, is clamped at x = 0 and released
from rest under strong gravity; it swings down through a large rotation, corotated. The script
steps it (`coarsegrain.simulate`: the fine model, the linear fine model beside it, and the
effective tensors' coarse model carried to the fine mesh) and computes the lowest natural modes
of both models (`coarsegrain.modes`, paired by MAC). Writes into --out: swing.png (the tip's
vertical displacement over time, fine, fine linear and coarse; the coarse frequencies against
the fine ones, coloured by MAC), result.json (the run's errors and figures) and scene.json (the
scene it ran, for `coarsegrain simulate out/scene.json --method effective-tensor`).

    /usr/bin/python3 examples/python_swinging_beam/swing.py --out out/python_swing
    /usr/bin/python3 examples/python_swinging_beam/swing.py --small --out /tmp/swing
"""
import argparse
import json
import pathlib

import numpy as np

import coarsegrain as cg

HERE = pathlib.Path(__file__).resolve().parent
METHOD = "effective-tensor"


def swinging_beam(small):
    """The example's scene dict; with `small` the fine grid halved per axis (16 x 4 x 4 hexes),
    the coarse one to 4 x 1 x 1 cells and 20 steps."""
    d = json.loads((HERE.parent / "swinging_beam" / "swinging_beam.json").read_text())
    if small:
        d["mesh"]["grid"]["cells"] = [16, 4, 4]
        d["coarse"]["mesh"]["grid"]["cells"] = [4, 1, 1]
        d["dynamics"]["steps"] = 20
    return d


def plot(sim, modes, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    z = 2  # the probes' vertical component
    left.plot(sim.times, sim.fine.probes[:, 0, z], "k-", label="fine (corotated)")
    left.plot(sim.times, sim.fine_linear.probes[:, 0, z], "k:", label="fine (linear)")
    left.plot(sim.times, sim.coarse.probes[:, 0, z], "C1--",
              label=f"{METHOD} ({sim.coarse.coarse_model.num_dofs} DOFs)")
    left.set_xlabel("time")
    left.set_ylabel("tip displacement z")
    left.legend()
    c = modes.coarse
    paired = c.frequencies_hz[c.pairs]
    top = 1.05 * max(paired.max(), modes.frequencies_hz.max())
    left_edge = 0.95 * modes.frequencies_hz.min()
    right.plot([left_edge, top], [left_edge, top], "k:", lw=0.8)
    points = right.scatter(modes.frequencies_hz, paired, c=c.mac, vmin=0, vmax=1, cmap="viridis")
    fig.colorbar(points, ax=right, label="MAC of the pair")
    right.set_xlabel("fine frequency (Hz)")
    right.set_ylabel("paired coarse frequency (Hz)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="out/python_swing")
    parser.add_argument("--small", action="store_true", help="a smaller, shorter run")
    parser.add_argument("--count", type=int, default=6, help="natural modes to compare")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    d = swinging_beam(args.small)
    (out / "scene.json").write_text(json.dumps(d, indent=1))
    scene = cg.scene_from_dict(d, base_dir=out, source=str(out / "scene.json"))
    sim = cg.simulate(scene, METHOD, frames=False)  # the probes are all this plots
    modes = cg.modes(scene, METHOD, count=args.count)
    plot(sim, modes, out / "swing.png")

    tip = sim.fine.probes[:, 0, :]
    result = {
        "method": METHOD,
        "errors": sim.errors,
        "fine_linear_errors": sim.fine_linear.entry["errors"],
        "tip_lowest_z": {"fine": tip[:, 2].min(),
                         "fine_linear": sim.fine_linear.probes[:, 0, 2].min(),
                         "coarse": sim.coarse.probes[:, 0, 2].min()},
        "frequencies_hz": {"fine": modes.frequencies_hz.tolist(),
                           "coarse_paired": modes.coarse.frequencies_hz[
                               modes.coarse.pairs].tolist()},
        "mac": modes.coarse.mac.tolist(),
        "frequency_rel": modes.coarse.frequency_rel.tolist(),
        "speedup_per_frame": sim.speedup["per_frame"],
    }
    (out / "result.json").write_text(json.dumps(result, indent=1))
    e = sim.errors
    print(f"{METHOD}: trajectory error {e['trajectory_l2_rel']:.3g} (linear fine model: "
          f"{result['fine_linear_errors']['trajectory_l2_rel']:.3g}), lowest tip z "
          f"{result['tip_lowest_z']['coarse']:.3g} (fine {result['tip_lowest_z']['fine']:.3g}); "
          f"lowest frequency {result['frequencies_hz']['coarse_paired'][0]:.4g} Hz "
          f"(fine {result['frequencies_hz']['fine'][0]:.4g}, MAC {result['mac'][0]:.3f})")
    print(f"wrote {out}/swing.png, result.json and scene.json")


if __name__ == "__main__":
    main()
