"""Parameter values per call and from then on in ``rhs``, never lost in a copy; and the
inverse dynamics, which gives back the torques a driven run was simulated with."""

from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"

# Two links on hinges, a shoulder motor and an elbow motor driven by functions of time.
DRIVEN = ROOT / "tests" / "scenes" / "driven_double_pendulum.lag"


@pytest.fixture()
def pendulum():
    return lagrange.load(EXAMPLES / "classics" / "simple_pendulum.lag").rhs()


def test_rhs_takes_parameter_values_for_one_call(pendulum):
    f = pendulum
    y = f.y0
    g = f.parameter_names.index("g")
    assert f(0.0, y, p={"g": 1.62})[1] == pytest.approx(-1.62 * np.sin(0.5), rel=1e-15)
    values = [f.parameters[name] for name in f.parameter_names]
    values[g] = 3.0
    assert f(0.0, y, values)[1] == pytest.approx(-3.0 * np.sin(0.5), rel=1e-15)
    # The call's values are the call's only.
    assert f(0.0, y)[1] == pytest.approx(-9.81 * np.sin(0.5), rel=1e-15)
    assert f.parameters["g"] == 9.81
    Y = np.array([y, [0.2, 1.0]])
    np.testing.assert_array_equal(f.batch(Y, p={"g": 1.62})[0], f(0.0, y, p={"g": 1.62}))


def test_solve_ivp_passes_parameter_values_through_args(pendulum):
    from scipy.integrate import solve_ivp

    f = pendulum
    moon = solve_ivp(f, (0.0, 1.0), f.y0, args=({"g": 1.62},), rtol=1e-12, atol=1e-12)
    f.parameters = {"g": 1.62}
    again = solve_ivp(f, (0.0, 1.0), f.y0, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(moon.y[:, -1], again.y[:, -1])
    f.parameters = {"g": 9.81}
    earth = solve_ivp(f, (0.0, 1.0), f.y0, rtol=1e-12, atol=1e-12)
    assert abs(earth.y[0, -1] - moon.y[0, -1]) > 0.1


def test_setting_parameters_takes_effect_or_is_refused(pendulum):
    f = pendulum
    f.parameters = {"g": 1.62}
    assert f.parameters["g"] == 1.62
    assert f(0.0, f.y0)[1] == pytest.approx(-1.62 * np.sin(0.5), rel=1e-15)
    f.parameters = np.full(len(f.parameter_names), 2.0)
    assert dict(f.parameters) == {name: 2.0 for name in f.parameter_names}
    # An item of the mapping cannot be changed: it would be a copy nothing reads.
    with pytest.raises(TypeError):
        f.parameters["g"] = 5.0
    assert f.parameters["g"] == 2.0
    with pytest.raises(KeyError, match="no parameter `gg`"):
        f.parameters = {"gg": 1.0}
    with pytest.raises(ValueError, match="parameter values for the"):
        f(0.0, f.y0, p=[1.0])
    with pytest.raises(ValueError, match="must be finite"):
        f.parameters = {"g": float("nan")}
    assert f.parameters["g"] == 2.0


def driven_run():
    scene = lagrange.load(DRIVEN)
    names = ["theta1", "theta2"]
    output = names + [n + "'" for n in names] + [n + "''" for n in names]
    run = scene.simulate(until=5.0, output=output, tolerance=1e-12, samples=101)
    q = np.column_stack([run[n] for n in names])
    qd = np.column_stack([run[n + "'"] for n in names])
    qdd = np.column_stack([run[n + "''"] for n in names])
    return scene, run["t"], q, qd, qdd


def test_inverse_dynamics_gives_back_the_torques_of_a_driven_run():
    scene, t, q, qd, qdd = driven_run()
    # With the motors off in the scene, the forces it takes are the motors'.
    tau = scene.inverse_dynamics(t, q, qd, qdd, p={"A1": 0.0, "A2": 0.0})
    applied = np.column_stack([3 * np.sin(2 * t) - np.cos(2 * t), np.cos(2 * t)])
    assert tau.shape == (101, 2)
    np.testing.assert_allclose(tau, applied, rtol=0, atol=1e-9)
    # With them on, the scene's own forces do it all.
    np.testing.assert_allclose(scene.inverse_dynamics(t, q, qd, qdd), 0.0, atol=1e-9)
    # One motion gives one row, and the derivation answers alike.
    one = scene.derive().inverse_dynamics(t[7], q[7], qd[7], qdd[7], p={"A1": 0.0, "A2": 0.0})
    assert one.shape == (2,)
    np.testing.assert_array_equal(one, tau[7])
    with pytest.raises(ValueError, match="coordinates"):
        scene.inverse_dynamics(t, q[:, :1], qd, qdd)


def test_inverse_dynamics_with_a_kept_rod_needs_no_force_for_a_free_swing():
    scene = lagrange.load(EXAMPLES / "classics" / "pendulum_cartesian.lag")
    f = scene.rhs()
    run = scene.simulate(until=1.0, output=["x", "y", "x'", "y'", "x''", "y''"], samples=21,
                         set={"x": 0.6, "y": -0.8}, tolerance=1e-12)
    columns = lambda suffix: np.column_stack([run["x" + suffix], run["y" + suffix]])
    tau = scene.inverse_dynamics(run["t"], columns(""), columns("'"), columns("''"))
    np.testing.assert_allclose(tau, 0.0, atol=1e-9)
    assert f.names == ["x", "y", "x'", "y'"]


def test_jac_takes_the_values_solve_ivp_hands_to_f(pendulum):
    from scipy.integrate import solve_ivp

    f = pendulum
    # θ̈ = −g/L·sin θ, so ∂θ̈/∂θ = −g/L·cos θ (L = 1).
    assert f.jac(0.0, f.y0, {"g": 1.62})[1, 0] == pytest.approx(-1.62 * np.cos(0.5), rel=1e-14)
    assert f.jac(0.0, f.y0)[1, 0] == pytest.approx(-9.81 * np.cos(0.5), rel=1e-14)
    moon = solve_ivp(f, (0.0, 1.0), f.y0, method="Radau", jac=f.jac, args=({"g": 1.62},),
                     rtol=1e-10, atol=1e-10)
    assert moon.success
    f.parameters = {"g": 1.62}
    again = solve_ivp(f, (0.0, 1.0), f.y0, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(moon.y[:, -1], again.y[:, -1], atol=1e-7)


# L = 2*a and I = m*L^2/12: derived parameters, which follow a and m.
DERIVED = ROOT / "tests" / "scenes" / "derived_length_pendulum.lag"


def test_derived_parameters_follow_the_free_ones_as_simulate_set_has_them():
    scene = lagrange.load(DERIVED)
    f = scene.rhs()
    assert f.parameter_names == ["a", "m", "g"]
    assert f.derived_parameter_names == ["L", "I"]
    assert dict(f.derived_parameters) == {"L": 2.0, "I": pytest.approx(1 / 3, rel=1e-15)}
    y = f.y0
    # simulate's `set` goes the command line's way (`simulate --set a=2`).
    run = scene.simulate(until=1e-3, samples=2, set={"a": 2}, output=["theta''"])
    by_hand = -1.5 * 9.81 * np.sin(0.5) / 4.0
    assert run["theta''"][0] == pytest.approx(by_hand, rel=1e-14)
    assert f(0.0, y, p={"a": 2})[1] == run["theta''"][0]
    assert f(0.0, y, p=[2.0, 1.0, 9.81])[1] == run["theta''"][0]
    Y = np.array([y, [0.1, 0.3]])
    batch = f.batch(Y, p={"a": 2})
    np.testing.assert_array_equal(batch[0], f(0.0, y, p={"a": 2}))
    np.testing.assert_array_equal(batch[1], f(0.0, Y[1], p={"a": 2}))
    # The Jacobian at a = 2 against central differences of f at a = 2.
    jac = f.jac(0.0, y, p={"a": 2})
    h = 1e-6
    column = (f(0.0, y + [h, 0.0], p={"a": 2}) - f(0.0, y - [h, 0.0], p={"a": 2})) / (2 * h)
    np.testing.assert_allclose(jac[:, 0], column, rtol=1e-8)
    # From then on, and back.
    f.parameters = {"a": 2}
    assert f.derived_parameters["L"] == 4.0
    assert f(0.0, y)[1] == run["theta''"][0]
    f.parameters = {"a": 1}
    assert f(0.0, y)[1] == pytest.approx(-1.5 * 9.81 * np.sin(0.5) / 2.0, rel=1e-14)


def test_a_derived_parameter_cannot_be_set_and_names_what_it_follows():
    scene = lagrange.load(DERIVED)
    f = scene.rhs()
    with pytest.raises(ValueError, match=r"`L` is derived from `a`; set `a` instead"):
        f(0.0, f.y0, p={"L": 3})
    with pytest.raises(ValueError, match=r"`I` is derived from `m` and `L`"):
        f.parameters = {"I": 3}
    with pytest.raises(KeyError, match="no parameter `b`"):
        f(0.0, f.y0, p={"b": 3})
    with pytest.raises(ValueError, match=r"5 parameter values for the 3 parameters \(a, m, g\)"):
        f(0.0, f.y0, p=[2.0, 1.0, 9.81, 4.0, 1.0])
    inverse = scene.inverse_dynamics
    with pytest.raises(ValueError, match=r"`L` is derived from `a`"):
        inverse(0.0, [0.5], [0.0], [0.0], p={"L": 3})
    with pytest.raises(ValueError, match=r"`L` is derived from `a`"):
        scene.simulate(until=0.1, set={"L": 3})


def test_inverse_dynamics_follows_derived_parameters():
    scene = lagrange.load(DERIVED)
    f = scene.rhs()
    y = f.y0
    accel = f(0.0, y, p={"a": 2})[1]
    # The scene moves on its own: no force is needed for its own acceleration at a = 2.
    tau = scene.inverse_dynamics(0.0, [0.5], [0.0], [accel], p={"a": 2})
    assert abs(tau[0]) < 1e-14
    tau = scene.inverse_dynamics(0.0, [0.5], [0.0], [accel])
    assert abs(tau[0]) > 1.0
    native = scene._native.inverse_dynamics()
    assert native.parameter_names == ["a", "m", "g"]
    assert native.derived_parameter_names == ["L", "I"]
    assert native.input_names == []


def test_derivation_names_what_each_derived_parameter_follows():
    d = lagrange.load(DERIVED).derive()
    assert d.derived_parameters == {"L": ["a"], "I": ["m", "L"]}
    assert d.parameters["I"] == pytest.approx(1 / 3, rel=1e-15)
