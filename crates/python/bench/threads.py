"""Threads from Python: how fast a pure-Python thread counts while a scene integrates (against
its rate alone), and the double pendulum from a grid of starts run by `Scene.batch` on one and
two threads, and by `simulate` calls on a `ThreadPoolExecutor` of one and two workers. Every
figure is from this one run.

    python crates/python/bench/threads.py [--grid 20] [--until 10]
"""

import argparse
import concurrent.futures
import threading
import time
from pathlib import Path

import numpy as np

import lagrange

ROOT = Path(__file__).resolve().parents[3]


def counting(seconds=None, during=None):
    """Increments per second of a pure-Python counter on a thread of its own, counted from
    just before to just after `time.sleep(seconds)` or `during()`: what that call let the
    thread do (a call that holds the GIL lets it do nothing)."""
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    worker = threading.Thread(target=spin)
    worker.start()
    time.sleep(0.05)  # the thread is counting
    before, started = count[0], time.perf_counter()
    if during is None:
        time.sleep(seconds)
    else:
        during()
    elapsed = time.perf_counter() - started
    counted = count[0] - before
    stop.set()
    worker.join()
    return counted / elapsed, elapsed


def timed(f):
    started = time.perf_counter()
    result = f()
    return time.perf_counter() - started, result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=20)
    parser.add_argument("--until", type=float, default=10.0)
    args = parser.parse_args()
    scene = lagrange.load(ROOT / "examples" / "classics" / "double_pendulum.lag")
    long_run = lambda: scene.simulate(until=200.0, tolerance=1e-12, output="theta1")
    long_run()
    alone, _ = counting(seconds=0.5)
    during, _ = counting(during=long_run)
    print(f"a Python thread counted at {during / alone:.0%} of its rate alone during simulate")

    a = np.linspace(-np.pi / 2, np.pi / 2, args.grid)
    values = np.array([[t1, t2] for t1 in a for t2 in a])
    names = ["theta1", "theta2"]
    scene.batch(values[:2], names, until=args.until, threads=2)  # compiled for two threads
    one, b1 = timed(lambda: scene.batch(values, names, until=args.until, threads=1))
    two, b2 = timed(lambda: scene.batch(values, names, until=args.until, threads=2))
    same = all(np.array_equal(b1[k], b2[k]) for k in b1)
    print(f"batch of {len(values)} runs to t = {args.until}: 1 thread {one:.2f} s, "
          f"2 threads {two:.2f} s ({two / one:.2f} of 1), the same numbers: {same}")

    def run(row):
        return scene.simulate(until=args.until, set=dict(zip(names, row)))["theta1"][-1]

    for workers in (1, 2):
        with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
            took, _ = timed(lambda: list(pool.map(run, values)))
        print(f"simulate on a ThreadPoolExecutor of {workers}: {took:.2f} s")


if __name__ == "__main__":
    main()
