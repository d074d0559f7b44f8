"""Scenes with one-sided contacts from Python: `simulate` runs them as the command does, with
the contact events as a table; what would hold every contact closed (the right-hand side and
its Jacobian and batch, linearize, inverse dynamics) refuses, naming the contacts."""

import math
from pathlib import Path

import numpy as np
import pytest

import lagrange

ROOT = Path(__file__).resolve().parents[3]
BALL = ROOT / "examples" / "contacts" / "bouncing_ball.lag"
# The scene's values: h0 = 1 m, g = 9.81 m/s², e = 4/5, m = 1/2 kg.
H0, G, E, M = 1.0, 9.81, 0.8, 0.5
T1 = math.sqrt(2 * H0 / G)


def test_the_ball_lands_at_the_closed_form_times_and_settles_where_they_accumulate():
    run = lagrange.load(BALL).simulate(tolerance=1e-10)
    assert run.contacts == ["floor"]
    events = run.contact_events
    assert list(events) == [
        "t", "contact", "kind", "closed", "impulse", "tangential_impulse", "energy_change",
        "slip",
    ]
    impacts = events.of("impact", "floor")
    assert len(impacts) > 20, events
    # The k-th impact at t1·(1 + 2(e + e² + … + e^(k−1))).
    expected = T1 * (1 + 2 * np.concatenate([[0.0], np.cumsum(E ** np.arange(1, len(impacts)))]))
    np.testing.assert_allclose(impacts, expected, rtol=1e-8)
    settled = events.settled("floor")
    assert settled == pytest.approx(T1 * (1 + E) / (1 - E), rel=1e-8)
    assert list(events["kind"]).count("settled") == 1
    last = events["kind"] == "settled"
    assert events["closed"][last].all() and not events["closed"][events["kind"] == "impact"].any()
    # The first impact takes Λ = (1 + e)·m·v and removes (1 − e²)·½mv², v = g·t1; the floor
    # has no grip.
    v = G * T1
    assert events["impulse"][0] == pytest.approx((1 + E) * M * v, rel=1e-8)
    assert events["energy_change"][0] == pytest.approx(-(1 - E * E) * 0.5 * M * v * v, rel=1e-8)
    assert np.isnan(events["tangential_impulse"]).all()
    # The impacts took all the energy of the drop; the ball rests on the floor after.
    assert run.energy_changed_by_impacts == pytest.approx(-M * G * H0, rel=1e-6)
    assert abs(run["y"][-1]) < 1e-9 and run["floor.force"][-1] == pytest.approx(M * G, rel=1e-9)
    assert events.count == len(events["t"]) and "impact" in repr(events)
    pandas = pytest.importorskip("pandas")
    frame = events.to_pandas()
    assert isinstance(frame, pandas.DataFrame) and list(frame.columns) == list(events)
    assert len(frame) == events.count and frame["contact"].iloc[0] == "floor"


def test_a_scene_without_contacts_has_an_empty_table():
    run = lagrange.load(ROOT / "examples" / "classics" / "simple_pendulum.lag").simulate(until=1)
    assert run.contacts == [] and run.contact_events.count == 0
    assert run.contact_events.settled() is None and run.energy_changed_by_impacts == 0.0


def test_a_batch_takes_contacts_as_simulate_does():
    scene = lagrange.load(BALL)
    b = scene.batch({"e": [0.5, 0.8]}, until=5, output=["y"], tolerance=1e-10)
    for k, e in enumerate([0.5, 0.8]):
        run = scene.simulate(until=5, output=["y"], set={"e": e}, tolerance=1e-10)
        assert b["y"][k] == run["y"][-1]
        assert run.contact_events.settled() == pytest.approx(T1 * (1 + e) / (1 - e), rel=1e-8)


def test_what_would_hold_every_contact_closed_refuses_naming_it():
    scene = lagrange.load(BALL)
    with pytest.raises(ValueError, match=r"`Scene.rhs\(\)`.*`floor`"):
        scene.rhs()
    with pytest.raises(ValueError, match=r"linearize.*`floor`"):
        scene.linearize(about="y=0")
    with pytest.raises(ValueError, match=r"inverse dynamics.*`floor`"):
        scene.inverse_dynamics(0.0, [0.0, 1.0], [0.0, 0.0], [0.0, -G])
    # M(q) is the same whichever contacts are closed: it takes them.
    np.testing.assert_allclose(scene.mass_matrix_function()(0.0, [0.0, 1.0]), M * np.eye(2))
    # The symplectic methods cannot take contacts, and say so.
    with pytest.raises(ValueError, match=r"does not take contacts.*`floor`"):
        scene.simulate(method="midpoint")


def test_an_ensemble_records_each_runs_settling_and_impacts():
    table = lagrange.load(BALL).ensemble(
        {"e": (0.5, 0.9, 5)},
        record=["settled(floor)", "impacts(floor)", "y"],
        until=10,
        tolerance=1e-10,
        threads=2,
    )
    assert table.recorded == ["settled(floor)", "impacts(floor)", "y"]
    assert all(f is None for f in table.failures)
    e = table["e"]
    np.testing.assert_allclose(table["settled(floor)"], T1 * (1 + e) / (1 - e), rtol=1e-8)
    assert np.all(np.diff(table["impacts(floor)"]) > 0) and np.all(np.abs(table["y"]) < 1e-9)
    # Each run is what `simulate` gives at its restitution.
    run = lagrange.load(BALL).simulate(until=10, tolerance=1e-10, set={"e": float(e[2])})
    assert table["settled(floor)"][2] == run.contact_events.settled("floor")
    assert table["impacts(floor)"][2] == len(run.contact_events.of("impact"))
    # A restitution past 1 is a run that fails with its reason; a contact the scene does not
    # have is refused.
    past = lagrange.load(BALL).ensemble({"e": (0.9, 1.1, 2)}, record="settled(floor)", until=10)
    assert past.failures[0] is None and "restitution of contact `floor`" in past.failures[1]
    with pytest.raises(ValueError, match="no contact `wall`"):
        lagrange.load(BALL).ensemble({"e": (0.5, 0.9, 2)}, record="settled(wall)")


def test_a_block_on_a_rough_incline_stops_and_slides_back_as_its_events_say():
    # examples/friction/block_on_incline.lag: m = 2 kg, γ = π/6, μ = 0.4, v0 = 3 m/s.
    block = lagrange.load(ROOT / "examples" / "friction" / "block_on_incline.lag")
    run = block.simulate(tolerance=1e-10)
    events = run.contact_events
    slips = events["kind"] == "slips"
    # It slips up from the start, then back down where it stops.
    assert list(events["slip"][slips]) == [1.0, -1.0]
    g, gamma, mu, v0 = 9.81, math.pi / 6, 0.4, 3.0
    stop = v0 / (g * (math.sin(gamma) + mu * math.cos(gamma)))
    assert events["t"][slips][1] == pytest.approx(stop, rel=1e-8)
    # Sliding down, friction is μ·N up the slope.
    assert run["plane.grip"][-1] == pytest.approx(mu * 2.0 * g * math.cos(gamma), rel=1e-9)
