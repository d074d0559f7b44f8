#!/usr/bin/env python3
"""Benchmark lagrange's derivation against SymEngine and SymPy's LagrangesMethod and KanesMethod.

It lives beside the cross-check (crosscheck.py) rather than in a new top-level folder: the
design card fixes the top level, and both scripts share the pinned requirements.txt. Unlike
crosscheck.py it asserts nothing; it measures.

For the n-link planar pendulum (point masses m on massless links of length l, every angle
from the downward vertical: the scene `lagrange generate n-link-pendulum N` writes) and the
same chain hinged to a sliding cart (`n-link-pendulum-on-cart`), n = 4, 8, 12, 16, 24, 32, it
times in the same run:

* lagrange, the whole process: `lagrange derive --format json` of the generated scene, from
  start to exit (parse, resolve, derive, simplify, verify, print), median of 3, with its peak
  resident memory;
* lagrange's library figure: parse, resolve, derive and lower M and f (`lagrange-bench
  derive`, median of 5), and the lowered operation count;
* SymEngine (C++, through its Python binding): the raw Euler-Lagrange derivation of the same
  chain, with symbols for the angles and rates: positions, velocities by differentiating the
  positions, T and V, then M_ij = d2L/dq'_i dq'_j and f_i = dL/dq_i - sum_j d2L/dq'_i dq_j q'_j,
  with no expansion, no simplification and no printing (median of 3);
* SymPy LagrangesMethod: form_lagranges_equations, then mass_matrix and forcing;
* SymPy KanesMethod: kanes_equations, then mass_matrix and forcing;

and prints the ratios (theirs over ours: above 1 means lagrange is faster), plus SymPy's
operation count after common-subexpression elimination (sympy.cse on M and f,
sympy.count_ops on the replacements and reduced expressions) beside lagrange's lowered
operation count. Each SymPy size runs in a child process with a time budget (--budget
seconds); a size past it is reported as such and larger sizes are skipped.

With --dop853 (and scipy installed), it also times SciPy's DOP853 with a lambdify right-hand
side on the double pendulum to t = 10 at rtol = atol = 1e-9, and lagrange's adaptive
methods at the loosest tolerance that reaches the same final error.

The script creates and uses a virtual environment (tests/sympy/.venv-bench, pinned sympy and
symengine) on first run. Usage:
    tests/sympy/sympy_compare.py [--sizes 4,8,12,16,24,32] [--families pendulum,cart]
                                 [--budget 150] [--no-sympy] [--plot FILE.svg] [--dop853]
"""

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
VENV = os.path.join(HERE, ".venv-bench")
PYTHON = os.path.join(VENV, "bin", "python")
PACKAGES = [
    "sympy==1.14.0", "mpmath==1.3.0", "symengine==0.15.0", "numpy==2.3.5", "scipy==1.16.3",
]


def ensure_venv():
    """Re-runs this script inside the pinned virtual environment, creating it if needed."""
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        return
    if not os.path.exists(PYTHON):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([PYTHON, "-m", "pip", "install", "-q", *PACKAGES[:3]])
        # numpy and scipy serve only the optional DOP853 comparison.
        subprocess.call([PYTHON, "-m", "pip", "install", "-q", *PACKAGES[3:]])
    else:
        # An environment made before SymEngine joined the comparison gets it now.
        probe = subprocess.run([PYTHON, "-c", "import symengine"], capture_output=True)
        if probe.returncode != 0:
            subprocess.check_call([PYTHON, "-m", "pip", "install", "-q", PACKAGES[2]])
    os.execv(PYTHON, [PYTHON, *sys.argv])


ensure_venv()

import argparse  # noqa: E402
import json  # noqa: E402
import multiprocessing as mp  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import symengine as se  # noqa: E402
import sympy as sp  # noqa: E402
from sympy.physics.mechanics import (  # noqa: E402
    KanesMethod,
    LagrangesMethod,
    Particle,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

# Cargo's target directory, wherever CARGO_TARGET_DIR puts it.
TARGET = os.environ.get("CARGO_TARGET_DIR") or os.path.join(ROOT, "target")
BENCH = os.path.join(TARGET, "release", "lagrange-bench")
LAGRANGE = os.path.join(TARGET, "release", "lagrange")


def chain(n, cart):
    """The n-link pendulum's points and particles (on a cart of mass M sliding along x when
    `cart`), as `lagrange generate` describes it: coordinates, speeds, the parameters
    (m, l, g, M), the frame and the particles."""
    q = list(dynamicsymbols(f"q1:{n + 1}"))
    u = list(dynamicsymbols(f"u1:{n + 1}"))
    m, l, g, M = sp.symbols("m l g M")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    particles = []
    previous = O
    if cart:
        x, v = dynamicsymbols("x v")
        C = O.locatenew("C", x * N.x)
        C.set_vel(N, v * N.x)
        particles.append(Particle("cart", C, M))
        previous = C
        q, u = [x, *q], [v, *u]
    angles, rates = q[-n:], u[-n:]
    for i in range(n):
        A = N.orientnew(f"A{i + 1}", "Axis", [angles[i], N.z])
        A.set_ang_vel(N, rates[i] * N.z)
        # The link hangs along -A.y: position l*(sin q, -cos q) in N, fixed in A.
        P = previous.locatenew(f"P{i + 1}", -l * A.y)
        P.v2pt_theory(previous, N, A)
        particles.append(Particle(f"p{i + 1}", P, m))
        previous = P
    return q, u, (m, l, g, M), N, particles


def lagranges(n, cart):
    q, _u, (m, l, g, M), N, particles = chain(n, cart)
    start = time.perf_counter()
    # Velocities by differentiating the positions, as lagrange does and as LagrangesMethod
    # is usually fed.
    t = dynamicsymbols._t
    angles = q[-n:]
    x0 = q[0] if cart else 0
    T = M * sp.diff(x0, t) ** 2 / 2 if cart else 0
    V = 0
    for k in range(n):
        x = x0 + l * sum(sp.sin(angles[i]) for i in range(k + 1))
        y = -l * sum(sp.cos(angles[i]) for i in range(k + 1))
        T += m * (sp.diff(x, t) ** 2 + sp.diff(y, t) ** 2) / 2
        V += m * g * y
    L = T - V
    lm = LagrangesMethod(L, q)
    lm.form_lagranges_equations()
    M, f = lm.mass_matrix, lm.forcing
    return time.perf_counter() - start, M, f


def kanes(n, cart):
    q, u, (m, l, g, M), N, particles = chain(n, cart)
    start = time.perf_counter()
    kd = [sp.diff(q[i], dynamicsymbols._t) - u[i] for i in range(len(q))]
    forces = [(p.point, -p.mass * g * N.y) for p in particles]
    km = KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    km.kanes_equations(particles, forces)
    M, f = km.mass_matrix, km.forcing
    return time.perf_counter() - start, M, f


def symengine_raw(n, cart):
    """SymEngine's Euler-Lagrange derivation of the chain, raw: symbols for the coordinates
    and their rates, velocities by differentiating the positions, then M and f by
    differentiating L, with nothing expanded, simplified or printed. Returns the seconds."""
    start = time.perf_counter()
    angles = [se.Symbol(f"q{i + 1}") for i in range(n)]
    angle_rates = [se.Symbol(f"u{i + 1}") for i in range(n)]
    m, l, g, M = se.symbols("m l g M")
    coords, rates = list(angles), list(angle_rates)
    x, y = se.Integer(0), se.Integer(0)
    T, V = se.Integer(0), se.Integer(0)
    if cart:
        x, v = se.Symbol("x"), se.Symbol("v")
        coords, rates = [x, *coords], [v, *rates]
        T += M * v**2 / 2

    def rate_of(e):
        return sum((se.diff(e, c) * r for c, r in zip(coords, rates)), se.Integer(0))

    for k in range(n):
        x = x + l * se.sin(angles[k])
        y = y - l * se.cos(angles[k])
        T += m * (rate_of(x) ** 2 + rate_of(y) ** 2) / 2
        V += m * g * y
    L = T - V
    mass, forcing = [], []
    for i in range(len(coords)):
        p = se.diff(L, rates[i])
        mass.append([se.diff(p, r) for r in rates])
        forcing.append(se.diff(L, coords[i])
                       - sum((se.diff(p, c) * r for c, r in zip(coords, rates)), se.Integer(0)))
    return time.perf_counter() - start


def cse_ops(M, f):
    exprs = list(M) + list(f)
    replacements, reduced = sp.cse(exprs)
    return sum(sp.count_ops(e) for _, e in replacements) + sum(sp.count_ops(e) for e in reduced)


def child(kind, n, cart, with_cse, queue):
    seconds, M, f = (lagranges if kind == "lagrange" else kanes)(n, cart)
    queue.put(("time", seconds))
    if with_cse:
        start = time.perf_counter()
        ops = cse_ops(M, f)
        queue.put(("cse", ops, time.perf_counter() - start))


def timed_child(kind, n, cart, budget, with_cse):
    """Runs one SymPy derivation in a child process: (seconds or None, cse ops or None)."""
    queue = mp.Queue()
    proc = mp.Process(target=child, args=(kind, n, cart, with_cse, queue))
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


FAMILIES = {"pendulum": "n-link-pendulum", "cart": "n-link-pendulum-on-cart"}


def lagrange_figures(family, n):
    out = subprocess.run([BENCH, "derive", family, str(n)], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def lagrange_process(family, n, repeats=3):
    """`lagrange derive --format json` of the generated scene as a whole process: the median
    wall time of `repeats` runs. (Its peak memory is lagrange-bench's figure: a child's
    ru_maxrss would include this Python process's, which it starts as a copy of.)"""
    scene = subprocess.run([LAGRANGE, "generate", family, str(n)], check=True,
                           capture_output=True, text=True).stdout
    with tempfile.NamedTemporaryFile("w", suffix=".lag", delete=False) as file:
        file.write(scene)
    times = []
    try:
        for _ in range(repeats):
            start = time.perf_counter()
            subprocess.run([LAGRANGE, "derive", "--format", "json", file.name], check=True,
                           stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - start)
    finally:
        os.unlink(file.name)
    return statistics.median(times)


def fmt(s):
    if s is None:
        return "over budget"
    return f"{s * 1e3:.1f} ms" if s < 1 else f"{s:.2f} s"


def ratio(theirs, ours):
    """Theirs over ours, as a factor: above 1 lagrange is faster."""
    if not theirs:
        return "-"
    r = theirs / ours
    return f"{r:.0f}x" if r >= 10 else f"{r:.2f}x"


def growth(rows):
    """The exponent k of time ~ n^k between the first and last rows that have a time."""
    import math

    timed = [(n, t) for n, t in rows if t]
    if len(timed) < 2 or timed[0][0] == timed[-1][0]:
        return "-"
    (n0, t0), (n1, t1) = timed[0], timed[-1]
    return f"n^{math.log(t1 / t0) / math.log(n1 / n0):.2f}"


def derivation_table(family, sizes, budget, with_sympy):
    cart = family == "n-link-pendulum-on-cart"
    print(f"## Derivation: {family}, lagrange against SymEngine {se.__version__} and SymPy "
          f"{sp.__version__} (same machine, same run)")
    print(f"{'n':>3} {'lagrange derive':>15} {'peak RSS':>9} {'SymEngine raw':>14} "
          f"{'SymE/ours':>10} {'Lagrange(SymPy)':>16} {'Lagr/ours':>10} {'Kane(SymPy)':>12} "
          f"{'Kane/ours':>10} {'lib derive+lower':>17} {'SymPy cse ops':>14} {'our ops':>8}")
    skip = {"lagrange": not with_sympy, "kane": not with_sympy}
    ours_by_n, symengine_by_n, lagranges_by_n, kanes_by_n = [], [], [], []
    for n in sizes:
        process = lagrange_process(family, n)
        library = lagrange_figures(family, n)
        peak = library.get("peak_rss_bytes")
        symengine = statistics.median(symengine_raw(n, cart) for _ in range(3))
        row = {}
        for kind in ("lagrange", "kane"):
            if skip[kind]:
                row[kind] = (None, None)
                continue
            # CSE of Kane's (smaller) result gives SymPy's operation count.
            seconds, ops = timed_child(kind, n, cart, budget, with_cse=(kind == "kane"))
            if seconds is None:
                skip[kind] = True
            row[kind] = (seconds, ops)
        lt, kt = row["lagrange"][0], row["kane"][0]
        cse = row["kane"][1]
        ours_by_n.append((n, process))
        symengine_by_n.append((n, symengine))
        lagranges_by_n.append((n, lt))
        kanes_by_n.append((n, kt))
        memory = f"{peak / 1e6:.1f} MB" if peak else "-"
        sympy = (fmt(lt) if lt or with_sympy else "-", fmt(kt) if kt or with_sympy else "-")
        print(f"{n:>3} {fmt(process):>15} {memory:>9} {fmt(symengine):>14} "
              f"{ratio(symengine, process):>10} {sympy[0]:>16} {ratio(lt, process):>10} "
              f"{sympy[1]:>12} {ratio(kt, process):>10} {fmt(library['lowered_s']):>17} "
              f"{cse if cse is not None else '-':>14} {library['ops']:>8}", flush=True)
    print(f"growth over n = {sizes[0]}..{sizes[-1]}: lagrange {growth(ours_by_n)}, "
          f"SymEngine {growth(symengine_by_n)}")
    print(f"(lagrange derive: the whole `lagrange derive --format json` process, median of 3; "
          f"SymEngine raw: Euler-Lagrange by differentiation, nothing expanded or printed, "
          f"median of 3; SymPy: one run each, budget {budget} s per size; theirs/ours above 1 "
          f"means lagrange is faster; lib derive+lower and peak RSS: `lagrange-bench derive`, "
          f"median of 5 and the largest peak of its runs; SymPy cse ops: count_ops after "
          f"sympy.cse of Kane's M and f)\n")
    return {
        "lagrange derive (whole process)": ours_by_n,
        f"SymEngine {se.__version__} raw Euler-Lagrange": symengine_by_n,
        f"SymPy {sp.__version__} KanesMethod": kanes_by_n,
        f"SymPy {sp.__version__} LagrangesMethod": lagranges_by_n,
    }


def plot(family, series, path):
    """A log-log SVG of seconds against n, one line per tool: the README's scaling figure."""
    import math

    points = [(n, t) for line in series.values() for n, t in line if t]
    if not points:
        return
    width, height, left, right, top, bottom = 640, 400, 70, 230, 40, 50
    n_lo, n_hi = min(n for n, _ in points), max(n for n, _ in points)
    t_lo = 10.0 ** math.floor(math.log10(min(t for _, t in points)))
    t_hi = 10.0 ** math.ceil(math.log10(max(t for _, t in points)))

    def x(n):
        span = math.log(n_hi / n_lo) or 1.0
        return left + (width - left - right) * math.log(n / n_lo) / span

    def y(t):
        return top + (height - top - bottom) * (1 - math.log(t / t_lo) / math.log(t_hi / t_lo))

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{left}" y="20" font-size="14">Derivation time, {family} '
           f'(same machine, same run)</text>']
    decade = t_lo
    while decade <= t_hi * 1.001:
        label = f"{decade * 1e3:g} ms" if decade < 1 else f"{decade:g} s"
        out.append(f'<line x1="{left}" x2="{width - right}" y1="{y(decade):.1f}" '
                   f'y2="{y(decade):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{left - 6}" y="{y(decade) + 4:.1f}" '
                   f'text-anchor="end">{label}</text>')
        decade *= 10
    for n in sorted({n for n, _ in points}):
        out.append(f'<text x="{x(n):.1f}" y="{height - bottom + 18}" '
                   f'text-anchor="middle">{n}</text>')
    out.append(f'<text x="{(left + width - right) / 2:.1f}" y="{height - 10}" '
               f'text-anchor="middle">n (links)</text>')
    colours = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd"]
    for k, (name, line) in enumerate(series.items()):
        line = [(n, t) for n, t in line if t]
        if not line:
            continue
        colour = colours[k % len(colours)]
        path_d = " ".join(f"{'M' if i == 0 else 'L'}{x(n):.1f},{y(t):.1f}"
                          for i, (n, t) in enumerate(line))
        out.append(f'<path d="{path_d}" fill="none" stroke="{colour}" stroke-width="2"/>')
        for n, t in line:
            out.append(f'<circle cx="{x(n):.1f}" cy="{y(t):.1f}" r="3" fill="{colour}"/>')
        ly = top + 10 + 22 * k
        out.append(f'<line x1="{width - right + 12}" x2="{width - right + 32}" y1="{ly}" '
                   f'y2="{ly}" stroke="{colour}" stroke-width="2"/>')
        out.append(f'<text x="{width - right + 38}" y="{ly + 4}" font-size="11">{name}</text>')
    out.append("</svg>")
    with open(path, "w") as file:
        file.write("\n".join(out) + "\n")


def double_pendulum_rhs():
    import numpy as np

    _, M, f = lagranges(2, cart=False)
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
    parser.add_argument("--sizes", default="4,8,12,16,24,32")
    parser.add_argument("--families", default="pendulum,cart")
    parser.add_argument("--budget", type=float, default=150.0)
    parser.add_argument("--no-sympy", action="store_true",
                        help="time lagrange and SymEngine only")
    parser.add_argument("--plot", metavar="FILE.svg",
                        help="draw the first family's times against n, log-log")
    parser.add_argument("--dop853", action="store_true")
    parser.add_argument("--skip-derivation", action="store_true")
    args = parser.parse_args()
    for binary in (BENCH, LAGRANGE):
        if not os.path.exists(binary):
            sys.exit(f"{binary} is missing: run `cargo build --release -p cli -p bench` first")
    print(f"sympy {sp.__version__}, symengine {se.__version__}, python "
          f"{sys.version.split()[0]}\n")
    if not args.skip_derivation:
        sizes = [int(s) for s in args.sizes.split(",")]
        for k, family in enumerate(args.families.split(",")):
            series = derivation_table(FAMILIES[family], sizes, args.budget, not args.no_sympy)
            if args.plot and k == 0:
                plot(FAMILIES[family], series, args.plot)
    if args.dop853:
        dop853_comparison()


if __name__ == "__main__":
    main()
