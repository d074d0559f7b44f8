"""examples/python/dask_ensemble.py on a `distributed.LocalCluster` of two worker processes:
the ensemble mapped over the cluster in chunks gathers the numbers of the same runs in this
process. CI installs dask[distributed]; where it is missing locally, this skips."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import lagrange

distributed = pytest.importorskip("dask.distributed")

ROOT = Path(__file__).resolve().parents[3]


def example():
    spec = importlib.util.spec_from_file_location(
        "dask_ensemble", ROOT / "examples" / "python" / "dask_ensemble.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_dask_example_gathers_the_serial_numbers():
    ensemble = example()
    scene = lagrange.load(ensemble.SCENE)
    values = ensemble.grid(6)
    alone = scene.batch(values, ensemble.NAMES, until=2.0)
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with cluster, distributed.Client(cluster) as client:
        spread = ensemble.ensemble_on_dask(
            client, scene, values, ensemble.NAMES, chunk=7, until=2.0
        )
        # The map ran on a cluster of two worker processes.
        assert len(client.scheduler_info()["workers"]) == 2
    assert set(spread) == set(alone)
    for name in alone:
        np.testing.assert_array_equal(spread[name], alone[name])
    assert len(spread["theta1"]) == 36
