"""Linearization along a motion from Python: the arrays stacked over the samples, A at a
sample at rest equal to ``linearize``'s, the state-transition matrix of a large swing against
whole runs started a little apart, a motion given as arrays, and what is refused."""

from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"

# Swung from 2.5 rad: A(t) changes sign over the swing.
SWING = """
param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord theta = 5/2
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
"""


def test_a_run_gives_every_samples_matrices_stacked():
    scene = lagrange.load(EXAMPLES / "control" / "cart_pole.lag")
    along = scene.linearize_along(until=0.5, samples=51)
    assert along.state == ["x", "theta", "x'", "theta'"]
    assert along.inputs == ["F"] and along.outputs == ["position", "angle"]
    assert len(along) == 51 and along.t[0] == 0.0 and along.t[-1] == 0.5
    assert along.A.shape == (51, 4, 4) and along.B.shape == (51, 4, 1)
    assert along.C.shape == (51, 2, 4) and along.D.shape == (51, 2, 1)
    assert along.transition.shape == (4, 4) and along.transition_method == "model"
    # Φ is the product of its intervals: det Φ = exp ∫ tr A dt (Liouville), to the trapezoids.
    traces = np.trace(along.A, axis1=1, axis2=2)
    integral = np.sum(np.diff(along.t) * (traces[1:] + traces[:-1]) / 2)
    assert np.linalg.det(along.transition) == pytest.approx(np.exp(integral), rel=1e-4)


def test_at_rest_it_is_the_linearization_about_the_rest():
    scene = lagrange.load(EXAMPLES / "control" / "cart_pole.lag")
    about = scene.linearize()
    # Upright at rest the cart-pole stays there: every sample is the equilibrium.
    along = scene.linearize_along(until=0.1, samples=3, set={"theta": 0})
    for k in range(3):
        assert np.array_equal(along.A[k], about.A)
        assert np.array_equal(along.B[k], about.B)


def test_the_state_transition_matrix_is_the_difference_of_whole_runs():
    scene = lagrange.loads(SWING)
    settings = dict(until=3.0, method="dop853", tolerance=1e-13)
    along = scene.linearize_along(samples=100, **settings)
    h = 1e-5

    def end(d_theta, d_omega):
        run = scene.simulate(
            output="theta, theta'",
            samples=2,
            set={"theta": 2.5 + d_theta, "theta'": d_omega},
            **settings,
        )
        return np.array([run["theta"][-1], run["theta'"][-1]])

    columns = [
        (end(h, 0) - end(-h, 0)) / (2 * h),
        (end(0, h) - end(0, -h)) / (2 * h),
    ]
    differenced = np.column_stack(columns)
    scale = np.abs(along.transition).max()
    assert np.abs(along.transition - differenced).max() < 1e-6 * scale


def test_a_motion_given_as_arrays_and_its_mistakes():
    scene = lagrange.loads(SWING)
    run = scene.simulate(until=1.0, samples=101, output="theta, theta'", tolerance=1e-12)
    states = np.column_stack([run["theta"], run["theta'"]])
    along = scene.linearize_along(run.t, states)
    assert along.transition_method == "interpolated"
    # θ'' = −g/L·sin θ: A's lower left is −g/L·cos θ at each sample.
    assert np.allclose(along.A[:, 1, 0], -9.81 * np.cos(run["theta"]), rtol=1e-14, atol=0)
    with pytest.raises(ValueError, match="does not come after"):
        scene.linearize_along(run.t[::-1], states)
    with pytest.raises(ValueError, match="one row per time"):
        scene.linearize_along(run.t, states[:-1])


def test_kept_constraints_are_taken_and_contacts_and_implicit_methods_refused():
    scene = lagrange.load(EXAMPLES / "classics" / "pendulum_cartesian.lag")
    along = scene.linearize_along(until=1.0, samples=11)
    # Every remaining coordinate, the rod kept: A at the bottom pulls a state back to it.
    assert along.state == ["x", "y", "x'", "y'"] and along.transition_method == "model"
    assert along.A.shape == (11, 4, 4)
    with pytest.raises(ValueError, match="radau is not one"):
        scene.linearize_along(until=1.0, method="radau")
    with pytest.raises(ValueError, match="does not take contacts"):
        lagrange.load(EXAMPLES / "contacts" / "bouncing_ball.lag").linearize_along()


def test_one_sample_feeds_python_control():
    control = pytest.importorskip("control")
    scene = lagrange.load(EXAMPLES / "control" / "cart_pole.lag")
    along = scene.linearize_along(until=0.5, samples=11)
    system = along.to_control(5)
    assert isinstance(system, control.StateSpace)
    assert np.array_equal(system.A, along.A[5]) and np.array_equal(system.B, along.B[5])


def test_the_examples_time_varying_lqr_holds_the_fall():
    import importlib.util

    path = EXAMPLES / "control" / "cart_pole_along.py"
    spec = importlib.util.spec_from_file_location("cart_pole_along", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    opened, held = module.main()
    # Open, the fall stretches an error of the start many times over; held, far less.
    assert opened > 10 and held < opened / 5
