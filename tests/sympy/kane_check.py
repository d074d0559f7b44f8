#!/usr/bin/env python3
"""Cross-check lagrange's rolling scenes against SymPy's KanesMethod.

crosscheck.py derives every scene again with LagrangesMethod from the `model` key of
lagrange's JSON report. This script is independent of that key as well: each scene with a
velocity (rolling, blade) constraint is written here again from its physics, with
`sympy.physics.mechanics` frames (`ReferenceFrame.orient_*`), points, `RigidBody`s, loads and
the constraints as velocity constraints, and its equations of motion come from `KanesMethod`:
the generalized speeds are the coordinates' rates (u_i = q_i'), those the constraints fix are
`u_dependent`, the constraints are `velocity_constraints`.

At random states that satisfy the constraints (parameters in [0.5, 2], t in [0, 1],
coordinates in [-1.2, 1.2] or a unit quaternion, independent rates in [-1, 1], dependent rates
from SymPy's constraints) it compares, in 40-digit arithmetic with mpmath:

* q'' from lagrange's report (`derive --format json`: the saddle-point system
  [M, -J^T; J, 0] [q''; lambda] = [f; bias] solved at the state) with u' from SymPy's
  `mass_matrix` and `forcing` (the independent speeds' equations and the differentiated
  constraints), for every coordinate, dependent ones included;
* lagrange's constraint equations, which must hold at SymPy's constrained state;
* lagrange's dependent rates (`independent_rates`, where the report has them), which must be
  the state's.

Differences are relative (to the largest entry of the vector; a constraint's residual to the
size of its terms); the tolerance is 1e-25.

Usage:
    kane_check.py [--lagrange PATH] [--states N] [--seed S] [SCENE.lag ...]

With no scene, every scene this script knows is checked (see SCENES). Exit status 1 when any
check fails.
"""

import argparse
import json
import os
import random
import sys

import mpmath
import sympy as sp
from sympy.physics.mechanics import (
    KanesMethod,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
    msubs,
)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from crosscheck import (  # noqa: E402
    ROOT,
    Evaluator,
    Scope,
    check_each,
    find_lagrange,
    run,
    solve,
)

TOLERANCE = 1e-25
mpmath.mp.dps = 40
t = dynamicsymbols._t


# --------------------------------------------------------------------------------------------
# The scenes, written again from their physics
# --------------------------------------------------------------------------------------------


class Model:
    """One scene for KanesMethod. `coords` are the scene's coordinate names (SymPy's
    dynamicsymbols of the same names, so that lagrange's expressions parse onto them);
    `dependent` the coordinates whose rates the constraints fix; `constraints` the velocity
    constraints, written in the rates q'; `sample(rng)` draws the coordinates of a state."""

    def __init__(self, coords, dependent, constraints, bodies, loads, frame, sample, note=""):
        self.coords = coords
        self.q = [dynamicsymbols(c) for c in coords]
        self.dependent = dependent
        self.constraints = constraints
        self.bodies = bodies
        self.loads = loads
        self.frame = frame
        self.sample = sample
        self.note = note


def uniform_coords(n):
    return lambda rng: [mpmath.mpf(rng.uniform(-1.2, 1.2)) for _ in range(n)]


def rolling_coin():
    """examples/space/rolling_coin.lag: a thin disk of radius r touching the table at
    (x, y, 0); heading psi about the vertical, lean theta about the heading frame's x axis,
    spin phi about the coin's own axis (its y axis). It rolls: the coin's material point at the
    table has no velocity (x and y components; the vertical one holds by the geometry)."""
    m, r, g = sp.symbols("m r g")
    x, y, psi, theta, phi = dynamicsymbols("x y psi theta phi")
    N = ReferenceFrame("N")
    heading = ReferenceFrame("heading")
    heading.orient_axis(N, N.z, psi)
    lean = ReferenceFrame("lean")
    lean.orient_axis(heading, heading.x, theta)
    coin = ReferenceFrame("coin")
    coin.orient_axis(lean, lean.y, phi)

    O = Point("O")
    O.set_vel(N, 0)
    contact = O.locatenew("contact", x * N.x + y * N.y)
    centre = contact.locatenew("centre", r * lean.z)
    centre.set_vel(N, centre.pos_from(O).dt(N))

    # A thin uniform disk about its centre: m r^2/2 about its axis, m r^2/4 across it.
    disk = inertia(coin, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4)
    body = RigidBody("coin", centre, coin, m, (disk, centre))
    slip = centre.vel(N) + coin.ang_vel_in(N).cross(contact.pos_from(centre))
    return Model(
        ["x", "y", "psi", "theta", "phi"], ["x", "y"],
        [slip.dot(N.x), slip.dot(N.y)],
        [body], [(centre, -m * g * N.z)], N, uniform_coords(5))


def chaplygin_sleigh():
    """examples/classics/chaplygin_sleigh.lag: a planar body whose blade touches the ice at
    (x, y) and points along theta; its centre of mass is a distance a ahead of the blade, its
    inertia about the centre I. The blade cannot slide sideways: the blade point's velocity has
    no component across the blade."""
    m, I, a = sp.symbols("m I a")
    x, y, theta = dynamicsymbols("x y theta")
    N = ReferenceFrame("N")
    sleigh = ReferenceFrame("sleigh")
    sleigh.orient_axis(N, N.z, theta)

    O = Point("O")
    O.set_vel(N, 0)
    blade = O.locatenew("blade", x * N.x + y * N.y)
    blade.set_vel(N, blade.pos_from(O).dt(N))
    centre = blade.locatenew("centre", a * sleigh.x)
    centre.set_vel(N, centre.pos_from(O).dt(N))

    # In the plane only the moment about the vertical counts.
    body = RigidBody("sleigh", centre, sleigh, m, (inertia(sleigh, 0, 0, I), centre))
    return Model(
        ["x", "y", "theta"], ["y"],
        [blade.vel(N).dot(sleigh.y)],
        [body], [], N, uniform_coords(3))


def ball_on_turntable():
    """examples/space/ball_on_turntable.lag: a uniform ball of radius r, centre at (x, y, r),
    oriented by Euler parameters (e0, e1, e2, e3) (`quaternion(e0, e1, e2, e3)`: the rotation
    by 2*acos(e0) about (e1, e2, e3), which is SymPy's orient_quaternion). It rolls on a table
    turning at W about the vertical through the origin: the ball's material point at the table
    moves with the table's point there. The Euler parameters stay on the unit sphere; here
    that holds through its time derivative, e . e' = 0, a third velocity constraint, which
    makes e0' a dependent rate beside x' and y' (so states keep e0 away from zero)."""
    m, r, W, g = sp.symbols("m r W g")
    x, y, e0, e1, e2, e3 = dynamicsymbols("x y e0 e1 e2 e3")
    N = ReferenceFrame("N")
    ball = ReferenceFrame("ball")
    ball.orient_quaternion(N, (e0, e1, e2, e3))

    O = Point("O")
    O.set_vel(N, 0)
    centre = O.locatenew("centre", x * N.x + y * N.y + r * N.z)
    centre.set_vel(N, centre.pos_from(O).dt(N))
    contact = centre.locatenew("contact", -r * N.z)

    uniform = sp.Rational(2, 5) * m * r**2
    body = RigidBody("ball", centre, ball, m, (inertia(ball, uniform, uniform, uniform), centre))
    slip = (centre.vel(N) + ball.ang_vel_in(N).cross(contact.pos_from(centre))
            - (W * N.z).cross(contact.pos_from(O)))
    unit = sum(e**2 for e in (e0, e1, e2, e3)).diff(t) / 2

    def sample(rng):
        while True:
            e = [rng.gauss(0.0, 1.0) for _ in range(4)]
            norm = sum(v * v for v in e) ** 0.5
            e = [v / norm for v in e]
            if abs(e[0]) >= 0.5:
                break
        e = [mpmath.mpf(v) for v in e]
        norm = mpmath.sqrt(sum(v * v for v in e))  # unit in 40 digits, not only in 16
        return [mpmath.mpf(rng.uniform(-1.2, 1.2)) for _ in range(2)] + [v / norm for v in e]

    return Model(
        ["x", "y", "e0", "e1", "e2", "e3"], ["x", "y", "e0"],
        [slip.dot(N.x), slip.dot(N.y), unit],
        [body], [(centre, -m * g * N.z)], N, sample,
        note="unit quaternion through e.e' = 0")


SCENES = {
    "examples/space/rolling_coin.lag": rolling_coin,
    "examples/classics/chaplygin_sleigh.lag": chaplygin_sleigh,
    "examples/space/ball_on_turntable.lag": ball_on_turntable,
}


# --------------------------------------------------------------------------------------------
# KanesMethod
# --------------------------------------------------------------------------------------------


def kane(model):
    """KanesMethod with u_i = q_i'. Returns (order, MM, FF): MM u' = FF, `order` the
    coordinates of the speeds in SymPy's order (independent, then dependent), every u written
    back as its q'."""
    speeds = {c: dynamicsymbols("u_" + c) for c in model.coords}
    rates = {q.diff(t): speeds[c] for c, q in zip(model.coords, model.q)}
    independent = [speeds[c] for c in model.coords if c not in model.dependent]
    dependent = [speeds[c] for c in model.dependent]
    kd = [speeds[c] - q.diff(t) for c, q in zip(model.coords, model.q)]
    constraints = [msubs(c, rates) for c in model.constraints]
    km = KanesMethod(model.frame, q_ind=model.q, u_ind=independent, kd_eqs=kd,
                     u_dependent=dependent, velocity_constraints=constraints)
    km.kanes_equations(model.bodies, model.loads)
    back = {speeds[c]: q.diff(t) for c, q in zip(model.coords, model.q)}
    order = [c for c in model.coords if c not in model.dependent] + list(model.dependent)
    MM = msubs(km.mass_matrix, back)
    FF = msubs(km.forcing, back)
    return order, MM, FF


def vector_difference(a, b):
    """max |a_i - b_i| relative to the largest |a_i|, |b_i|; zero when both are zero."""
    scale = max([abs(v) for v in list(a) + list(b)] + [mpmath.mpf(0)])
    if scale == 0:
        return 0.0
    return float(max(abs(p - q) for p, q in zip(a, b)) / scale)


def check(model, report, n_states, seed):
    """Compares one scene; returns (summary, max relative difference)."""
    if report["coordinates"] != model.coords:
        raise AssertionError(f"lagrange keeps {report['coordinates']}, the model has "
                             f"{model.coords}")
    scope = Scope(report["parameters"].keys(), model.coords)
    rng = random.Random(seed)
    n = len(model.coords)
    evaluator = Evaluator(scope, model.coords)

    order, MM, FF = kane(model)
    used = MM.free_symbols | FF.free_symbols | sp.Matrix(model.constraints).free_symbols
    unknown = {s.name for s in used} - set(scope.params) - {"t"}
    if unknown:
        raise AssertionError(f"the model uses {sorted(unknown)}, not parameters of the scene")
    sym_MM, sym_FF = evaluator.function(list(MM)), evaluator.function(list(FF))

    # The constrained state: the dependent rates from the model's own constraints, which are
    # affine in the rates, B q'_dep + b = 0 (b holds the independent rates' part).
    dep_rates = [scope.coords[c].diff(t) for c in model.dependent]
    cons = sp.Matrix(model.constraints)
    B = cons.jacobian(dep_rates)
    b = cons.xreplace({d: 0 for d in dep_rates})
    con_B, con_b = evaluator.function(list(B)), evaluator.function(list(b))

    # lagrange: M q'' = f + J^T lambda, J q'' = bias; its constraint equations; its dependent
    # rates.
    kept = report["constraints"]
    lag_M = evaluator.function([scope.parse(e) for row in report["mass_matrix"] for e in row])
    lag_f = evaluator.function([scope.parse(e) for e in report["forcing"]])
    lag_J = evaluator.function([scope.parse(e) for c in kept for e in c["jacobian"]])
    lag_bias = evaluator.function([scope.parse(c["bias"]) for c in kept])
    sides = [c["equation"].split("=") for c in kept]
    if any(len(s) != 2 for s in sides):
        raise AssertionError("a constraint equation without exactly one `=`")
    lag_residual = evaluator.function([scope.parse(lhs) - scope.parse(rhs) for lhs, rhs in sides])
    # The scale of a velocity constraint's residual is |J| |q'| + |its part without rates|; a
    # position constraint's (the unit quaternion) is |lhs| + |rhs|.
    no_rates = {scope.coords[c].diff(t): 0 for c in model.coords}
    lag_rest = evaluator.function([(scope.parse(lhs) - scope.parse(rhs)).xreplace(no_rates)
                                   for lhs, rhs in sides])
    lag_sides = evaluator.function([scope.parse(e) for s in sides for e in s])
    position = ["'" not in c["equation"] for c in kept]
    given = report.get("independent_rates") or {}
    dependent_names = [c.rstrip("'") for c in given.get("dependent", {})]
    lag_dependent = evaluator.function(
        [scope.parse(e) for e in given.get("dependent", {}).values()])

    worst_acc = worst_cons = worst_dep = 0.0
    k = len(kept)
    d = len(model.dependent)
    for _ in range(n_states):
        params = [mpmath.mpf(rng.uniform(0.5, 2.0)) for _ in scope.params]
        now = [mpmath.mpf(rng.uniform(0.0, 1.0))]
        q = model.sample(rng)
        rates = {c: mpmath.mpf(rng.uniform(-1.0, 1.0)) for c in model.coords
                 if c not in model.dependent}
        for c in model.dependent:
            rates[c] = mpmath.mpf(0)
        partial = params + now + q + [rates[c] for c in model.coords] + [0] * n
        Bv = con_B(*partial)
        dep = solve([[Bv[i * d + j] for j in range(d)] for i in range(d)],
                    [-v for v in con_b(*partial)])
        rates.update(zip(model.dependent, dep))
        u = [rates[c] for c in model.coords]
        state = params + now + q + u + [0] * n

        # lagrange's q'' from its saddle-point system.
        M, f, J, bias = lag_M(*state), lag_f(*state), lag_J(*state), lag_bias(*state)
        A = [[M[i * n + j] for j in range(n)] + [-J[c * n + i] for c in range(k)]
             for i in range(n)]
        A += [[J[c * n + j] for j in range(n)] + [0] * k for c in range(k)]
        lag_acc = solve(A, list(f) + list(bias))[:n]

        # SymPy's u', mapped back to the coordinates.
        mm = sym_MM(*state)
        du = solve([[mm[i * n + j] for j in range(n)] for i in range(n)], sym_FF(*state))
        sym_acc = [du[order.index(c)] for c in model.coords]
        worst_acc = max(worst_acc, vector_difference(lag_acc, sym_acc))

        # lagrange's constraints at SymPy's constrained state.
        residual, rest, both = lag_residual(*state), lag_rest(*state), lag_sides(*state)
        speed = max(abs(v) for v in u)
        for c in range(k):
            if position[c]:
                scale = abs(both[2 * c]) + abs(both[2 * c + 1])
            else:
                scale = max(abs(J[c * n + j]) for j in range(n)) * speed + abs(rest[c])
            if scale:
                worst_cons = max(worst_cons, float(abs(residual[c]) / scale))

        # lagrange's dependent rates against the state's.
        if dependent_names:
            # Relative to the largest rate: a dependent rate may be zero at a state.
            diff = max(abs(a - rates[c]) for a, c in zip(lag_dependent(*state), dependent_names))
            worst_dep = max(worst_dep, float(diff / speed))

    primed = lambda names: ", ".join(c + "'" for c in names)
    parts = [f"KanesMethod, u = ({primed(order)}), dependent {primed(model.dependent)}"]
    if model.note:
        parts.append(model.note)
    parts.append(f"q'' at {n_states} states {worst_acc:.1e}")
    parts.append(f"lagrange's {k} constraint equations {worst_cons:.1e}")
    if dependent_names:
        parts.append(f"its dependent rates {primed(dependent_names)} {worst_dep:.1e}")
    return "; ".join(parts), max(worst_acc, worst_cons, worst_dep)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", help="scene files (default: every one in SCENES)")
    parser.add_argument("--lagrange", default=os.environ.get("LAGRANGE"),
                        help="the lagrange binary (default: $LAGRANGE, else "
                        "target/{release,debug})")
    parser.add_argument("--states", type=int, default=10, help="random states per scene")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random states")
    args = parser.parse_args()
    lagrange = find_lagrange(args.lagrange)

    known = {os.path.normpath(os.path.join(ROOT, k)): k for k in SCENES}
    scenes = args.scenes or [os.path.join(ROOT, k) for k in SCENES]
    def check_one(path):
        key = known.get(os.path.normpath(os.path.abspath(path)))
        if key is None:
            raise ValueError(f"no Kane model for this scene (known: {', '.join(SCENES)})")
        report = json.loads(run([lagrange, "derive", path, "--format", "json", "--no-units"]))
        return check(SCENES[key](), report, args.states, args.seed)

    jobs = [(os.path.relpath(path), path) for path in scenes]
    sys.exit(check_each(jobs, check_one, TOLERANCE))

if __name__ == "__main__":
    main()
