#!/usr/bin/env python3
"""SciPy's event loop on the contact scenes, the peer of `lagrange-bench contacts --peer`.

What a SciPy user writes for a one-sided contact: `solve_ivp` (DOP853) with a terminal event at
the gap, the impulse applied by hand at each event, and a new `solve_ivp` from there, until the
end time. Both models are derived by hand here, not lowered from lagrange:

- ball (examples/contacts/bouncing_ball.lag): y'' = -g, the event y = 0 falling, and at it
  v <- -e*v. The impacts accumulate at a finite time, past which no event loop goes: the loop
  stops once the next flight (2*v/g after an impact) would be shorter than the request's
  `floor` (lagrange-bench passes the flight at which lagrange settles the ball), and the ball
  rests from there.
- block (examples/contacts/rocking_block.lag): Housner's rocking block reduced to its one
  coordinate, the tilt theta, pivoting about the corner on the side s = sign(theta):
  theta'' = -p^2 sin(s*alpha - theta), p^2 = 3g/(4R), R = sqrt(b^2 + h^2), alpha = atan(b/h);
  the event theta = 0, and at it the pivot switches (s <- -s) and theta' <- r*theta' with
  Housner's r = 1 - 3/2 sin^2(alpha). Its impacts accumulate too, where it is released low
  enough: the loop stops once the next flight (r times the last, as a small swing's) would be
  shorter than the `floor`.

It reads requests from standard input, one JSON object per line:

    {"scene": "ball" | "block", "params": {...}, "until": T, "starts": [h0 or theta0, ...],
     "references": [[t_1, t_2, ...] per start], "floors": [flight per start, or 0],
     "target": E, "repeats": R}

and for each it looks for the rtol (= atol) whose worst relative impact-time error over the
starts against the references is at most the target and as close to it as it can get: a
ladder of four tolerances a decade from 1e-3 down, then bisection of log(rtol) between the
loosest rung that meets the target (with every tighter rung scanned meeting it too) and the
next looser one. At that rtol it times every start `repeats` times and writes one JSON line:
the rtol, its error, the impact times at each start, impacts, steps and right-hand sides (of
the middle start), and the median wall time and thread CPU time of a run. It measures and asserts nothing else.
It makes and uses a virtual environment of its own (tests/sympy/.venv-contacts, pinned NumPy
and SciPy) on first run.
"""

PACKAGES = ["numpy==2.3.5", "scipy==1.16.3"]

from pinned import run_inside  # noqa: E402

run_inside("contacts", PACKAGES)

import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402


def ball(params, h0, until, rtol, floor):
    """The ball dropped from h0: its impact times, steps and right-hand sides."""
    g, e = params["g"], params["e"]

    def rhs(t, y):
        return np.array([y[1], -g])

    def floor_hit(t, y):
        return y[0]

    floor_hit.terminal = True
    floor_hit.direction = -1

    t, y = 0.0, np.array([h0, 0.0])
    impacts, steps, evaluations = [], 0, 0
    while t < until:
        sol = solve_ivp(rhs, (t, until), y, method="DOP853", rtol=rtol, atol=rtol,
                        events=floor_hit)
        steps += len(sol.t) - 1
        evaluations += sol.nfev
        if sol.status != 1:
            break
        t = float(sol.t_events[0][0])
        v = float(sol.y_events[0][0][1])
        impacts.append(t)
        y = np.array([0.0, -e * v])
        if 2.0 * e * abs(v) / g < floor:
            # The next flight is shorter than the floor: the ball rests from here.
            break
    return impacts, steps, evaluations


def block(params, theta0, until, rtol, floor):
    """The block released at theta0: its impact times, steps and right-hand sides."""
    b, h, g = params["b"], params["h"], params["g"]
    radius = math.sqrt(b * b + h * h)
    alpha = math.atan(b / h)
    p2 = 3.0 * g / (4.0 * radius)
    ratio = 1.0 - 1.5 * math.sin(alpha) ** 2
    side = 1.0 if theta0 > 0 else -1.0

    t, y = 0.0, np.array([theta0, 0.0])
    impacts, steps, evaluations = [], 0, 0
    while t < until:
        s = side

        def rhs(t, y):
            return np.array([y[1], -p2 * math.sin(s * alpha - y[0])])

        def landing(t, y):
            return s * y[0]

        landing.terminal = True
        landing.direction = -1
        sol = solve_ivp(rhs, (t, until), y, method="DOP853", rtol=rtol, atol=rtol,
                        events=landing)
        steps += len(sol.t) - 1
        evaluations += sol.nfev
        if sol.status != 1:
            break
        t = float(sol.t_events[0][0])
        impacts.append(t)
        y = np.array([0.0, ratio * float(sol.y_events[0][0][1])])
        side = -side
        if len(impacts) >= 2 and ratio * (impacts[-1] - impacts[-2]) < floor:
            # The next flight (that of a small swing shrinks as the rate) is shorter than the
            # floor: the block rests from here.
            break
    return impacts, steps, evaluations


SCENES = {"ball": ball, "block": block}


def error(times, reference):
    """The worst relative error of the impact times; infinite where the counts differ."""
    if len(times) != len(reference):
        return math.inf
    return max((abs(t - r) / r for t, r in zip(times, reference)), default=0.0)


def worst(request, rtol):
    """The worst error over the starts at rtol, and the runs."""
    scene = SCENES[request["scene"]]
    floors = request.get("floors") or [0.0] * len(request["starts"])
    runs = [scene(request["params"], start, request["until"], rtol, floor)
            for start, floor in zip(request["starts"], floors)]
    return max(error(run[0], ref) for run, ref in zip(runs, request["references"])), runs


def search(request):
    """The rtol whose error is at most the target and closest to it; how many were tried."""
    target = request["target"]
    ladder = [10.0 ** (-3.0 - k / 4.0) for k in range(45)]
    errors = []
    for rtol in ladder:
        errors.append(worst(request, rtol)[0])
        # Two rungs in a row ten times inside the target: tighter ones only cost more.
        if len(errors) >= 2 and max(errors[-2:]) <= target / 10.0:
            break
    tried = len(errors)
    # The loosest rung from which every tighter rung scanned meets the target.
    meets = None
    for k in range(len(errors) - 1, -1, -1):
        if errors[k] > target:
            break
        meets = k
    if meets is None:
        return ladder[len(errors) - 1], tried
    if meets == 0:
        return ladder[0], tried
    # Between the next looser rung (too loose) and it, in log(rtol).
    tight, loose = math.log(ladder[meets]), math.log(ladder[meets - 1])
    for _ in range(6):
        middle = 0.5 * (tight + loose)
        tried += 1
        if worst(request, math.exp(middle))[0] <= target:
            tight = middle
        else:
            loose = middle
    return math.exp(tight), tried


def main():
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        rtol, tried = search(request)
        err, runs = worst(request, rtol)
        scene = SCENES[request["scene"]]
        floors = request.get("floors") or [0.0] * len(request["starts"])
        seconds, per_impact, cpu = [], [], []
        for _ in range(max(1, request.get("repeats", 3))):
            for start, floor in zip(request["starts"], floors):
                began, began_cpu = time.perf_counter(), time.thread_time()
                impacts, _, _ = scene(request["params"], start, request["until"], rtol, floor)
                took = time.perf_counter() - began
                cpu.append(time.thread_time() - began_cpu)
                seconds.append(took)
                per_impact.append(took / max(1, len(impacts)))
        middle = runs[len(runs) // 2]
        print(json.dumps({
            "label": request.get("label"), "rtol": rtol, "error": err, "tried": tried,
            "times": [run[0] for run in runs], "impacts": len(middle[0]), "steps": middle[1],
            "evaluations": middle[2], "seconds": statistics.median(seconds),
            "seconds_per_impact": statistics.median(per_impact),
            "cpu_seconds": statistics.median(cpu),
        }), flush=True)


if __name__ == "__main__":
    main()
