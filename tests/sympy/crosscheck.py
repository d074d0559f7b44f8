#!/usr/bin/env python3
"""Cross-check lagrange's equations of motion against SymPy's LagrangesMethod.

For each scene, `lagrange derive --format json` gives two things:

* lagrange's result: the mass matrix M and forcing f (M q'' = f, plus J^T lambda with
  multipliers), the multiplier rows J q'' = bias, and the reactions;
* the scene's primitive data (the `model` key): declared coordinates, bodies, gravity,
  potentials, dissipation, Lagrangian terms, forces, torques, constraints.

From the primitive data alone this script derives the equations again with
`sympy.physics.mechanics` and compares the accelerations q'' (and the reactions the scene
asks for) at random states, evaluated in 40-digit arithmetic with mpmath.

Usage:
    crosscheck.py [--lagrange PATH] [--states N] [--generated FAMILY:N ...] [SCENE.lag ...]

With no scene and no --generated, every examples/**/*.lag is checked. Exit status 1 when
any check fails.
"""

import argparse
import glob
import json
import os
import random
import re
import subprocess
import sys
import tempfile
import time

import mpmath
import sympy as sp
from sympy.physics.mechanics import (
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOLERANCE = 1e-9
mpmath.mp.dps = 40

# --------------------------------------------------------------------------------------------
# Scene-syntax expressions -> SymPy
# --------------------------------------------------------------------------------------------

def real_abs(u):
    """|u| for a real u. SymPy's Abs of a function of time not declared real differentiates
    into re() and im() terms that no printer evaluates; sqrt(u**2) differentiates as |u| does
    for real u (u*u'/|u|), and so do the sign, min and max written with it."""
    return sp.sqrt(u**2)


FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "exp": sp.exp, "ln": sp.log, "sqrt": sp.sqrt,
    "abs": real_abs,
    "sign": lambda u: u / real_abs(u),
    "min": lambda a, b: (a + b - real_abs(a - b)) / 2,
    "max": lambda a, b: (a + b + real_abs(a - b)) / 2,
}

# A name (possibly dotted, like `floor.force`) with its primes. The lookbehind keeps the `e`
# of a number like `1e-3` from being read as a name.
NAME = re.compile(r"(?<![\w.])([^\W\d]\w*(?:\.[^\W\d]\w*)?)('*)")

# parse_expr evaluates the rewritten text with only these globals, so scene names can never
# collide with SymPy's (`I`, `E`, `N`, `S`, `beta`, `gamma`, the keyword `lambda`, ...).
GLOBALS = {"Integer": sp.Integer, "Rational": sp.Rational, "Float": sp.Float}


class Scope:
    """The names of one scene: parameters (symbols), coordinates (dynamicsymbols), time."""

    def __init__(self, params, coords):
        self.t = dynamicsymbols._t
        self.params = {p: sp.Symbol(p) for p in params}
        self.coords = {c: dynamicsymbols(c) for c in coords}
        # Reactions (`floor.force`) and other dotted names are plain symbols.
        self.others = {}

    def lookup(self, name, primes):
        if name in self.coords:
            return self.coords[name].diff(self.t, primes) if primes else self.coords[name]
        if primes:
            raise ValueError(f"`{name}` has primes but is not a coordinate")
        if name in self.params:
            return self.params[name]
        if name in FUNCTIONS:
            return FUNCTIONS[name]
        if name == "pi":
            return sp.pi
        if name == "t":
            return self.t
        if "." in name:
            return self.others.setdefault(name, sp.Symbol(name))
        raise ValueError(f"unknown name `{name}`")

    def parse(self, text):
        # Every name becomes a placeholder bound to its SymPy object; `^` is a power.
        table = {}

        def placeholder(match):
            key = f"_n{len(table)}"
            table[key] = self.lookup(match.group(1), len(match.group(2)))
            return key

        source = NAME.sub(placeholder, text).replace("^", "**")
        return sp.parse_expr(source, local_dict=table, global_dict=dict(GLOBALS))


# --------------------------------------------------------------------------------------------
# Numbers at random states
# --------------------------------------------------------------------------------------------


class Evaluator:
    """Turns expressions in dynamicsymbols into mpmath functions of one flat state vector:
    parameters, t, coordinates, rates, accelerations, then any extra plain symbols."""

    def __init__(self, scope, coords, extras=()):
        t = scope.t
        self.args = [scope.params[p] for p in scope.params] + [sp.Symbol("t_")]
        self.plain = {t: self.args[-1]}
        # q, q', q'' become plain symbols so lambdify sees ordinary arguments (xreplace matches
        # the largest subtree first, so a derivative is replaced whole, before its q(t)).
        for level, suffix in ((0, ""), (1, "__d"), (2, "__dd")):
            for c in coords:
                q = scope.coords[c]
                s = sp.Symbol(c + suffix)
                self.plain[q.diff(t, level) if level else q] = s
                self.args.append(s)
        self.args.extend(extras)

    def function(self, exprs):
        plain = [sp.sympify(e).xreplace(self.plain) for e in exprs]
        # Left-over time (from an explicit t) is the same symbol as the dynamicsymbols' time.
        return sp.lambdify(self.args, plain, modules="mpmath")


def random_state(rng, n_params, n_coords):
    """Parameters in [0.5, 2], t in [0, 1], coordinates in [-1.2, 1.2], rates in [-1, 1]."""
    mpf = mpmath.mpf
    params = [mpf(rng.uniform(0.5, 2.0)) for _ in range(n_params)]
    t = [mpf(rng.uniform(0.0, 1.0))]
    q = [mpf(rng.uniform(-1.2, 1.2)) for _ in range(n_coords)]
    u = [mpf(rng.uniform(-1.0, 1.0)) for _ in range(n_coords)]
    return params + t + q + u


def solve(matrix, vector):
    return list(mpmath.lu_solve(mpmath.matrix(matrix), mpmath.matrix(vector)))


def relative(a, b):
    """|a - b| relative to the larger of the two; exact zeros on both sides agree."""
    scale = max(abs(a), abs(b))
    return 0.0 if scale == 0 else float(abs(a - b) / max(scale, mpmath.mpf("1e-25")))


# --------------------------------------------------------------------------------------------
# The independent derivation
# --------------------------------------------------------------------------------------------


def sympy_system(model, scope, coords, substitute, kept, velocity=()):
    """LagrangesMethod in `coords`, after substituting the eliminated coordinates
    (`substitute`, applied to q, q' and q''), with the constraints `kept` (a list of Phi) as
    constraint equations: holonomic, except those whose index is in `velocity`, which are
    nonholonomic (linear in the rates). Returns (MM, FF, order): MM [q'; q''; lam] = FF, with
    lam in SymPy's order (holonomic first), `order[i]` the place of kept[i]'s multiplier."""
    t = scope.t
    sub = lambda e: e.xreplace(substitute)
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    dim = max([len(b["position"]) for b in model["bodies"]] + [2])

    def vector(components):
        comps = [sub(scope.parse(c)) for c in components]
        return sum((x * e for x, e in zip(comps, [N.x, N.y, N.z])), sp.S(0) * N.x)

    gravity = model["gravity"]
    if gravity:
        down = [0] * dim
        down[-1] = -1
        given = gravity["direction"]
        d = [sp.S(x) for x in down] if given is None else [sub(scope.parse(x)) for x in given]
        # The language says `gravity g along (dx, dy)`: g is the strength, so the direction is
        # taken as a unit vector.
        norm = sp.sqrt(sum(x**2 for x in d))
        g_vec = sub(scope.parse(gravity["strength"])) / norm * sum(
            (x * e for x, e in zip(d, [N.x, N.y, N.z])), sp.S(0) * N.x)

    bodies, points, frames = [], {}, {}
    for b in model["bodies"]:
        P = O.locatenew(b["name"], vector(b["position"]))
        P.set_vel(N, P.pos_from(O).dt(N))
        mass = sub(scope.parse(b["mass"]))
        if b["kind"] == "rigid":
            # A planar rigid body turns about N.z by its angle; its inertia is about the centre
            # of mass, so only the zz entry matters.
            B = ReferenceFrame(b["name"] + "_frame")
            B.orient_axis(N, N.z, sub(scope.parse(b["angle"])))
            body = RigidBody(b["name"], P, B, mass,
                             (inertia(B, 0, 0, sub(scope.parse(b["inertia"]))), P))
            frames[b["name"]] = B
        elif b["kind"] == "spatial":
            # The orientation carries body axes into world axes, so it is N.dcm(B); SymPy
            # works out the angular velocity from it on its own.
            B = ReferenceFrame(b["name"] + "_frame")
            if "euler_parameters" in b:
                # SymPy's own quaternion orientation, with its own angular velocity.
                e = [sub(scope.parse(x)) for x in b["euler_parameters"]]
                B.orient_quaternion(N, e)
            else:
                R = sp.Matrix([[sub(scope.parse(x)) for x in row] for row in b["orientation"]])
                B.orient_explicit(N, R)
            I = [[sub(scope.parse(x)) for x in row] for row in b["inertia"]]
            tensor = inertia(B, I[0][0], I[1][1], I[2][2], I[0][1], I[1][2], I[0][2])
            body = RigidBody(b["name"], P, B, mass, (tensor, P))
            frames[b["name"]] = B
        else:
            body = Particle(b["name"], P, mass)
        if gravity:
            # V = -m g . r: the work of gravity from the origin.
            body.potential_energy = -mass * g_vec.dot(P.pos_from(O))
        bodies.append(body)
        points[b["name"]] = P

    L = Lagrangian(N, *bodies) if bodies else sp.S(0)
    L -= sum(sub(scope.parse(v)) for v in model["potentials"])
    L += sum(sub(scope.parse(l)) for l in model["lagrangian"])
    # Expanded, the Lagrangian of a chain (nested sums of sines) differentiates about four
    # times faster; it is the same function.
    L = sp.expand(L)

    forcelist = []
    for f in model["forces"]:
        comps = f["vector"] if isinstance(f["vector"], list) else [f["vector"]]
        point = points[f["body"]]
        if "at" in f:
            # A force at a point of the body: its own point, moving as its position does.
            point = O.locatenew(f["name"] + "_at", vector(f["at"]))
            point.set_vel(N, point.pos_from(O).dt(N))
        forcelist.append((point, vector(comps)))
    for tq in model["torques"]:
        if tq["body"] not in frames:
            raise ValueError(f"torque on `{tq['body']}`, which has no angle")
        if isinstance(tq["torque"], list):
            forcelist.append((frames[tq["body"]], vector(tq["torque"])))
        else:
            forcelist.append((frames[tq["body"]], sub(scope.parse(tq["torque"])) * N.z))

    q = [scope.coords[c] for c in coords]
    hol = [phi for i, phi in enumerate(kept) if i not in velocity]
    nonhol = [phi for i, phi in enumerate(kept) if i in velocity]
    lm = LagrangesMethod(L, q, forcelist=forcelist or None, frame=N,
                         hol_coneqs=hol or None, nonhol_coneqs=nonhol or None)
    lm.form_lagranges_equations()
    MM, FF = lm.mass_matrix_full, lm.forcing_full.copy()

    # Rayleigh dissipation is not part of LagrangesMethod: add its generalized force -dD/dq'
    # to the forcing rows (rows n..2n-1 of forcing_full hold lm.forcing).
    D = sum((sub(scope.parse(d)) for d in model["dissipation"]), sp.S(0))
    for i, qi in enumerate(q):
        FF[len(q) + i] += -D.diff(qi.diff(t))
    order, h, v = [], 0, len(hol)
    for i in range(len(kept)):
        if i in velocity:
            order.append(v)
            v += 1
        else:
            order.append(h)
            h += 1
    return MM, FF, order


def check_eliminations(model, scope, substitute, evaluate, n_args, rng):
    """Each eliminated constraint's Phi must vanish identically once its solution (and the
    others') is substituted: algebraically when SymPy can show it, else at random states.
    `evaluate` compiles expressions of the reduced state; `n_args` counts its arguments after
    the state (accelerations, multipliers), which Phi does not use."""
    for c in model["constraints"]:
        if c.get("treatment") != "eliminated":
            continue
        phi = scope.parse(c["phi"]).xreplace(substitute)
        if sp.simplify(phi) == 0:
            continue
        f = evaluate([phi])
        n = len(model["coordinates"]) - sum(
            1 for k in model["constraints"] if k.get("treatment") == "eliminated")
        for _ in range(10):
            value = f(*random_state(rng, len(scope.params), n), *[0] * n_args)[0]
            if abs(value) > 1e-20:
                raise AssertionError(
                    f"constraint {c['name']}: Phi = {c['phi']} is not zero under "
                    f"{c['coordinate']} = {c['solution']} (Phi = {mpmath.nstr(value, 5)})")


def crosscheck(report, n_states, seed):
    """Compares one scene; returns (summary, max relative difference)."""
    model = report["model"]
    declared = model["coordinates"]
    remaining = report["coordinates"]
    # Inputs are symbols of their own in the derivation; here they are compared like
    # parameters, at random values (a driven run substitutes them, nothing else changes).
    scope = Scope(list(report["parameters"]) + list(report.get("inputs", {})), declared)
    t = scope.t
    rng = random.Random(seed)

    # lagrange's choice of eliminations, checked and applied.
    eliminated = {c["coordinate"]: c for c in model["constraints"]
                  if c.get("treatment") == "eliminated"}
    expected = [c for c in declared if c not in eliminated]
    if remaining != expected:
        raise AssertionError(f"coordinates {remaining}, expected {expected}")
    substitute = {}
    for name, c in eliminated.items():
        sol = scope.parse(c["solution"])
        q = scope.coords[name]
        substitute.update({q.diff(t, 2): sol.diff(t, 2), q.diff(t): sol.diff(t), q: sol})
    kept = [c for c in model["constraints"] if c.get("treatment") == "multiplier"]
    lam_names = [c["multiplier"] for c in kept]
    lam_syms = [scope.lookup(n, 0) for n in lam_names]

    n = len(remaining)
    reduced = Evaluator(scope, remaining, extras=lam_syms)
    n_extra = n + len(lam_syms)  # accelerations and multipliers, after the state
    check_eliminations(model, scope, substitute, reduced.function, n_extra, rng)

    # lagrange: M q'' = f + J^T lam, J q'' = bias, from the report.
    lag_M = reduced.function([scope.parse(e) for row in report["mass_matrix"] for e in row])
    lag_f = reduced.function([scope.parse(e) for e in report["forcing"]])
    rows = {c["name"]: c for c in report["constraints"]}
    lag_J = reduced.function([scope.parse(e) for c in kept for e in rows[c["name"]]["jacobian"]])
    lag_bias = reduced.function([scope.parse(rows[c["name"]]["bias"]) for c in kept])
    reaction_names = list(report["reactions"])
    lag_reactions = reduced.function([scope.parse(report["reactions"][r]) for r in reaction_names])

    # SymPy in the remaining coordinates, with lagrange's kept constraints as multipliers.
    phis = [scope.parse(c["phi"]).xreplace(substitute) for c in kept]
    # A grip is a velocity row too, held while its contact is closed (closed at the start here).
    velocity = {i for i, c in enumerate(kept) if c.get("kind") in ("velocity", "grip")}
    MM, FF, order = sympy_system(model, scope, remaining, substitute, phis, velocity)
    sym_MM, sym_FF = reduced.function(list(MM)), reduced.function(list(FF))
    size = MM.shape[0]

    # The reactions of eliminated constraints: SymPy keeps every constraint instead, in all the
    # declared coordinates, and its multipliers are the reactions.
    by_reaction = {c["reaction"]: c for c in model["constraints"]}
    wanted_full = [r for r in reaction_names if by_reaction[r].get("treatment") == "eliminated"]
    if wanted_full:
        all_phis = [scope.parse(c["phi"]) for c in model["constraints"]]
        all_velocity = {i for i, c in enumerate(model["constraints"])
                        if c.get("kind") in ("velocity", "grip")}
        fMM, fFF, forder = sympy_system(model, scope, declared, {}, all_phis, all_velocity)
        full = Evaluator(scope, declared)
        full_MM, full_FF = full.function(list(fMM)), full.function(list(fFF))
        # The full state from the reduced one: eliminated coordinates from their solutions.
        lift = reduced.function([scope.coords[c].xreplace(substitute) for c in declared]
                                + [scope.coords[c].diff(t).xreplace(substitute) for c in declared])
        constraint_index = {c["reaction"]: i for i, c in enumerate(model["constraints"])}

    worst = 0.0
    for _ in range(n_states):
        state = random_state(rng, len(scope.params), n)
        pad = [0] * n_extra

        # lagrange's q'' and lam from its augmented system [M, -J^T; J, 0].
        M = lag_M(*state, *pad)
        f = lag_f(*state, *pad)
        J = lag_J(*state, *pad)
        bias = lag_bias(*state, *pad)
        k = len(kept)
        A = [[M[i * n + j] for j in range(n)] + [-J[c * n + i] for c in range(k)]
             for i in range(n)]
        A += [[J[c * n + j] for j in range(n)] + [0] * k for c in range(k)]
        x = solve(A, list(f) + list(bias))
        lag_acc, lag_lam = x[:n], x[n:]

        # SymPy's [q'; q''; lam] from mass_matrix_full and forcing_full.
        y = solve([list(r) for r in _rows(sym_MM(*state, *pad), size)], sym_FF(*state, *pad))
        sym_acc = y[n:2 * n]
        sym_lam = [y[2 * n + order[i]] for i in range(len(kept))]
        # SymPy's mass_matrix puts -dPhi/dq against lam on the left (M q'' - J^T lam = f), so
        # its lam has lagrange's sign: generalized constraint force +lam dPhi/dq.
        # (Its `lm.eom` writes the multiplier term with the other sign; we do not use it.)
        for a, b in zip(lag_acc, sym_acc):
            worst = max(worst, relative(a, b))
        for a, b in zip(lag_lam, sym_lam):
            worst = max(worst, relative(a, b))

        if reaction_names:
            values = lag_reactions(*state, *lag_acc, *lag_lam)
            for r, value in zip(reaction_names, values):
                c = by_reaction[r]
                if c.get("treatment") == "multiplier":
                    worst = max(worst, relative(value, sym_lam[lam_names.index(r)]))
                else:
                    full_state = state[:len(scope.params) + 1] + lift(*state, *pad)
                    m = len(model["constraints"])
                    fs = len(declared)
                    z = solve(_rows(full_MM(*full_state, *[0] * fs), 2 * fs + m),
                              full_FF(*full_state, *[0] * fs))
                    worst = max(worst, relative(value, z[2 * fs + forder[constraint_index[r]]]))
                    # The full system's accelerations must agree with the reduced ones too.
                    for i, name in enumerate(remaining):
                        worst = max(worst, relative(z[fs + declared.index(name)], lag_acc[i]))

    parts = [f"q = ({', '.join(remaining)})"]
    if eliminated:
        parts.append("eliminated " + ", ".join(
            f"{c} (Phi = 0 checked)" for c in eliminated))
    if kept:
        parts.append("multipliers " + ", ".join(lam_names))
    parts.append(f"q''{' and lambda' if kept else ''} at {n_states} states")
    if reaction_names:
        parts.append("reactions " + ", ".join(reaction_names))
    return "; ".join(parts), worst


def _rows(flat, size):
    """lambdify returns a Matrix's entries as one flat list; back to rows."""
    flat = list(flat)
    return [flat[i * size:(i + 1) * size] for i in range(size)]


# --------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------


def find_lagrange(given):
    if given:
        return given
    for profile in ("release", "debug"):
        target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
        path = os.path.join(target, profile, "lagrange")
        if os.path.exists(path):
            return path
    sys.exit("crosscheck: no lagrange binary; build one (cargo build --release -p cli) "
             "or pass --lagrange PATH")


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{out.stderr}")
    return out.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", help="scene files (default: examples/**/*.lag)")
    parser.add_argument("--lagrange", default=os.environ.get("LAGRANGE"),
                        help="the lagrange binary (default: $LAGRANGE, else target/{release,debug})")
    parser.add_argument("--generated", action="append", default=[], metavar="FAMILY:N",
                        help="also check `lagrange generate FAMILY N`, e.g. n-link-pendulum:10")
    parser.add_argument("--states", type=int, default=10, help="random states per scene")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random states")
    args = parser.parse_args()
    lagrange = find_lagrange(args.lagrange)

    scenes = list(args.scenes)
    if not scenes and not args.generated:
        scenes = sorted(glob.glob(os.path.join(ROOT, "examples", "**", "*.lag"), recursive=True))
    jobs = [(os.path.relpath(s), s) for s in scenes]
    tmp = tempfile.TemporaryDirectory()
    for spec in args.generated:
        family, _, count = spec.partition(":")
        path = os.path.join(tmp.name, f"{family}-{count}.lag")
        with open(path, "w") as fh:
            fh.write(run([lagrange, "generate", family, count]))
        jobs.append((f"generated {family} {count}", path))

    def check_one(path):
        # Units are checked by lagrange's own tests (tests/units.rs); the scenes here test the
        # mechanics.
        report = json.loads(run([lagrange, "derive", path, "--format", "json", "--no-units"]))
        return crosscheck(report, args.states, args.seed)

    sys.exit(check_each(jobs, check_one, TOLERANCE))


def check_each(jobs, check_one, tolerance):
    """Runs `check_one(path)` -> (summary, worst relative difference) for each (label, path),
    printing one `ok`/`FAIL` line per scene and the count; returns the exit status (1 when any
    failed). A crash is a failure of its scene, not of the run."""
    passed = failed = 0
    for label, path in jobs:
        start = time.time()
        try:
            summary, worst = check_one(path)
            ok = worst < tolerance
            line = f"{summary}; max rel diff {worst:.1e}"
        except Exception as e:
            ok, line = False, f"error: {type(e).__name__}: {e}"
        status = "ok  " if ok else "FAIL"
        print(f"{status} {label}: {line} ({time.time() - start:.1f} s)", flush=True)
        passed, failed = passed + ok, failed + (not ok)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    main()
