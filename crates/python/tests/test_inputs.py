"""Inputs in ``rhs``, ``rhs.jac`` and the inverse dynamics: ``u=`` as numbers, arrays per row
and callables of (t, y), against the cart-pole's equations written out here; inputs kept out
of the parameters; and ``simulate(hold=…)``, a zero-order hold of a feedback law."""

from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
CART_POLE = ROOT / "examples" / "classics" / "inverted_pendulum_on_cart.lag"
M, MASS, L, G = 2.0, 1.0, 1.0, 9.81


def law(t, y):
    """The state feedback of docs/simulating.md, which places the cart-pole's poles at −2,
    −2.5, −3 and −3.5."""
    x, theta, v, w = y
    return 10.7034 * x + 129.6334 * theta + 16.2589 * v + 38.2589 * w


LAW_TEXT = "10.7034*x + 129.6334*theta + 16.2589*x' + 38.2589*theta'"


@pytest.fixture()
def scene():
    return lagrange.load(CART_POLE, units=False)


def by_hand(y, force):
    """(ẋ, θ̇, ẍ, θ̈) from (M + m)·ẍ + m·L·cos θ·θ̈ − m·L·sin θ·θ̇² = F and
    L·θ̈ + cos θ·ẍ = g·sin θ."""
    x, theta, v, w = y
    a = np.array([[M + MASS, MASS * L * np.cos(theta)], [np.cos(theta), L]])
    b = np.array([force + MASS * L * np.sin(theta) * w**2, G * np.sin(theta)])
    return np.concatenate([[v, w], np.linalg.solve(a, b)])


def differenced(f, y, step=1e-6):
    """∂f/∂y by central differences, column by column."""
    columns = []
    for i in range(len(y)):
        e = np.zeros(len(y))
        e[i] = step
        columns.append((f(y + e) - f(y - e)) / (2 * step))
    return np.array(columns).T


def test_inputs_are_not_parameters(scene):
    f = scene.rhs()
    assert f.parameter_names == ["M", "m", "L", "g"]
    assert f.input_names == ["F"]
    assert dict(f.inputs) == {"F": 0.0}
    assert "F" not in dict(f.parameters)
    d = scene.derive()
    assert "F" not in d.parameters
    assert d.symbols["F"] not in d.parameter_values()
    with pytest.raises(KeyError, match="no parameter `F`"):
        f(0.0, f.y0, p={"F": 1.0})
    assert scene.inverse_dynamics(0.0, [0, 0], [0, 0], [0, 0]).shape == (2,)
    assert scene._inverse.parameter_names == ["M", "m", "L", "g"]


def test_rhs_takes_inputs_as_numbers_arrays_and_callables(scene):
    f = scene.rhs()
    y = np.array([0.3, 0.2, -0.4, 0.7])
    np.testing.assert_allclose(f(0.5, y, u={"F": 3.0}), by_hand(y, 3.0), rtol=1e-13, atol=1e-14)
    np.testing.assert_array_equal(f(0.5, y, u=[3.0]), f(0.5, y, u={"F": 3.0}))
    np.testing.assert_allclose(f(0.5, y), by_hand(y, 0.0), rtol=1e-13, atol=1e-14)
    seen = []

    def recorded(t, state):
        seen.append((t, list(state)))
        return law(t, state)

    np.testing.assert_array_equal(f(0.5, y, u={"F": recorded}), f(0.5, y, u={"F": law(0.5, y)}))
    assert seen == [(0.5, list(y))]
    # A batch takes one value per row.
    Y = np.array([y, 2 * y, -y])
    batch = f.batch(Y, t=0.5, u={"F": np.array([1.0, 2.0, 3.0])})
    for row, (state, force) in enumerate(zip(Y, [1.0, 2.0, 3.0])):
        np.testing.assert_array_equal(batch[row], f(0.5, state, u={"F": force}))
    np.testing.assert_array_equal(f.batch(Y, u={"F": law})[2], f(0.0, -y, u={"F": law(0, -y)}))


def test_inputs_given_wrongly_are_refused(scene):
    f = scene.rhs()
    y = f.y0
    with pytest.raises(KeyError, match="`g` is a parameter, not an input"):
        f(0.0, y, u={"g": 1.0})
    with pytest.raises(KeyError, match="no input `G`; the inputs are F"):
        f(0.0, y, u={"G": 1.0})
    with pytest.raises(TypeError, match="input `F` takes a number or a callable"):
        f(0.0, y, u={"F": "x"})
    with pytest.raises(ValueError, match="2 input values for the 1 inputs"):
        f(0.0, y, u=[1.0, 2.0])
    with pytest.raises(ValueError, match="input `F` must be finite"):
        f(0.0, y, u={"F": float("nan")})
    with pytest.raises(TypeError, match="returned 'no', not a number"):
        f(0.0, y, u={"F": lambda t, y: "no"})
    with pytest.raises(ValueError, match="input `F` has 2 values for 1 states"):
        f.batch(np.array([y]), u={"F": [1.0, 2.0]})


def test_jac_takes_inputs_and_the_chain_rule_through_a_callable(scene):
    f = scene.rhs()
    y = np.array([0.3, 0.2, -0.4, 0.7])
    held = differenced(lambda s: by_hand(s, 3.0), y)
    np.testing.assert_allclose(f.jac(0.0, y, u={"F": 3.0}), held, rtol=1e-7, atol=1e-7)
    closed = differenced(lambda s: by_hand(s, law(0.0, s)), y)
    jac = f.jac(0.0, y, u={"F": law})
    np.testing.assert_allclose(jac, closed, rtol=1e-7, atol=1e-7)
    # The feedback's gains show in the rows of the accelerations.
    assert abs(jac[2, 1] - held[2, 1]) > 10.0


def test_solve_ivp_with_a_law_meets_simulate(scene):
    from scipy.integrate import solve_ivp

    f = scene.rhs()
    span = (0.0, 3.0)
    ours = scene.simulate(until=3.0, input={"F": LAW_TEXT}, tolerance=1e-12, samples=4)
    theirs = solve_ivp(
        f, span, f.y0, method="Radau", jac=f.jac, args=(None, {"F": law}),
        rtol=1e-11, atol=1e-12, t_eval=ours.t,
    )
    assert theirs.success
    np.testing.assert_allclose(theirs.y[0], ours["x"], atol=1e-7)
    np.testing.assert_allclose(theirs.y[1], ours["theta"], atol=1e-7)
    assert abs(ours["theta"][-1]) < 0.5 * abs(ours["theta"][0])


def test_simulate_holds_a_law_between_samples(scene):
    held = scene.simulate(
        until=1.0, input={"F": LAW_TEXT}, hold=0.1, output=["x", "theta", "x'", "theta'", "F"]
    )
    t, force = held.t, held["F"]
    state = np.array([held[name] for name in ["x", "theta", "x'", "theta'"]])
    for k in range(10):
        inside = (t >= 0.1 * k - 1e-12) & (t < 0.1 * (k + 1) - 1e-12)
        assert np.ptp(force[inside]) == 0.0, k
        first = np.flatnonzero(inside)[0]
        assert force[first] == pytest.approx(law(0, state[:, first]), rel=1e-12, abs=1e-12)
    with pytest.raises(ValueError, match="`hold` must be a positive time"):
        scene.simulate(until=1.0, input={"F": LAW_TEXT}, hold=-1.0)
