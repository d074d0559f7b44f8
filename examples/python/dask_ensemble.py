"""An ensemble over a Dask cluster: the double pendulum's time to its first flip over a grid of
start angles (the map of docs/ensembles.md), its runs mapped in chunks over the cluster's
workers, gathered, and checked against the whole ensemble run in this process, the table
`lagrange ensemble` writes.

A scene pickles as its text, so the cluster gets it once (`client.scatter`) and each task
runs its range of the ensemble's runs with `Scene.ensemble(..., start=, stop=)`, which
derives and lowers the scene once per task. Any Dask cluster serves: here a
`distributed.LocalCluster` of two worker processes; on a real cluster pass its scheduler's
address (`--scheduler tcp://…:8786`), or start one with dask-jobqueue or dask-kubernetes.

    python examples/python/dask_ensemble.py [--grid 30] [--chunk 150] [--scheduler ADDRESS]
"""

import argparse
import time
from pathlib import Path

import numpy as np

import lagrange

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "classics" / "double_pendulum_flip.lag"
RECORD = ["t", "theta1", "theta2"]


def grid(n):
    """n × n starts of the two angles: the ensemble's `vary`."""
    return {"a1": (-3.0, 3.0, n), "a2": (-3.0, 3.0, n)}


def ensemble_on_dask(client, scene, vary, chunk, **settings):
    """`scene.ensemble(vary, **settings)` run on the cluster of `client`, `chunk` runs a task:
    its columns (name to an array, a value per run) and failures, gathered in the ensemble's
    order."""

    # Nested, so that it travels by value: the workers need not import this file.
    def run_chunk(scene, start, stop):
        table = scene.ensemble(vary, start=start, stop=stop, threads=1, **settings)
        return {name: table[name] for name in table}, table.failures

    runs = scene.ensemble(vary, stop=0, **settings).runs
    # One copy of the scene on every worker, not one inside every task.
    [shared] = client.scatter([scene], broadcast=True)
    starts = list(range(0, runs, chunk))
    stops = [min(k + chunk, runs) for k in starts]
    futures = client.map(run_chunk, [shared] * len(starts), starts, stops, pure=False)
    parts = client.gather(futures)
    columns = {name: np.concatenate([p[0][name] for p in parts]) for name in parts[0][0]}
    failures = [f for p in parts for f in p[1]]
    return columns, failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=30, help="starts per angle")
    parser.add_argument("--chunk", type=int, default=150, help="runs per task")
    parser.add_argument("--scheduler", help="a running cluster's address (default: a local one)")
    args = parser.parse_args()

    from dask.distributed import Client, LocalCluster

    scene = lagrange.load(SCENE)
    vary = grid(args.grid)
    started = time.perf_counter()
    alone = scene.ensemble(vary, record=RECORD, threads=1)
    serial = time.perf_counter() - started

    if args.scheduler:
        client = Client(args.scheduler)
    else:
        client = Client(LocalCluster(n_workers=2, threads_per_worker=1, processes=True))
    with client:
        # The workers import lagrange on their first task: not part of what is timed.
        ensemble_on_dask(client, scene, grid(2), 2, record=RECORD)
        started = time.perf_counter()
        columns, failures = ensemble_on_dask(client, scene, vary, args.chunk, record=RECORD)
        spread = time.perf_counter() - started
    same = failures == alone.failures and all(
        np.array_equal(columns[name], alone[name], equal_nan=True) for name in alone
    )
    print(f"{len(failures)} runs: one thread {serial:.2f} s, the cluster {spread:.2f} s "
          f"(chunks of {args.chunk}); the same numbers: {same}")
    if not same:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
