"""The control example end to end (examples/control/cart_pole_lqr.py): A and B from
``linearize`` against the hand derivation, the LQR from python-control, and the closed loop as
lagrange simulates it against the same law integrated by SciPy on equations of motion written
here by hand, not lagrange's. python-control is needed: .ci/run installs it, and these tests
fail in CI (``CI`` set) without it, and are skipped elsewhere."""

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

ROOT = Path(__file__).resolve().parents[3]
SCRIPT = ROOT / "examples" / "control" / "cart_pole_lqr.py"

if os.environ.get("CI"):
    import control  # noqa: F401  (CI installs it; its absence there is a failure)
else:
    pytest.importorskip("control")


def example():
    spec = importlib.util.spec_from_file_location("cart_pole_lqr", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# The scene's values: cart M, uniform pole m of length L.
M, m, L, g = 1.0, 0.25, 1.0, 9.81


def hand_rhs(gain):
    """(x', theta', x'', theta'') of the closed loop, from the equations of motion by hand:
    T = (M + m)/2·x'² + m·L/2·cos θ·x'·θ' + m·L²/6·θ'², V = m·g·L/2·cos θ give
    (M + m)·x'' + m·L/2·cos θ·θ'' − m·L/2·sin θ·θ'² = F and 2·L/3·θ'' + cos θ·x'' = g·sin θ."""

    def rhs(t, y):
        x, theta, v, w = y
        force = -(gain @ y)
        s, c = np.sin(theta), np.cos(theta)
        a11, a12, a21, a22 = M + m, m * L / 2 * c, c, 2 * L / 3
        r1, r2 = force + m * L / 2 * s * w * w, g * s
        det = a11 * a22 - a12 * a21
        return [v, w, (r1 * a22 - a12 * r2) / det, (a11 * r2 - a21 * r1) / det]

    return rhs


@pytest.fixture(scope="module")
def designed():
    module = example()
    scene = module.load()
    lin, gain = module.design(scene)
    return module, scene, lin, gain


def test_a_and_b_are_the_hand_derivation(designed):
    _, _, lin, _ = designed
    Ms, ms, Ls, gs = sp.symbols("M m L g")
    den = 4 * Ms + ms
    hand_a = sp.Matrix(
        [
            [0, 0, 1, 0],
            [0, 0, 0, 1],
            [0, -3 * ms * gs / den, 0, 0],
            [0, 6 * (Ms + ms) * gs / (den * Ls), 0, 0],
        ]
    )
    hand_b = sp.Matrix([0, 0, 4 / den, -6 / (den * Ls)])
    assert lin.exact
    assert sp.simplify(lin.A_sym - hand_a) == sp.zeros(4, 4)
    assert sp.simplify(lin.B_sym - hand_b) == sp.zeros(4, 1)
    values = {Ms: M, ms: m, Ls: L, gs: g}
    np.testing.assert_allclose(lin.A, np.array(hand_a.subs(values), dtype=float), rtol=1e-14)
    np.testing.assert_allclose(lin.B, np.array(hand_b.subs(values), dtype=float), rtol=1e-14)


def test_the_lqr_gain_stabilises_the_linearization(designed):
    _, _, lin, gain = designed
    poles = np.linalg.eigvals(lin.A - lin.B @ gain[np.newaxis, :])
    assert poles.real.max() < -0.1, poles
    # Tilted towards +x, the cart is pushed that way: every gain is negative.
    assert (gain < 0).all(), gain


def test_the_closed_loop_balances_and_agrees_with_an_independent_integration(designed):
    from scipy.integrate import solve_ivp

    module, scene, _, gain = designed
    run = module.closed_loop(scene, gain)
    t = run["t"]
    ours = np.column_stack([run["x"], run["theta"], run["x'"], run["theta'"]])
    start = [0.0, 0.2, 0.0, 0.0]
    np.testing.assert_array_equal(ours[0], start)
    hand = solve_ivp(
        hand_rhs(gain), (0.0, t[-1]), start, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-12
    )
    assert hand.success
    largest = np.abs(ours - hand.y.T).max()
    print(f"largest difference from SciPy's integration: {largest:.2e}")
    assert largest < 1e-6, largest
    # The force recorded is the law's.
    np.testing.assert_allclose(run["F"], -(ours @ gain), rtol=1e-9, atol=1e-9)
    # It balances: upright and back at the origin at the end, having pushed.
    assert abs(run["theta"][-1]) < 1e-4 and abs(run["x"][-1]) < 1e-3, ours[-1]
    assert np.abs(run["F"]).max() > 1.0
    # Without the law the pole falls.
    free = scene.simulate(until=2.0, output=["theta"], samples=21)
    assert np.abs(free["theta"]).max() > 1.0
