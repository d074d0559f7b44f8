#!/usr/bin/env python3
"""Benchmark lagrange's derivation against SymPy's LagrangesMethod and KanesMethod.

It lives beside the cross-check (crosscheck.py) rather than in a new top-level folder: the
design card fixes the top level, and both scripts share the pinned requirements.txt. Unlike
crosscheck.py it asserts nothing; it measures.

For the n-link planar pendulum (point masses m on massless links of length l, every angle
from the downward vertical: the scene `lagrange generate n-link-pendulum N` writes), and
n = 2, 4, 8, 12, 16, it times in the same run:

* SymPy LagrangesMethod: form_lagranges_equations, then mass_matrix and forcing;
* SymPy KanesMethod: kanes_equations, then mass_matrix and forcing;
* lagrange: parse, resolve, derive and lower M and f (`lagrange-bench derive`, median of 5);

and prints the ratios, plus SymPy's operation count after common-subexpression elimination
(sympy.cse on M and f, sympy.count_ops on the replacements and reduced expressions) beside
lagrange's lowered operation count. Each SymPy size runs in a child process with a time
budget (--budget seconds); a size past it is reported as such and larger sizes are skipped.

With --dop853 (and scipy installed), it also times SciPy's DOP853 with a lambdify right-hand
side on the double pendulum to t = 10 at rtol = atol = 1e-9, and lagrange's adaptive
methods at the loosest tolerance that reaches the same final error.

The script creates and uses a virtual environment (tests/sympy/.venv-bench, pinned sympy) on
first run. Usage:
    tests/sympy/sympy_compare.py [--sizes 2,4,8,12,16] [--budget 150] [--dop853]
"""

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
VENV = os.path.join(HERE, ".venv-bench")
PYTHON = os.path.join(VENV, "bin", "python")
PACKAGES = ["sympy==1.14.0", "mpmath==1.3.0", "numpy==2.3.5", "scipy==1.16.3"]


def ensure_venv():
    """Re-runs this script inside the pinned virtual environment, creating it if needed."""
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        return
    if not os.path.exists(PYTHON):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([PYTHON, "-m", "pip", "install", "-q", PACKAGES[0], PACKAGES[1]])
        # numpy and scipy serve only the optional DOP853 comparison.
        subprocess.call([PYTHON, "-m", "pip", "install", "-q", *PACKAGES[2:]])
    os.execv(PYTHON, [PYTHON, *sys.argv])


ensure_venv()

import argparse  # noqa: E402
import json  # noqa: E402
import multiprocessing as mp  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import sympy as sp  # noqa: E402
from sympy.physics.mechanics import (  # noqa: E402
    KanesMethod,
    LagrangesMethod,
    Particle,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

BENCH = os.path.join(ROOT, "target", "release", "lagrange-bench")
LAGRANGE = os.path.join(ROOT, "target", "release", "lagrange")


def chain(n):
    """The n-link pendulum's points and particles, as `lagrange generate` describes it."""
    q = dynamicsymbols(f"q1:{n + 1}")
    u = dynamicsymbols(f"u1:{n + 1}")
    m, l, g = sp.symbols("m l g")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    particles = []
    previous = O
    for i in range(n):
        A = N.orientnew(f"A{i + 1}", "Axis", [q[i], N.z])
        A.set_ang_vel(N, u[i] * N.z)
        # The link hangs along -A.y: position l*(sin q, -cos q) in N, fixed in A.
        P = previous.locatenew(f"P{i + 1}", -l * A.y)
        P.v2pt_theory(previous, N, A)
        particles.append(Particle(f"p{i + 1}", P, m))
        previous = P
    return q, u, (m, l, g), N, particles


def lagranges(n):
    q, _u, (m, l, g), N, particles = chain(n)
    start = time.perf_counter()
    # Velocities by differentiating the positions, as lagrange does and as LagrangesMethod
    # is usually fed.
    t = dynamicsymbols._t
    T, V = 0, 0
    for k in range(len(particles)):
        x = l * sum(sp.sin(q[i]) for i in range(k + 1))
        y = -l * sum(sp.cos(q[i]) for i in range(k + 1))
        T += m * (sp.diff(x, t) ** 2 + sp.diff(y, t) ** 2) / 2
        V += m * g * y
    L = T - V
    lm = LagrangesMethod(L, q)
    lm.form_lagranges_equations()
    M, f = lm.mass_matrix, lm.forcing
    return time.perf_counter() - start, M, f


def kanes(n):
    q, u, (m, l, g), N, particles = chain(n)
    start = time.perf_counter()
    kd = [sp.diff(q[i], dynamicsymbols._t) - u[i] for i in range(n)]
    forces = [(p.point, -m * g * N.y) for p in particles]
    km = KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    km.kanes_equations(particles, forces)
    M, f = km.mass_matrix, km.forcing
    return time.perf_counter() - start, M, f


def cse_ops(M, f):
    exprs = list(M) + list(f)
    replacements, reduced = sp.cse(exprs)
    return sum(sp.count_ops(e) for _, e in replacements) + sum(sp.count_ops(e) for e in reduced)


def child(kind, n, with_cse, queue):
    seconds, M, f = (lagranges if kind == "lagrange" else kanes)(n)
    queue.put(("time", seconds))
    if with_cse:
        start = time.perf_counter()
        ops = cse_ops(M, f)
        queue.put(("cse", ops, time.perf_counter() - start))


def timed_child(kind, n, budget, with_cse):
    """Runs one SymPy derivation in a child process: (seconds or None, cse ops or None)."""
    queue = mp.Queue()
    proc = mp.Process(target=child, args=(kind, n, with_cse, queue))
    proc.start()
    seconds, ops = None, None
    deadline = time.monotonic() + budget
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            break
        try:
            msg = queue.get(timeout=min(remaining, 1.0))
        except Exception:
            if not proc.is_alive() and queue.empty():
                break
            continue
        if msg[0] == "time":
            seconds = msg[1]
            if not with_cse:
                break
        else:
            ops = msg[1]
            break
    if proc.is_alive():
        proc.terminate()
    proc.join()
    return seconds, ops


def lagrange_figures(n):
    out = subprocess.run([BENCH, "derive", "n-link-pendulum", str(n)], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def fmt(s):
    if s is None:
        return "over budget"
    return f"{s * 1e3:.1f} ms" if s < 1 else f"{s:.2f} s"


def derivation_table(sizes, budget):
    print("## Derivation: SymPy 1.14 against lagrange, n-link pendulum (same machine, same run)")
    print(f"{'n':>3} {'Lagrange(SymPy)':>16} {'Kane(SymPy)':>12} {'lagrange':>10} "
          f"{'Lagr/ours':>10} {'Kane/ours':>10} {'SymPy cse ops':>14} {'our ops':>8}")
    skip = {"lagrange": False, "kane": False}
    for n in sizes:
        ours = lagrange_figures(n)
        row = {}
        for kind in ("lagrange", "kane"):
            if skip[kind]:
                row[kind] = (None, None)
                continue
            # CSE of Kane's (smaller) result gives SymPy's operation count.
            seconds, ops = timed_child(kind, n, budget, with_cse=(kind == "kane"))
            if seconds is None:
                skip[kind] = True
            row[kind] = (seconds, ops)
        lt, kt = row["lagrange"][0], row["kane"][0]
        ratio = lambda s: f"{s / ours['lowered_s']:.0f}x" if s else "-"
        cse = row["kane"][1]
        print(f"{n:>3} {fmt(lt):>16} {fmt(kt):>12} {fmt(ours['lowered_s']):>10} "
              f"{ratio(lt):>10} {ratio(kt):>10} {cse if cse is not None else '-':>14} "
              f"{ours['ops']:>8}", flush=True)
    print(f"(lagrange: parse + resolve + derive + lower M and f, median of 5; SymPy: one run "
          f"each, budget {budget} s per size; SymPy cse ops: count_ops after sympy.cse of "
          f"Kane's M and f)\n")


def double_pendulum_rhs():
    import numpy as np

    _, M, f = lagranges(2)
    q = dynamicsymbols("q1:3")
    qd = [sp.diff(x, dynamicsymbols._t) for x in q]
    m, l, g = sp.symbols("m l g")
    a, b = sp.symbols("a1:3"), sp.symbols("b1:3")
    subs = dict(zip(qd, b)) | dict(zip(q, a))
    Mf = sp.lambdify([a, b, m, l, g], M.subs(subs), "numpy")
    ff = sp.lambdify([a, b, m, l, g], f.subs(subs), "numpy")

    def rhs(_t, y):
        qq, rr = y[:2], y[2:]
        acc = np.linalg.solve(np.array(Mf(qq, rr, 1.0, 1.0, 9.81), dtype=float),
                              np.array(ff(qq, rr, 1.0, 1.0, 9.81), dtype=float).ravel())
        return np.concatenate([rr, acc])

    return rhs


def lagrange_run(method, tol):
    scene = os.path.join(ROOT, "examples", "classics", "double_pendulum.lag")
    proc = subprocess.run(
        [LAGRANGE, "simulate", scene, "--until", "10", "--method", method, "--tolerance",
         str(tol), "--output", "theta1, theta2, theta1', theta2'"],
        check=True, capture_output=True, text=True)
    last = [float(v) for v in proc.stdout.strip().splitlines()[-1].split(",")]
    summary = proc.stderr
    wall = float(summary.split(" s wall time")[0].rsplit(",", 1)[1].strip())
    evals = int(summary.split(" right-hand-side")[0].rsplit(",", 1)[1].strip())
    return last[1:], wall, evals


def dop853_comparison():
    try:
        import numpy as np
        from scipy.integrate import solve_ivp
    except ImportError:
        print("(scipy is not installed: no DOP853 comparison)")
        return
    print("## Double pendulum to t = 10: SciPy DOP853 + lambdify against lagrange")
    reference, _, _ = lagrange_run("dop853", 1e-14)
    rhs = double_pendulum_rhs()
    y0 = [np.pi / 2, np.pi / 2, 0.0, 0.0]
    times = []
    for _ in range(5):
        start = time.perf_counter()
        sol = solve_ivp(rhs, (0, 10), y0, method="DOP853", rtol=1e-9, atol=1e-9)
        times.append(time.perf_counter() - start)
    scipy_time = statistics.median(times)
    scipy_error = max(abs(a - b) for a, b in zip(sol.y[:, -1], reference))
    print(f"SciPy DOP853 rtol = atol = 1e-9: error {scipy_error:.2e}, {sol.nfev} evaluations, "
          f"{fmt(scipy_time)} (median of 5; solve_ivp only)")
    for method in ("dopri5", "dop853"):
        for k in range(4, 15):
            tol = 10.0 ** -k
            runs = [lagrange_run(method, tol) for _ in range(5)]
            error = max(abs(a - b) for a, b in zip(runs[0][0], reference))
            if error <= scipy_error:
                wall = statistics.median(r[1] for r in runs)
                # The summary prints the wall time to the millisecond: for runs this short,
                # `lagrange-bench precision` gives the finer figure.
                print(f"lagrange {method} tol {tol:.0e}: error {error:.2e}, {runs[0][2]} "
                      f"evaluations, {fmt(wall)} (median of 5; integration only, 1 ms "
                      f"resolution): {scipy_time / wall:.0f}x faster than SciPy")
                break
        else:
            print(f"lagrange {method}: no tolerance down to 1e-14 reached the SciPy error")
    print()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", default="2,4,8,12,16")
    parser.add_argument("--budget", type=float, default=150.0)
    parser.add_argument("--dop853", action="store_true")
    parser.add_argument("--skip-derivation", action="store_true")
    args = parser.parse_args()
    for binary in (BENCH, LAGRANGE):
        if not os.path.exists(binary):
            sys.exit(f"{binary} is missing: run `cargo build --release -p cli -p bench` first")
    print(f"sympy {sp.__version__}, python {sys.version.split()[0]}\n")
    if not args.skip_derivation:
        derivation_table([int(s) for s in args.sizes.split(",")], args.budget)
    if args.dop853:
        dop853_comparison()


if __name__ == "__main__":
    main()
