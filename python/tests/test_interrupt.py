"""Long calls release the GIL and stop on Ctrl-C."""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import coarsegrain as cg

# A call of about 4 s (the demo beam at scale 0.67, 32 x 8 x 8 hexes, the 3-level hierarchy),
# most of it in two phases of its second level: "Z and C adapted" (about half of the call, from
# 5% on) and "A" (about 40%).
SCENE = "cg.scene_from_dict(cg.demo_scene(0.67))"
METHOD = "mra-linear"


def seconds_until_interrupted(scene, call, delay):
    """Runs `call` (Python text using `scene`) in a child interpreter, sends it SIGINT `delay`
    seconds after it starts, and returns how long the call ran before KeyboardInterrupt."""
    child = textwrap.dedent(f"""
        import sys, time
        import coarsegrain as cg
        scene = {scene}
        print("start", flush=True)
        t = time.perf_counter()
        try:
            {call}
            print("finished", time.perf_counter() - t, flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.perf_counter() - t, flush=True)
    """)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    p = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True,
                         env=env)
    assert p.stdout.readline().strip() == "start"
    time.sleep(delay)
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=120)
    word, seconds = out.split()
    assert word == "interrupted", out
    return float(seconds)


def ticks_during(call):
    """Runs call() while another Python thread appends a time every 10 ms; returns the ticks
    away from the call's ends and the call's duration."""
    done = threading.Event()
    ticks = []

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.01)

    t = threading.Thread(target=count)
    start = time.perf_counter()
    t.start()
    call()
    end = time.perf_counter()
    done.set()
    t.join()
    return [x for x in ticks if start + 0.1 < x < end - 0.1], end - start


def test_ctrl_c_stops_a_long_call():
    # Ctrl-C at 8% of the call lands in "Z and C adapted", which finishes; "A" and the rest never
    # start: the call ends at about 55% of its whole time (80% leaves room for noise). Times are
    # fractions of the call measured here, so the test holds on machines of any speed.
    full = seconds_of(SCENE, lambda scene: cg.coarsen(scene, METHOD))
    seconds = seconds_until_interrupted(SCENE, f"cg.coarsen(scene, {METHOD!r})", 0.08 * full)
    assert seconds < 0.8 * full, (seconds, full)


def seconds_of(scene, call):
    """How long call(scene) takes in this process, the scene built from the Python text `scene`
    beforehand."""
    scene = eval(scene)
    t = time.perf_counter()
    call(scene)
    return time.perf_counter() - t


def test_the_gil_is_released():
    """Another Python thread runs while coarsen() computes: it counts far more often than a
    thread that only gets the GIL at the call's end would (once)."""
    scene = eval(SCENE)
    during, duration = ticks_during(lambda: cg.coarsen(scene, METHOD))
    # 10 ms sleeps over the call: at least a quarter of the possible ticks
    assert len(during) >= 0.25 * (duration - 0.2) / 0.01, (len(during), duration)


def test_threads_share_a_fine_model():
    """Two threads coarsen with one FineModel at once: the second waits for the first's fine
    solve (without holding the GIL, which the first needs to finish) and reuses it."""
    scene = cg.scene_from_dict(cg.demo_scene(0.25))
    fine = cg.build_fine_model(scene)
    results = {}

    def run(method):
        results[method] = cg.coarsen(scene, method, fine=fine)

    threads = [threading.Thread(target=run, args=(m,)) for m in ("naive", "reuss")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not any(t.is_alive() for t in threads), "deadlock"
    for method, r in results.items():
        alone = cg.coarsen(scene, method)
        # the same computation on the same data: round-off of the solvers' reductions
        for key, value in alone.errors.items():
            assert r.errors[key] == pytest.approx(value, rel=1e-9), (method, key)


# A simulate() call of about 1.6 s: the demo beam at scale 0.25 (16x4x4 hexes) corotated, nearly
# all of it the fine model's 110 steps of about 14 ms each (a few Newton iterations).
SIMULATE_SCENE = "cg.scene_from_dict(dict(cg.demo_scene(0.25), kinematics='corotational'))"


def test_ctrl_c_stops_a_simulation_between_steps():
    # Ctrl-C at 20% of the call lands in the time stepping, which stops before its next step (or
    # Newton phase), one step (under 1% of the call) later: the call ends at about 21% of its
    # whole time (half of it leaves room for noise)
    full = seconds_of(SIMULATE_SCENE, lambda scene: cg.simulate(scene))
    seconds = seconds_until_interrupted(SIMULATE_SCENE, "cg.simulate(scene)", 0.2 * full)
    assert seconds < 0.5 * full, (seconds, full)


def test_a_simulation_releases_the_gil():
    """As test_the_gil_is_released, for simulate() (the demo beam at scale 0.5, linear: about
    1.2 s, most of it the fine factorization and 110 steps)."""
    scene = cg.scene_from_dict(cg.demo_scene(0.5))
    during, duration = ticks_during(lambda: cg.simulate(scene, "effective-tensor"))
    # as test_the_gil_is_released: at least a quarter of the possible 10 ms ticks
    assert len(during) >= 0.25 * (duration - 0.2) / 0.01, (len(during), duration)
