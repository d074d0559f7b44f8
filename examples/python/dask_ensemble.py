"""An ensemble over a Dask cluster: the double pendulum from a grid of starts, mapped in chunks
over the cluster's workers, gathered, and checked against the same runs on this machine alone.

A scene pickles as its text, so each worker loads (and derives) it once per chunk it is sent,
then runs the chunk with `Scene.batch`. Any Dask cluster serves: here a
`distributed.LocalCluster` of two worker processes; on a real cluster pass its scheduler's
address (`--scheduler tcp://…:8786`), or start one with dask-jobqueue or dask-kubernetes.

    python examples/python/dask_ensemble.py [--grid 30] [--chunk 100] [--scheduler ADDRESS]
"""

import argparse
import time
from pathlib import Path

import numpy as np

import lagrange

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "classics" / "double_pendulum.lag"
NAMES = ["theta1", "theta2"]


def grid(n):
    """n × n starts of the two angles, a row a run."""
    a = np.linspace(-np.pi / 2, np.pi / 2, n)
    return np.array([[t1, t2] for t1 in a for t2 in a])


def ensemble_on_dask(client, scene, values, names, chunk, **settings):
    """`scene.batch(values, names, **settings)` run on the cluster of `client`, `chunk` rows
    a task; the columns gathered back in the order of `values`."""

    # Nested, so that it travels by value: the workers need not import this file.
    def run_chunk(scene, rows):
        b = scene.batch(rows, names, **settings)
        return {name: b[name] for name in b}

    # One copy of the scene on every worker, not one inside every task.
    [shared] = client.scatter([scene], broadcast=True)
    chunks = [values[k : k + chunk] for k in range(0, len(values), chunk)]
    futures = client.map(run_chunk, [shared] * len(chunks), chunks, pure=False)
    parts = client.gather(futures)
    return {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=30, help="starts per angle")
    parser.add_argument("--chunk", type=int, default=100, help="runs per task")
    parser.add_argument("--until", type=float, default=10.0)
    parser.add_argument("--scheduler", help="a running cluster's address (default: a local one)")
    args = parser.parse_args()

    from dask.distributed import Client, LocalCluster

    scene = lagrange.load(SCENE)
    values = grid(args.grid)
    started = time.perf_counter()
    alone = scene.batch(values, NAMES, until=args.until)
    serial = time.perf_counter() - started

    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True)
        client = Client(cluster)
    with client:
        ensemble_on_dask(client, scene, values[:2], NAMES, args.chunk, until=args.until)
        started = time.perf_counter()
        spread = ensemble_on_dask(client, scene, values, NAMES, args.chunk, until=args.until)
        distributed = time.perf_counter() - started
    same = all(np.array_equal(spread[name], alone[name]) for name in alone)
    print(f"{len(values)} runs to t = {args.until}: one process {serial:.2f} s, "
          f"the cluster {distributed:.2f} s; the same numbers: {same}")
    if not same:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
