#!/usr/bin/env python3
"""SciPy's least_squares on the fitting examples, the peer of `lagrange-bench fit --peer`.

The fit a SciPy user writes to estimate parameters from a recording: the scene's equations
formed by sympy.physics.mechanics.LagrangesMethod, the accelerations solved symbolically and
turned into a Python function by sympy.lambdify, the residuals model - data at the data's
times from scipy.integrate.solve_ivp (DOP853, t_eval the data's times), and
scipy.optimize.least_squares with its defaults: method 'trf', the Jacobian by 2-point finite
differences of whole runs, ftol = xtol = gtol = 1e-8. The two scenes:

- pendulum (examples/fitting/damped_pendulum.lag): a bob of mass m on a light rod of length
  L, damped at the pivot by the torque -c theta'; free L and c, the column theta.
- cart (examples/fitting/cart_pendulum.lag): a cart of mass M on a rail with viscous friction
  b, pushed by the force F(t); from it hangs a pole of mass m, length L and inertia I about
  its centre; free b and I, the columns x and theta. F is the recorded push, interpolated
  piecewise linearly (np.interp) as lagrange interpolates its series inputs.

It reads requests from standard input, one JSON object per line:

    {"scene": "pendulum" | "cart", "data": CSV, "input": CSV or null, "params": {...},
     "start": {...}, "free": [NAMES], "columns": [NAMES], "rtol": R, "repeats": N}

`params` are the fixed parameters, `start` the free ones' start values and the state's
(NAME and NAME_rate), `free` the order of the estimates. For each it derives and lambdifies the
scene once (timed apart, `load`), then fits `repeats` times, and writes one JSON line: the
estimates, nfev, njev (nfev leaves out the runs of the differences: `runs` counts
every one), the cost (least_squares' own, half the sum of squares), its status and
message, the right-hand sides of the last fit, and the median wall time of a fit. It measures
and asserts nothing else. It makes and uses a virtual environment of its own
(tests/sympy/.venv-fit, pinned NumPy, SciPy and SymPy) on first run.
"""

PACKAGES = ["numpy==2.3.5", "scipy==1.16.3", "sympy==1.14.0"]

from pinned import run_inside  # noqa: E402

run_inside("fit", PACKAGES)

import csv  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402
from sympy.physics.mechanics import (  # noqa: E402
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
)


def pendulum():
    """The damped pendulum's coordinates, its symbols by name, and its equations."""
    m, length, g, c = sp.symbols("m L g c")
    theta = dynamicsymbols("theta")
    n = ReferenceFrame("N")
    rod = n.orientnew("A", "Axis", [theta, n.z])
    pivot = Point("O")
    pivot.set_vel(n, 0)
    # The rod's frame turned by theta from the downward vertical: the bob is L along -A.y.
    place = pivot.locatenew("P", -length * rod.y)
    place.v2pt_theory(pivot, n, rod)
    bob = Particle("bob", place, m)
    bob.potential_energy = m * g * place.pos_from(pivot).dot(n.y)
    # The dissipation c/2 theta'^2 as the torque it exerts on the rod.
    damping = [(rod, -c * theta.diff() * n.z)]
    method = LagrangesMethod(Lagrangian(n, bob), [theta], forcelist=damping, frame=n)
    return [theta], {"m": m, "L": length, "g": g, "c": c}, method


def cart():
    """The pushed cart and its pole: coordinates, symbols by name, the input F's symbol, and
    the equations."""
    big_m, m, length, g, b, i_pole, push = sp.symbols("M m L g b I F")
    x, theta = dynamicsymbols("x theta")
    n = ReferenceFrame("N")
    pole_frame = n.orientnew("B", "Axis", [theta, n.z])
    origin = Point("O")
    origin.set_vel(n, 0)
    on_rail = origin.locatenew("P", x * n.x)
    on_rail.set_vel(n, x.diff() * n.x)
    centre = on_rail.locatenew("G", -length / 2 * pole_frame.y)
    centre.v2pt_theory(on_rail, n, pole_frame)
    carriage = Particle("cart", on_rail, big_m)
    carriage.potential_energy = 0
    pole = RigidBody("pole", centre, pole_frame, m, (inertia(pole_frame, 0, 0, i_pole), centre))
    pole.potential_energy = m * g * centre.pos_from(origin).dot(n.y)
    # The rail's friction (the dissipation b/2 x'^2) and the push, both on the cart.
    forces = [(on_rail, (push - b * x.diff()) * n.x)]
    method = LagrangesMethod(Lagrangian(n, carriage, pole), [x, theta], forcelist=forces, frame=n)
    symbols = {"M": big_m, "m": m, "L": length, "g": g, "b": b, "I": i_pole}
    return [x, theta], symbols, method, push


def load(request):
    """The right-hand side f(t, y, free) with the fixed parameters substituted, the state's
    names in order, and the start state."""
    push = None
    if request["scene"] == "pendulum":
        coords, symbols, method = pendulum()
    else:
        coords, symbols, method, push = cart()
    method.form_lagranges_equations()
    accelerations = method.mass_matrix.LUsolve(method.forcing)
    q = sp.symbols(f"q0:{len(coords)}")
    u = sp.symbols(f"u0:{len(coords)}")
    plain = {c.diff(): v for c, v in zip(coords, u)}
    plain.update({c: v for c, v in zip(coords, q)})
    fixed = {symbols[k]: v for k, v in request["params"].items()}
    free = [symbols[k] for k in request["free"]]
    exprs = [e.subs(plain).subs(fixed) for e in accelerations]
    arguments = [*q, *u, *free] + ([push] if push is not None else [])
    accel = sp.lambdify(arguments, exprs, "math")
    names = [str(c.func) for c in coords]
    start = request["start"]
    y0 = [start.get(nm, 0.0) for nm in names] + [start.get(nm + "_rate", 0.0) for nm in names]
    k = len(coords)

    if push is None:

        def rhs(t, y, theta):
            a = accel(*y, *theta)
            return [*y[k:], *a]

    else:
        table = read_csv(request["input"])
        times, values = np.array(table["t"]), np.array(table["F"])

        def rhs(t, y, theta):
            a = accel(*y, *theta, float(np.interp(t, times, values)))
            return [*y[k:], *a]

    return rhs, names, y0


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {name: [float(r[name]) for r in rows] for name in rows[0]}


def main():
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        began = time.perf_counter()
        rhs, names, y0 = load(request)
        loaded = time.perf_counter() - began
        data = read_csv(request["data"])
        times = np.array(data["t"])
        rows = [names.index(c) for c in request["columns"]]
        measured = np.concatenate([np.array(data[c]) for c in request["columns"]])
        rtol = request["rtol"]
        calls = [0]
        runs = [0]

        def counted(t, y, theta):
            calls[0] += 1
            return rhs(t, y, theta)

        def residuals(theta):
            runs[0] += 1
            sol = solve_ivp(counted, (times[0], times[-1]), y0, method="DOP853", t_eval=times,
                            rtol=rtol, atol=rtol, args=(tuple(theta),))
            return np.concatenate([sol.y[r] for r in rows]) - measured

        x0 = [request["start"][nm] for nm in request["free"]]
        walls = []
        for _ in range(request["repeats"]):
            calls[0] = runs[0] = 0
            began = time.perf_counter()
            result = least_squares(residuals, x0)
            walls.append(time.perf_counter() - began)
        print(json.dumps({
            "estimates": [float(v) for v in result.x],
            "nfev": int(result.nfev),
            "njev": int(result.njev),
            "cost": float(result.cost),
            "status": int(result.status),
            "message": result.message,
            "runs": runs[0],
            "rhs": calls[0],
            "load": loaded,
            "wall": statistics.median(walls),
        }), flush=True)


if __name__ == "__main__":
    main()
