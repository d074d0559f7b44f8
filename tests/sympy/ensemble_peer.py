#!/usr/bin/env python3
"""SciPy's DOP853 on the double pendulum's flip-time map, the peer of `lagrange-bench ensemble`.

The scene is examples/classics/double_pendulum_flip.lag: two unit masses on rods of 1 m under
g = 9.81, released at rest from the angles (a1, a2), run until either angle reaches +-pi (the
first flip) or t = 10. Here its Lagrangian is written in SymPy, its equations formed by
sympy.physics.mechanics.LagrangesMethod, the accelerations solved symbolically and turned into
a Python function by sympy.lambdify; scipy.integrate.solve_ivp integrates it with DOP853 at
rtol = atol = TOL, the flips as terminal events. Deriving and lambdifying happen once, before
any run is timed.

The starts come on standard input, one JSON object {"a1": .., "a2": ..} a line (the sample
of the map lagrange-bench chose); for each it writes one JSON line: the start, the time of
the first flip (or 10), the wall time and the CPU time of the run, and the number of
right-hand sides.

It measures and asserts nothing. It makes and uses a virtual environment of its own
(tests/sympy/.venv-ensemble, pinned NumPy, SciPy and SymPy) on first run.
Usage:
    echo '{"a1": 2, "a2": 2}' | tests/sympy/ensemble_peer.py [--tol 1e-10] [--until 10]
"""

import sys

PACKAGES = ["numpy==2.3.5", "scipy==1.16.3", "sympy==1.14.0"]

from pinned import run_inside  # noqa: E402

run_inside("ensemble", PACKAGES)

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import sympy as sp  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols  # noqa: E402

VALUES = {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81}


def accelerations():
    """The accelerations of the two angles as a function of (theta1, theta2, rates)."""
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g", positive=True)
    th1, th2 = dynamicsymbols("theta1 theta2")
    t = dynamicsymbols._t
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    speed2 = lambda x, y: sp.diff(x, t) ** 2 + sp.diff(y, t) ** 2  # noqa: E731
    kinetic = m1 * speed2(x1, y1) / 2 + m2 * speed2(x2, y2) / 2
    potential = m1 * g * y1 + m2 * g * y2
    method = LagrangesMethod(kinetic - potential, [th1, th2])
    method.form_lagranges_equations()
    solved = method.mass_matrix.LUsolve(method.forcing)
    w1, w2 = dynamicsymbols("theta1 theta2", 1)
    q1, q2, u1, u2 = sp.symbols("q1 q2 u1 u2")
    plain = {w1: u1, w2: u2, th1: q1, th2: q2}
    values = {m1: VALUES["m1"], m2: VALUES["m2"], l1: VALUES["l1"], l2: VALUES["l2"], g: VALUES["g"]}
    exprs = [sp.simplify(e.subs(plain).subs(values)) for e in solved]
    return sp.lambdify((q1, q2, u1, u2), exprs, "math")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument("--until", type=float, default=10.0)
    args = parser.parse_args()
    acc = accelerations()

    def rhs(t, y):
        a1, a2 = acc(y[0], y[1], y[2], y[3])
        return [y[2], y[3], a1, a2]

    events = []
    for k in (0, 1):
        for side in (math.pi, -math.pi):
            event = lambda t, y, k=k, side=side: y[k] - side  # noqa: E731
            event.terminal = True
            events.append(event)

    for line in sys.stdin:
        if not line.strip():
            continue
        start = json.loads(line)
        y0 = [start["a1"], start["a2"], 0.0, 0.0]
        began, began_cpu = time.perf_counter(), time.process_time()
        sol = solve_ivp(rhs, (0.0, args.until), y0, method="DOP853", rtol=args.tol,
                        atol=args.tol, events=events)
        seconds, cpu = time.perf_counter() - began, time.process_time() - began_cpu
        print(json.dumps({"a1": start["a1"], "a2": start["a2"], "t": float(sol.t[-1]),
                          "seconds": seconds, "cpu_seconds": cpu,
                          "evaluations": int(sol.nfev),
                          "ok": sol.status >= 0}), flush=True)


if __name__ == "__main__":
    main()
