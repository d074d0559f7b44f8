"""examples/python/dask_ensemble.py on a `distributed.LocalCluster` of two worker processes:
the ensemble mapped over the cluster in chunks gathers the table of the whole ensemble run in
this process, and (where the `lagrange` command is built) the CSV of `lagrange ensemble`. CI
installs dask[distributed] and points LAGRANGE_BIN at its release build; where either is
missing locally, that part skips."""

import csv
import importlib.util
import io
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]


def example():
    spec = importlib.util.spec_from_file_location(
        "dask_ensemble", ROOT / "examples" / "python" / "dask_ensemble.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ENSEMBLE = example()
RECORD = ["t", "theta1", "max(theta2)"]


@pytest.fixture(scope="module")
def scene():
    return lagrange.load(ENSEMBLE.SCENE)


@pytest.fixture(scope="module")
def alone(scene):
    return scene.ensemble(ENSEMBLE.grid(6), record=RECORD, until=3.0, threads=1)


def test_the_ensemble_in_chunks_and_threads_is_the_whole_one(scene, alone):
    vary = ENSEMBLE.grid(6)
    assert alone.runs == 36 and alone.varied == ["a1", "a2"]
    assert alone.recorded == RECORD
    two = scene.ensemble(vary, record=RECORD, until=3.0, threads=2)
    parts = [scene.ensemble(vary, record=RECORD, until=3.0, start=k, stop=k + 10) for k in (0, 10, 20, 30)]
    for name in alone:
        np.testing.assert_array_equal(two[name], alone[name])
        np.testing.assert_array_equal(np.concatenate([p[name] for p in parts]), alone[name])
    np.testing.assert_allclose(alone.axes["a1"], np.linspace(-3, 3, 6), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(np.unique(alone["a1"]), np.sort(alone.axes["a1"]))
    # A run of the ensemble is the run simulate makes with its values.
    run = scene.simulate(until=3.0, set={"a1": alone["a1"][7], "a2": alone["a2"][7]})
    assert alone["t"][7] == run["t"][-1] and alone["theta1"][7] == run["theta1"][-1]
    batch = scene.batch({"a1": alone["a1"], "a2": alone["a2"]}, until=3.0)
    np.testing.assert_array_equal(batch["t"], alone["t"])


def test_the_dask_example_gathers_the_ensemble(scene, alone):
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with cluster, distributed.Client(cluster) as client:
        columns, failures = ENSEMBLE.ensemble_on_dask(
            client, scene, ENSEMBLE.grid(6), chunk=7, record=RECORD, until=3.0
        )
        # The map ran on a cluster of two worker processes.
        assert len(client.scheduler_info()["workers"]) == 2
    assert failures == alone.failures
    assert list(columns) == list(alone)
    for name in alone:
        np.testing.assert_array_equal(columns[name], alone[name])


def test_the_ensemble_is_the_table_the_command_writes(alone, tmp_path):
    binary = os.environ.get("LAGRANGE_BIN")
    if not binary or not Path(binary).is_file():
        pytest.skip("LAGRANGE_BIN names no built `lagrange` command")
    out = subprocess.run(
        [binary, "ensemble", str(ENSEMBLE.SCENE), "--vary", "a1=-3:3:6", "--vary", "a2=-3:3:6",
         "--record", ",".join(RECORD), "--until", "3", "--threads", "1"],
        capture_output=True, text=True, check=True,
    ).stdout
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == 36
    for name in alone:
        column = np.array([float(r[name]) if r[name] else np.nan for r in rows])
        np.testing.assert_array_equal(column, alone[name])
