"""One right-hand side from Python, and a batch of states: the figures of the Python package.

The 4-link pendulum (`lagrange generate n-link-pendulum 4`): one call of `scene.rhs()` against
SymPy's LagrangesMethod lowered with `lambdify` and solved with NumPy (the usual PyDy-free path),
and `f.batch` on 100,000 states. Every figure is the median of repeats in this one run.

    python crates/python/bench/rhs.py [--lagrange target/release/lagrange]
"""

import argparse
import statistics
import subprocess
import tempfile
import time

import numpy as np
import sympy as sp
from sympy.physics.mechanics import LagrangesMethod, Particle, Point, ReferenceFrame, dynamicsymbols

import lagrange


def per_call(f, repeats=7, target=0.05):
    """Seconds per call: batches sized to about `target` seconds, the median of `repeats`."""
    n = 1
    while True:
        start = time.perf_counter()
        for _ in range(n):
            f()
        took = time.perf_counter() - start
        if took > target or n > 1 << 24:
            break
        n *= 10 if took < target / 10 else 2
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(n):
            f()
        times.append((time.perf_counter() - start) / n)
    return statistics.median(times)


def sympy_rhs(n, values):
    """The n-link pendulum (unit masses and lengths as the generated scene has them) by
    LagrangesMethod, lambdified; y' = [q', solve(M, F)]."""
    q = dynamicsymbols(f"q1:{n + 1}")
    qd = [x.diff() for x in q]
    g = sp.Symbol("g")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    bodies, prev = [], O
    for i in range(n):
        P = prev.locatenew(f"P{i}", values["l"] * (sp.sin(q[i]) * N.x - sp.cos(q[i]) * N.y))
        P.set_vel(N, P.pos_from(O).dt(N))
        particle = Particle(f"p{i}", P, values["m"])
        particle.potential_energy = values["m"] * g * P.pos_from(O).dot(N.y)
        bodies.append(particle)
        prev = P
    lagrangian = sum((b.kinetic_energy(N) - b.potential_energy for b in bodies), 0)
    lm = LagrangesMethod(lagrangian, q)
    lm.form_lagranges_equations()
    args = q + qd + [g]
    M = sp.lambdify(args, lm.mass_matrix, "numpy")
    F = sp.lambdify(args, lm.forcing, "numpy")

    def rhs(t, y):
        a = list(y) + [values["g"]]
        acc = np.linalg.solve(np.asarray(M(*a), dtype=float), np.asarray(F(*a), dtype=float).ravel())
        return np.concatenate([y[n:], acc])

    return rhs


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lagrange", default="target/release/lagrange")
    parser.add_argument("--links", type=int, default=4)
    parser.add_argument("--batch", type=int, default=100_000)
    a = parser.parse_args()
    n = a.links
    text = subprocess.run([a.lagrange, "generate", "n-link-pendulum", str(n)],
                          check=True, capture_output=True, text=True).stdout
    scene = lagrange.loads(text)
    f = scene.rhs()
    params = f.parameters
    values = {"m": 1.0, "l": 1.0, "g": 9.81}
    values.update({k: v for k, v in params.items() if k in values})
    rng = np.random.default_rng(1)
    y = rng.uniform(-1, 1, 2 * n)
    ours = per_call(lambda: f(0.0, y))
    ref = sympy_rhs(n, values)
    np.testing.assert_allclose(f(0.0, y), ref(0.0, y), rtol=1e-9, atol=1e-9)
    theirs = per_call(lambda: ref(0.0, y))
    Y = rng.uniform(-1, 1, (a.batch, 2 * n))
    batch = per_call(lambda: f.batch(Y), repeats=5, target=0.2)
    print(f"{n}-link pendulum, one right-hand side from Python")
    print(f"  lagrange  scene.rhs()           {ours * 1e6:8.2f} µs")
    print(f"  SymPy     lambdify + solve      {theirs * 1e6:8.2f} µs   ({theirs / ours:.1f}× ours)")
    print(f"  lagrange  f.batch({a.batch:,} states) {batch * 1e3:8.2f} ms = {batch / a.batch * 1e9:.0f} ns a state")


if __name__ == "__main__":
    main()
