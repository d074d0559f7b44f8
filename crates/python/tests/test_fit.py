"""Fits from Python: `Scene.fit` estimates what `lagrange fit` estimates, from a DataFrame or a
dict of arrays, with measured inputs as series, and refuses bad data at its place."""

import csv
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
FITTING = ROOT / "examples" / "fitting"


def columns(path):
    """A CSV file's columns as arrays, by header."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {name: np.array([float(r[k]) for r in body]) for k, name in enumerate(header)}


def test_a_damped_pendulums_fit_is_the_command_lines():
    data = columns(FITTING / "damped_pendulum.csv")
    fit = lagrange.load(FITTING / "damped_pendulum.lag").fit(data, ["L", "c"])
    assert fit.converged and fit.names == ["L", "c"]
    for value, error, truth in zip(fit.estimates, fit.standard_errors, [1.1, 0.3]):
        assert abs(value - truth) <= 2 * error
    assert fit.covariance.shape == (2, 2) and fit.correlation[0, 0] == pytest.approx(1.0)
    assert fit.model["theta"].shape == fit.t.shape == (201,)
    assert "L = " in fit.scene and fit.values["L"] == fit.estimates[0]
    binary = os.environ.get("LAGRANGE_BIN")
    if binary is None:
        pytest.skip("LAGRANGE_BIN names no lagrange binary to compare with")
    command = [
        binary, "fit", str(FITTING / "damped_pendulum.lag"), "--data",
        str(FITTING / "damped_pendulum.csv"), "--free", "L,c", "--json",
    ]
    report = json.loads(subprocess.run(command, check=True, capture_output=True).stdout)
    estimates = [u["estimate"] for u in report["unknowns"]]
    assert estimates == pytest.approx(list(fit.estimates), rel=1e-12)


def test_a_pushed_cart_takes_its_push_as_a_series_and_its_data_as_a_dataframe():
    pandas = pytest.importorskip("pandas")
    data = pandas.DataFrame(columns(FITTING / "cart_pendulum.csv"))
    push = columns(FITTING / "push.csv")
    scene = lagrange.load(FITTING / "cart_pendulum.lag")
    fit = scene.fit(data, {"b": None, "I": 0.01}, input={"F": (push["t"], push["F"])})
    assert fit.initial[1] == 0.01
    for value, error, truth in zip(fit.estimates, fit.standard_errors, [0.8, 0.009]):
        assert abs(value - truth) <= 2 * error


def test_an_unmeasured_cell_is_nan_and_a_start_value_is_free():
    data = columns(FITTING / "damped_pendulum.csv")
    data["theta"][::2] = np.nan
    fit = lagrange.load(FITTING / "damped_pendulum.lag").fit(data, "L, c, theta(0)")
    assert fit.kinds == ["parameter", "parameter", "start"]
    assert fit.rms["theta"][1] == 100


def test_bad_data_and_names_are_refused_at_their_place():
    scene = lagrange.load(FITTING / "damped_pendulum.lag")
    with pytest.raises(ValueError, match=r"(?s)the rows' times must increase.*\^"):
        scene.fit({"t": [0.0, 0.2, 0.1], "theta": [1.0, 0.9, 0.8]}, "L")
    with pytest.raises(ValueError, match=r"(?s)unknown name `thetta`.*\^"):
        scene.fit({"t": [0.0, 0.1], "thetta": [1.0, 0.9]}, "L")
    with pytest.raises(ValueError, match=r"(?s)neither a parameter nor a start value.*\^"):
        scene.fit(columns(FITTING / "damped_pendulum.csv"), "Lc")
