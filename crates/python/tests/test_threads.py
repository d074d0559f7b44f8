"""The package off the main thread and out of the process: scenes and right-hand sides shared
by threads give the numbers they give alone, runs let other Python threads go on, batches
give the numbers of single runs whatever their thread count, scenes and right-hand sides
pickle (into other processes too), and Ctrl-C stops a long run."""

import _thread
import concurrent.futures
import importlib.util
import multiprocessing
import pickle
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="module")
def pendulum():
    return lagrange.load(EXAMPLES / "classics" / "double_pendulum.lag")


def final_angles(scene, theta1):
    """Where the double pendulum is at t = 3 from a start angle, and the run's length."""
    run = scene.simulate(until=3.0, set={"theta1": theta1}, tolerance=1e-10)
    return run["theta1"][-1], run["theta2"][-1], len(run["t"])


def test_a_shared_scene_and_rhs_give_the_serial_numbers_on_threads(pendulum):
    starts = np.linspace(0.5, 2.5, 12)
    serial = [final_angles(pendulum, a) for a in starts]
    with concurrent.futures.ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(lambda a: final_angles(pendulum, a), starts))
    assert threaded == serial
    # The callables too: one Rhs evaluated from four threads at once, with parameters per call.
    f = pendulum.rhs()
    states = np.random.default_rng(1).normal(size=(200, 4))

    def at(k):
        return f(0.0, states[k], p={"g": 1.0 + k % 7})

    alone = [at(k) for k in range(len(states))]
    with concurrent.futures.ThreadPoolExecutor(max_workers=4) as pool:
        shared = list(pool.map(at, range(len(states))))
    for a, b in zip(alone, shared):
        np.testing.assert_array_equal(a, b)
    # Parameters given per call were put back: the scene's own are in use.
    assert f.parameters["g"] == 9.81


def bench_module(name):
    """A script of crates/python/bench, imported: the test measures as the benchmark does."""
    path = Path(__file__).resolve().parents[1] / "bench" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


counter_rate = bench_module("threads").counting


def test_python_threads_run_while_a_scene_integrates(pendulum):
    run = lambda until: pendulum.simulate(until=until, tolerance=1e-12, output="theta1")
    run(400.0)  # compiled once, so that the timed calls only integrate
    # Long enough to measure on any machine: about half a second, however fast a run is.
    start = time.perf_counter()
    run(400.0)
    took = time.perf_counter() - start
    until = 400.0 * max(1.0, 0.5 / max(took, 1e-3))
    long_run = lambda: run(until)
    alone, _ = counter_rate(0.3)
    during, elapsed = counter_rate(during=long_run)
    assert elapsed > 0.1, "the run is too short to measure anything"
    # Holding the GIL, the call let the counter count at 5 to 16 % of its rate alone (what
    # the interpreter's switches around the call allow); released, at 74 to 85 % on two
    # loaded cores, and about half of it with one core to share.
    assert during > 0.3 * alone, (during, alone)


def test_batch_gives_the_numbers_of_single_runs_whatever_the_threads(pendulum):
    values = np.array([[a, b] for a in (0.4, 1.1, 2.0) for b in (-0.5, 0.3)])
    one = pendulum.batch(values, ["theta1", "theta2'"], until=2.0, samples=21)
    two = pendulum.batch(values, ["theta1", "theta2'"], until=2.0, samples=21, threads=2)
    for name in ("t", "theta1", "theta2"):
        np.testing.assert_array_equal(one[name], two[name])
        assert one[name].shape == (6,)
    np.testing.assert_array_equal(one.samples["theta1"], two.samples["theta1"])
    assert one.samples["theta1"].shape == (6, 21)
    np.testing.assert_allclose(one.samples_t, np.linspace(0, 2.0, 21), rtol=1e-15)
    for k, (a, b) in enumerate(values):
        run = pendulum.simulate(until=2.0, set={"theta1": a, "theta2'": b}, samples=21)
        assert one["theta1"][k] == run["theta1"][-1]
        assert one["theta2"][k] == run["theta2"][-1]
        np.testing.assert_array_equal(one.samples["theta2"][k], run["theta2"])
        np.testing.assert_array_equal(one.samples_t, run["t"])
    # The same runs from a list of dicts, and from a dict of columns.
    dicts = [{"theta1": a, "theta2'": b} for a, b in values]
    np.testing.assert_array_equal(pendulum.batch(dicts, until=2.0)["theta2"], one["theta2"])
    columns = {"theta1": values[:, 0], "theta2'": values[:, 1]}
    np.testing.assert_array_equal(pendulum.batch(columns, until=2.0)["theta2"], one["theta2"])


def test_batch_reports_stops_and_refuses_bad_values(pendulum):
    # Swinging from 0.1 the pendulum never reaches 0.2; from 0.5 it does: the stop is per run.
    simple = lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag")
    b = simple.batch({"theta": [0.1, 0.5]}, until=5.0, stop_when="theta = 0.2")
    assert b.stopped_by[0] is None and b.stopped_by[1] is not None
    assert b.t[0] == 5.0 and b.t[1] < 5.0
    np.testing.assert_allclose(b["theta"][1], 0.2, atol=1e-9)
    assert b.fault == [None, None]
    with pytest.raises(ValueError, match="no parameter or coordinate"):
        pendulum.batch({"nosuch": [1.0]}, until=1.0)
    with pytest.raises(ValueError, match="finite"):
        pendulum.batch({"g": [float("nan")]}, until=1.0)


def simulate_in_worker(scene, theta1):
    """A run in another process, of a scene that came there pickled."""
    return scene.simulate(until=1.0, set={"theta1": theta1})["theta2"][-1]


def evaluate_in_worker(f, y):
    return f(0.0, y)


def test_scenes_and_rhs_pickle_into_other_processes(pendulum):
    again = pickle.loads(pickle.dumps(pendulum))
    assert again.source == pendulum.source and again.path == pendulum.path
    np.testing.assert_array_equal(
        again.simulate(until=1.0)["theta2"], pendulum.simulate(until=1.0)["theta2"]
    )
    f = pendulum.rhs()
    f.parameters = {"g": 3.7}
    g = pickle.loads(pickle.dumps(f))
    assert g.parameters["g"] == 3.7 and g.names == f.names
    y = np.array([0.3, -0.2, 1.0, 0.5])
    np.testing.assert_array_equal(g(0.0, y), f(0.0, y))
    np.testing.assert_array_equal(g.jac(0.0, y), f.jac(0.0, y))
    # A scene loaded without the dimension check pickles so.
    loose = lagrange.loads(pendulum.source, name="loose.lag", units=False)
    assert pickle.loads(pickle.dumps(loose))._native.units is False

    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
        remote = list(pool.map(simulate_in_worker, [pendulum] * 3, [0.5, 1.0, 1.5]))
        remote_f = pool.submit(evaluate_in_worker, f, y).result()
    local = [simulate_in_worker(pendulum, a) for a in (0.5, 1.0, 1.5)]
    assert remote == local
    np.testing.assert_array_equal(remote_f, f(0.0, y))


def interrupt_after(seconds):
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    return timer


def test_ctrl_c_stops_a_long_run(pendulum):
    # A run of some minutes, stopped 0.3 s in: KeyboardInterrupt well before it would end.
    flip = lagrange.load(EXAMPLES / "classics" / "double_pendulum_flip.lag")
    many = {"a1": (-3, 3, 300), "a2": (-3, 3, 300)}  # 90,000 runs of a few milliseconds
    for long_run in (
        lambda: pendulum.simulate(until=1e6, tolerance=1e-12, output="theta1"),
        lambda: pendulum.batch({"theta1": [0.5, 1.0, 1.5]}, until=1e6, threads=2),
        lambda: flip.ensemble(many, threads=2),
    ):
        started = time.perf_counter()
        timer = interrupt_after(0.3)
        with pytest.raises(KeyboardInterrupt):
            long_run()
        timer.join()
        assert time.perf_counter() - started < 10.0
    # The scene runs again afterwards.
    assert pendulum.simulate(until=0.5)["t"][-1] == 0.5


def test_numpy_is_imported_with_the_package():
    code = "import sys, lagrange; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


def test_an_input_callable_that_calls_its_own_rhs_raises_rather_than_waiting():
    # The rhs holds its programs for the call; a law that calls the same rhs would wait for
    # itself. Another rhs of the same scene is free to call.
    cart = lagrange.load(EXAMPLES / "classics" / "inverted_pendulum_on_cart.lag", units=False)
    f, other = cart.rhs(), cart.rhs()
    y = np.zeros(len(f.names))
    with pytest.raises(RuntimeError, match="may not call the rhs it drives"):
        f(0.0, y, u={"F": lambda t, state: f(t, state, u={"F": 0.0})[-1]})
    pushed = 1.0 + other(0.0, y, u={"F": 0.0})[-1]
    through_other = f(0.0, y, u={"F": lambda t, state: 1.0 + other(t, state, u={"F": 0.0})[-1]})
    np.testing.assert_array_equal(through_other, f(0.0, y, u={"F": pushed}))
    # And the rhs works afterwards.
    np.testing.assert_array_equal(f(0.0, y, u={"F": 2.0}), other(0.0, y, u={"F": 2.0}))
