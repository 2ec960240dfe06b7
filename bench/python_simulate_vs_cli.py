#!/usr/bin/python3
"""Wall-clock time of the Python module's simulate() and modes() against `coarsegrain simulate`
and `coarsegrain modes` on the same scene.

Both run one method on the demo beam (`coarsegrain demo`'s scene at --scale, default 0.5:
32 x 8 x 8 hexes, 8,019 DOFs; its "dynamics": 110 midpoint steps, every frame saved),
--repeat times each (default 3), alternating; the best time of each is kept:

- cli:            the whole `coarsegrain --quiet simulate SCENE --method M --out DIR` process,
                  which also writes the ParaView series (a VTU per saved frame and run),
                  trajectory.csv, animation_data.bin, the plots and summary.json;
- cli steps:      its summary's stepping seconds (fine and coarse per_step x steps, the fine
                  and coarse factorizations; of its last run), the part the Python call runs
                  alike;
- python:         coarsegrain.simulate(scene, M) in this process (frames kept as arrays);
- python probes:  coarsegrain.simulate(scene, M, frames=False);
- python steps:   the Python run's stepping seconds, as "cli steps";
- modes:          `coarsegrain modes SCENE --method M --count 10` against coarsegrain.modes().

Both get the same threads (OMP_NUM_THREADS if set, else all cores) and OPENBLAS_NUM_THREADS=1.

Usage:
    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_simulate_vs_cli.py \
        [--cli build/release/coarsegrain] [--method effective-tensor] [--scale 0.5] [--repeat 3]
"""
import argparse
import json
import os
import pathlib
import subprocess
import tempfile
import time

os.environ["OPENBLAS_NUM_THREADS"] = "1"
import coarsegrain as cg  # noqa: E402  (after the environment it reads)


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def main():
    root = pathlib.Path(__file__).resolve().parents[1]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cli", default=str(root / "build" / "release" / "coarsegrain"))
    parser.add_argument("--method", default="effective-tensor")
    parser.add_argument("--scale", type=float, default=0.5)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    env = dict(os.environ, COARSEGRAIN_SCRIPTS=str(root / "scripts"))

    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        path = tmp / "scene.json"
        path.write_text(json.dumps(cg.demo_scene(args.scale)))
        scene = cg.load_scene(str(path))

        def cli(command, *extra):
            out = tmp / command
            subprocess.run([args.cli, "--quiet", command, str(path), "--method", args.method,
                            "--out", str(out), *extra], check=True, env=env,
                           stdout=subprocess.DEVNULL)
            return json.loads((out / "summary.json").read_text())

        rows = []
        t_cli, summary = best(lambda: cli("simulate"), args.repeat)
        steps = summary["dynamics"]["steps"]

        def stepping(timings):
            return (timings["fine"]["factorize"] + steps * timings["fine"]["per_step"]
                    + timings["coarse"]["factorize"] + steps * timings["coarse"]["per_step"])

        t_py, sim = best(lambda: cg.simulate(scene, args.method), args.repeat)
        t_probes, _ = best(lambda: cg.simulate(scene, args.method, frames=False), args.repeat)
        rows += [("simulate: cli", t_cli), ("simulate: cli steps", stepping(summary["timings"])),
                 ("simulate: python", t_py), ("simulate: python probes", t_probes),
                 ("simulate: python steps", stepping(sim.timings))]
        t_cli_modes, _ = best(lambda: cli("modes", "--count", "10"), args.repeat)
        t_py_modes, _ = best(lambda: cg.modes(scene, args.method, count=10), args.repeat)
        rows += [("modes: cli", t_cli_modes), ("modes: python", t_py_modes)]

    print(f"{summary['fine']['dofs']} fine DOFs, {args.method} ({sim.coarse.coarse_model.num_dofs}"
          f" DOFs), {steps} steps, {len(sim.times)} saved frames, best of {args.repeat}")
    for name, t in rows:
        print(f"  {name:26s} {t:8.3f} s")
    print(f"  python / cli: simulate {t_py / t_cli:.3f}, modes {t_py_modes / t_cli_modes:.3f}")


if __name__ == "__main__":
    main()
