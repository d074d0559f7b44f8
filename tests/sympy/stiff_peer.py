#!/usr/bin/env python3
"""SciPy's stiff integrators on the stiffness ladder, the peer of `lagrange-bench stiffness`.

The scene is examples/classics/stiff_spring_pendulum.lag: a bob of mass m on a spring of
stiffness k and rest length L0 with a dashpot along it at damping ratio zeta, in polar
coordinates (r, theta), released at rest from 60 degrees at the spring's static stretch:

    m r'' = m r theta'^2 + m g cos(theta) - k (r - L0) - 2 zeta sqrt(k m) r'
    r theta'' = -2 r' theta' - g sin(theta)

Its right-hand side and its exact Jacobian are written here by hand in NumPy (not lowered
from lagrange), and handed to `scipy.integrate.solve_ivp` with method Radau and BDF at
rtol = atol = TOL, to t = 10, for each k of the ladder. For each run it prints (or, with
--json, writes one JSON object per line) the steps, right-hand-side evaluations, Jacobian
evaluations, LU factorizations, the wall time (the fastest of --repeat runs) and the error at
t = 10 against a reference: with --reference FILE, the JSON lines `lagrange-bench stiffness`
computed, so both sides are measured against the same numbers; without, SciPy's own Radau at
a hundredth of the tolerance, for k up to 1e10 only (at k = 1e12 and rtol = 1e-10 it ran past
five minutes here without finishing, so larger k show no error then).

Like sympy_compare.py it measures and asserts nothing. It makes and uses a virtual
environment of its own (tests/sympy/.venv-stiff, pinned NumPy and SciPy) on first run.
Usage:
    tests/sympy/stiff_peer.py [--ks 1e4,1e6,1e8,1e10,1e12] [--tol 1e-8] [--repeat 3] [--json]
"""

PACKAGES = ["numpy==2.3.5", "scipy==1.16.3"]

from pinned import run_inside  # noqa: E402

run_inside("stiff", PACKAGES)

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

M, L0, G, ZETA = 1.0, 1.0, 9.81, 5.0
T_END = 10.0


def problem(k):
    """The right-hand side, its Jacobian and the start for stiffness k."""
    c = 2.0 * ZETA * math.sqrt(k * M)

    def rhs(t, y):
        r, th, rd, thd = y
        s, co = math.sin(th), math.cos(th)
        return np.array([
            rd,
            thd,
            r * thd * thd + G * co - (k * (r - L0) + c * rd) / M,
            (-2.0 * rd * thd - G * s) / r,
        ])

    def jac(t, y):
        r, th, rd, thd = y
        s, co = math.sin(th), math.cos(th)
        return np.array([
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [thd * thd - k / M, -G * s, -c / M, 2.0 * r * thd],
            [(2.0 * rd * thd + G * s) / (r * r), -G * co / r, -2.0 * thd / r, -2.0 * rd / r],
        ])

    start = np.array([L0 + M * G / k, math.pi / 3.0, 0.0, 0.0])
    return rhs, jac, start


def run(k, method, tol, repeat):
    rhs, jac, start = problem(k)
    best, sol = math.inf, None
    for _ in range(repeat):
        began = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, T_END), start, method=method, jac=jac, rtol=tol, atol=tol)
        best = min(best, time.perf_counter() - began)
    return sol, best


def references(ks, path, tol):
    """The state at t = 10 for each k: from lagrange-bench's JSON lines, or SciPy's own."""
    found = {}
    if path:
        with open(path) as f:
            for line in f:
                row = json.loads(line)
                if row.get("reference"):
                    found[float(row["k"])] = np.array(row["state"])
    for k in ks:
        if k not in found and k <= 1e10:
            sol, _ = run(k, "Radau", tol / 100.0, 1)
            found[k] = sol.y[:, -1]
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ks", default="1e4,1e6,1e8,1e10,1e12")
    parser.add_argument("--tol", type=float, default=1e-8)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--reference", help="JSON lines with the reference states")
    parser.add_argument("--json", action="store_true", help="one JSON object per run")
    args = parser.parse_args()
    ks = [float(k) for k in args.ks.split(",")]
    refs = references(ks, args.reference, args.tol)
    if not args.json:
        print(f"SciPy solve_ivp with the exact Jacobian, rtol = atol = {args.tol:g}, to t = {T_END:g}")
        print(f"{'k':>8} {'method':>6} {'steps':>7} {'f evals':>8} {'jacs':>5} {'LUs':>6} "
              f"{'time':>9} {'error':>9}")
    for k in ks:
        for method in ("Radau", "BDF"):
            sol, seconds = run(k, method, args.tol, args.repeat)
            if sol.status != 0:
                error = math.inf
            elif k not in refs:
                error = math.nan
            else:
                error = float(np.max(np.abs(sol.y[:, -1] - refs[k])))
            row = {
                "k": k, "method": f"scipy-{method.lower()}", "steps": len(sol.t) - 1,
                "evaluations": int(sol.nfev), "jacobians": int(sol.njev), "lu": int(sol.nlu),
                "seconds": seconds, "error": error, "ok": sol.status == 0,
            }
            if args.json:
                print(json.dumps(row), flush=True)
            else:
                print(f"{k:>8.0e} {method:>6} {row['steps']:>7} {row['evaluations']:>8} "
                      f"{row['jacobians']:>5} {row['lu']:>6} {seconds:>8.3f}s {error:>9.1e}",
                      flush=True)


if __name__ == "__main__":
    main()
