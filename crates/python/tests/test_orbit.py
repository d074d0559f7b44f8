"""Periodic orbits from Python: `Scene.orbit` finds them as `lagrange orbit` does, and gives
the fixed point, the multipliers and the map's Jacobian as numbers."""

import math
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
WHEEL = ROOT / "examples" / "contacts" / "rimless_wheel.lag"
PENDULUM = ROOT / "examples" / "orbits" / "driven_pendulum.lag"


def test_the_rimless_wheel_rolls_at_mcgeers_rate_with_the_multiplier_c_squared():
    orbit = lagrange.load(WHEEL).orbit(section="impact", shift={"theta": "pi/4"}, ignore="x")
    m, inertia, l, g, gamma, alpha = 1.0, 0.1, 1.0, 9.81, 0.1, math.pi / 8
    c = (inertia + m * l * l * math.cos(2 * alpha)) / (inertia + m * l * l)
    rate = c * math.sqrt(4 * m * g * l * math.sin(alpha) * math.sin(gamma) / (inertia + m * l * l))
    rate /= math.sqrt(1 - c * c)
    assert orbit.state == ["x", "y", "theta", "x'", "y'", "theta'"]
    assert orbit.fixed_point[5] == pytest.approx(-rate, rel=1e-8)
    assert len(orbit.multipliers) == 1 and orbit.trivial == 5
    assert orbit.multipliers[0] == pytest.approx(c * c, abs=1e-8)
    assert orbit.stable and orbit.jumps == 1
    assert orbit.monodromy.shape == (6, 6)
    # Newton's first run is loose, its last at the tolerance asked for; the last step is taken
    # unchecked, expected to leave the map's rounding at most.
    assert len(orbit.tolerances) == len(orbit.residuals)
    assert orbit.tolerances[0] == 1e-6 and orbit.tolerances[-1] < 1e-6
    assert orbit.last_step is not None and orbit.last_step < 1e-14


def test_the_driven_pendulum_contracts_areas_by_liouvilles_factor():
    orbit = lagrange.load(PENDULUM).orbit(period="2*pi/w", set={"A": 1})
    period = math.pi
    assert orbit.period == pytest.approx(period, rel=1e-14)
    expected = math.exp(-0.5 * period)
    assert np.linalg.det(orbit.monodromy) == pytest.approx(expected, rel=1e-8)
    product = np.prod(orbit.multipliers)
    assert product.real == pytest.approx(expected, rel=1e-8) and abs(product.imag) < 1e-12


def test_mistakes_are_refused():
    scene = lagrange.load(PENDULUM)
    with pytest.raises(ValueError, match="one of period"):
        scene.orbit()
    with pytest.raises(ValueError, match="rising"):
        scene.orbit(section="theta", direction="up")
    with pytest.raises(ValueError, match="no contact to land on"):
        scene.orbit(section="impact")
