#!/usr/bin/env python3
"""SciPy's shooting loop on the periodic orbits, the peer of `lagrange-bench orbit --peer`.

What a SciPy user writes to find a periodic orbit and its multipliers: Newton's method on the
return map, the map's Jacobian by forward differences of whole runs of `solve_ivp` (DOP853),
and the multipliers as the eigenvalues of that Jacobian at the fixed point. Both models are
derived by hand here, not lowered from lagrange:

- wheel (examples/contacts/rimless_wheel.lag): McGeer's rimless wheel reduced to the stance
  spoke's angle phi from the slope's normal, (I + m l^2) phi'' = m g l sin(phi + gamma); the
  event phi = alpha (the next spoke lands), and at it phi <- -alpha, phi' <- c phi'. The map
  goes from just after a landing to just after the next, on phi' alone (phi is -alpha there).
- walker (examples/contacts/simplest_walker.lag): Garcia et al.'s simplest walker in the
  paper's limit of massless feet, theta'' = sin(theta - gamma), phi'' = sin(theta - gamma)
  + (theta'^2 - cos(theta - gamma)) sin(phi), the strike at phi = 2 theta past mid-stance,
  and at it theta <- -theta, theta' <- cos(2 theta) theta', phi <- -2 theta,
  phi' <- cos(2 theta) (1 - cos(2 theta)) theta'. The map goes from just after a strike to
  just after the next, on (theta, theta') (phi and phi' follow from them there).
- pendulum (examples/orbits/driven_pendulum.lag): m l^2 theta'' + c theta' + m g l sin(theta)
  = A cos(w t) over one period 2 pi / w, on (theta, theta').

It reads requests from standard input, one JSON object per line:

    {"scene": "wheel" | "walker" | "pendulum", "params": {...}, "start": [...], "rtol": R,
     "step": H, "repeats": N, "span": S}

and for each finds the fixed point from `start` (the wheel: first run to its first landing)
with rtol = atol = R and difference step H (relative), at least `repeats` times and for at
least S seconds, and writes one JSON
line: the fixed point, the multipliers (re, im), the Newton iterations, the runs, the
right-hand sides, and the median wall time of a search. It measures and asserts nothing else.
It makes and uses a virtual environment of its own (tests/sympy/.venv-orbit, pinned NumPy and
SciPy) on first run.
"""

PACKAGES = ["numpy==2.3.5", "scipy==1.16.3"]

from pinned import run_inside  # noqa: E402

run_inside("orbit", PACKAGES)

import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402


class Counter:
    def __init__(self):
        self.runs = 0
        self.evaluations = 0


def wheel_map(p, rtol, counter):
    m, inertia, l, g, gamma = p["m"], p["I"], p["l"], p["g"], p["gamma"]
    alpha = math.pi / 8
    c = (inertia + m * l * l * math.cos(2 * alpha)) / (inertia + m * l * l)
    k = m * g * l / (inertia + m * l * l)

    def rhs(t, y):
        return np.array([y[1], k * math.sin(y[0] + gamma)])

    def landing(t, y):
        return y[0] - alpha

    landing.terminal = True
    landing.direction = 1

    def step(state):
        sol = solve_ivp(rhs, (0.0, 100.0), state, method="DOP853", rtol=rtol, atol=rtol,
                        events=landing)
        counter.runs += 1
        counter.evaluations += sol.nfev
        rate = float(sol.y_events[0][0][1])
        return float(sol.t_events[0][0]), c * rate

    def after_landing(rate):
        return step(np.array([-alpha, rate]))

    return step, after_landing


def walker_map(p, rtol, counter):
    gamma = p["gamma"]

    def rhs(t, y):
        theta, rate, phi, phi_rate = y
        down = math.sin(theta - gamma)
        return np.array([rate, down, phi_rate,
                         down + (rate * rate - math.cos(theta - gamma)) * math.sin(phi)])

    # The swing foot passes the ground at mid-stance (phi = 2 theta near theta = 0), a scuff
    # the paper ignores: the strike is looked for once the stance leg is well past the normal.
    def strike(t, y):
        return y[2] - 2 * y[0] if y[0] < -0.1 else 1.0

    strike.terminal = True
    strike.direction = 1

    def step(state):
        theta, rate = state
        c = math.cos(2 * theta)
        start = np.array([theta, rate, 2 * theta, (1 - c) * rate])
        sol = solve_ivp(rhs, (0.0, 100.0), start, method="DOP853", rtol=rtol, atol=rtol,
                        events=strike)
        counter.runs += 1
        counter.evaluations += sol.nfev
        theta, rate = float(sol.y_events[0][0][0]), float(sol.y_events[0][0][1])
        return np.array([-theta, math.cos(2 * theta) * rate])

    return step


def pendulum_map(p, rtol, counter):
    m, l, g, cd, a, w = p["m"], p["l"], p["g"], p["c"], p["A"], p["w"]
    period = 2 * math.pi / w

    def rhs(t, y):
        return np.array([y[1], (a * math.cos(w * t) - cd * y[1] - m * g * l * math.sin(y[0]))
                         / (m * l * l)])

    def flow(state):
        sol = solve_ivp(rhs, (0.0, period), state, method="DOP853", rtol=rtol, atol=rtol)
        counter.runs += 1
        counter.evaluations += sol.nfev
        return sol.y[:, -1]

    return flow, period


def newton(f, x, step, tolerance=1e-12, limit=30):
    """Newton on g(x) = f(x) - x with the Jacobian of f by forward differences: its last
    Jacobian (at the fixed point) and the iterations."""
    x = np.array(x, dtype=float)
    for iteration in range(1, limit + 1):
        fx = f(x)
        jac = np.empty((len(x), len(x)))
        for j in range(len(x)):
            h = step * max(1.0, abs(x[j]))
            probe = x.copy()
            probe[j] += h
            jac[:, j] = (f(probe) - fx) / h
        residual = fx - x
        if np.max(np.abs(residual)) <= tolerance * max(1.0, np.max(np.abs(x))):
            return x, jac, iteration
        x = x - np.linalg.solve(jac - np.eye(len(x)), residual)
    return x, jac, limit


def search(request):
    counter = Counter()
    p, rtol, step = request["params"], request["rtol"], request["step"]
    if request["scene"] == "wheel":
        first, after = wheel_map(p, rtol, counter)
        _, rate = first(np.array(request["start"], dtype=float))
        fixed, jac, iterations = newton(lambda x: np.array([after(x[0])[1]]), [rate], step)
    elif request["scene"] == "walker":
        fixed, jac, iterations = newton(walker_map(p, rtol, counter), request["start"], step)
    else:
        flow, _ = pendulum_map(p, rtol, counter)
        fixed, jac, iterations = newton(flow, request["start"], step)
    multipliers = np.linalg.eigvals(jac)
    return fixed, multipliers, iterations, counter


def main():
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        walls = []
        # At least `repeats` searches, spanning at least `span` seconds: the machine's speed
        # moves in phases of seconds, and a few milliseconds' searches would see one phase.
        started = time.perf_counter()
        span = request.get("span", 0.0)
        while len(walls) < request["repeats"] or time.perf_counter() - started < span:
            began = time.perf_counter()
            fixed, multipliers, iterations, counter = search(request)
            walls.append(time.perf_counter() - began)
        print(json.dumps({
            "fixed": [float(v) for v in fixed],
            "multipliers": [[float(z.real), float(z.imag)] for z in multipliers],
            "iterations": iterations,
            "runs": counter.runs,
            "evaluations": counter.evaluations,
            "wall": statistics.median(walls),
        }), flush=True)


if __name__ == "__main__":
    main()
