"""Mistakes a Python caller makes, each refused with a message that says what was expected,
rather than a run of something else or NumPy's words: and a scene whose input drives a
constraint, which runs take though derivations cannot."""

import math
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
PENDULUM = ROOT / "examples" / "classics" / "simple_pendulum.lag"
DOUBLE = ROOT / "examples" / "classics" / "double_pendulum.lag"

SLIDING_PIVOT = """param m = 1 kg, L = 1 m, g = 9.81 m/s^2, A = 0.1 m, w = 2 rad/s
input s = 0.05 m
coord x = 0.3, y ~ -1
particle bob { mass m; position (x, y) }
gravity g
constraint rod: (x - s)^2 + y^2 = L^2
"""


def test_a_bool_is_not_a_time():
    scene = lagrange.load(PENDULUM)
    for name in ("until", "tolerance", "step", "hold"):
        with pytest.raises(TypeError, match=f"`{name}` must be a number, not True"):
            scene.simulate(**{name: True})


def test_a_grid_count_is_a_whole_number():
    scene = lagrange.load(PENDULUM)
    with pytest.raises(ValueError, match="`g` must be a whole number of values, not 2.9"):
        scene.ensemble({"g": (1, 2, 2.9)})
    with pytest.raises(ValueError, match="whole number"):
        scene.linearize(sweep={"g": (1, 2, 2.5)})
    assert len(scene.ensemble({"g": (1, 2, 3.0)})["g"]) == 3


def test_an_ensemble_range_and_thread_count_must_make_sense():
    scene = lagrange.load(PENDULUM)
    with pytest.raises(ValueError, match=r"runs 5\.\.3 are not a range of this ensemble's 3 runs"):
        scene.ensemble({"g": (1, 2, 3)}, start=5)
    with pytest.raises(ValueError, match=r"runs 3\.\.3"):
        scene.ensemble({"g": (1, 2, 3)}, start=3)
    # A chunk's end past the last run ends there, as a slice does.
    assert len(scene.ensemble({"g": (1, 2, 3)}, start=2, stop=10)["g"]) == 1
    with pytest.raises(ValueError, match="`threads` must be a positive whole number, not 0"):
        scene.ensemble({"g": (1, 2, 3)}, threads=0)
    assert len(scene.ensemble({"g": (1, 2, 3)}, start=1, stop=3)["g"]) == 2


def test_one_state_is_a_1d_array_and_many_go_to_batch():
    f = lagrange.load(PENDULUM).rhs()
    with pytest.raises(ValueError, match=r"y is one state, a 1-D array of 2 entries \(theta, theta'\).*batch"):
        f(0.0, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="1-D array"):
        f.jac(0.0, np.zeros((1, 2)))
    np.testing.assert_array_equal(f(0.0, [0.5, 0.0]), f.batch(np.array([[0.5, 0.0]]))[0])


def test_the_mass_matrix_raises_where_it_is_not_finite_as_rhs_does():
    scene = lagrange.load(DOUBLE)
    M = scene.mass_matrix_function()
    assert np.all(np.isfinite(M(0.0, [0.1, 0.2])))
    with pytest.raises(lagrange.NumericError, match="M"):
        M(0.0, [math.nan, 0.2])
    with pytest.raises(lagrange.NumericError):
        scene.rhs()(0.0, [math.nan, 0.2, 0.0, 0.0])


def test_an_input_that_drives_a_constraint_runs_as_the_command_runs_it():
    scene = lagrange.loads(SLIDING_PIVOT)
    law = {"s": "A*(1 - cos(w*t))"}
    run = scene.simulate(until=1.0, input=law, samples=3, output=["x", "y"], tolerance=1e-10)
    written = lagrange.loads(SLIDING_PIVOT.replace("input s = 0.05 m\n", "").replace(
        "(x - s)", "(x - A*(1 - cos(w*t)))"))
    by_hand = written.simulate(until=1.0, samples=3, output=["x", "y"], tolerance=1e-10)
    np.testing.assert_allclose(run["x"], by_hand["x"], atol=1e-9)
    np.testing.assert_allclose(run["y"], by_hand["y"], atol=1e-9)
    # The derivation needs the input as a symbol, which a constraint cannot differentiate.
    for call in (scene.derive, scene.check, scene.rhs):
        with pytest.raises(lagrange.SceneError, match="a constraint cannot depend on the input `s`"):
            call()
    assert "parameter `A` is never used" in scene.warnings


def test_counts_past_memory_are_refused_in_python_words():
    scene = lagrange.load(PENDULUM)
    with pytest.raises(ValueError, match=r"`samples=1000000000` would record more than 1 GiB"):
        scene.simulate(samples=10**9)
