#!/usr/bin/env python3
"""Cross-check `lagrange linearize` against SymPy's own equations of motion.

For each scene with a `linearize about` line and no constraint, SymPy derives the equations
again from the scene's primitive data (as crosscheck.py does, LagrangesMethod), the state
derivative x' = F(x) with x = (q, q') is differentiated numerically at the reference in
40-digit arithmetic (central differences with h = 1e-15), and the eigenvalues of that Jacobian
are compared with lagrange's. lagrange leaves cyclic coordinates out of its state, which adds
zero eigenvalues on SymPy's side; only the eigenvalues away from zero are compared, and each
of lagrange's must have a partner within 1e-9 (relative to the largest).

Usage:
    linearize_check.py [--lagrange PATH] SCENE.lag ...
"""

import argparse
import json
import os
import sys

import mpmath

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from crosscheck import Evaluator, Scope, find_lagrange, run, solve, sympy_system  # noqa: E402

TOLERANCE = 1e-9


def sympy_eigenvalues(report, lin):
    """Eigenvalues of SymPy's linearized state equation at lagrange's reference."""
    model = report["model"]
    coords = report["coordinates"]
    # Inputs are held at their declared values, as `linearize` takes them; here they are
    # symbols beside the parameters.
    inputs = report.get("inputs", {})
    scope = Scope(list(report["parameters"]) + list(inputs), coords)
    MM, FF, _ = sympy_system(model, scope, coords, {}, [])
    n = len(coords)
    evaluator = Evaluator(scope, coords)
    mm, ff = evaluator.function(list(MM)), evaluator.function(list(FF))
    given = {**report["parameters"], **inputs}
    params = [mpmath.mpf(given[p]["numeric"]) for p in scope.params]
    # The reference as lagrange read it (expressions of the parameters), at their values.
    values = {scope.params[p]: v for p, v in zip(scope.params, params)}
    about = {k: mpmath.mpf(str(scope.parse(v).subs(values).evalf(40)))
             for k, v in lin["about"].items()}
    x0 = [about.get(c, mpmath.mpf(0)) for c in coords] + \
         [about.get(c + "'", mpmath.mpf(0)) for c in coords]

    def derivative(x):
        state = params + [mpmath.mpf(0)] + list(x) + [0] * n
        size = MM.shape[0]
        m = mm(*state)
        rows = [[m[i * size + j] for j in range(size)] for i in range(size)]
        return solve(rows, ff(*state))

    h = mpmath.mpf("1e-15")
    columns = []
    for k in range(2 * n):
        up, down = list(x0), list(x0)
        up[k] += h
        down[k] -= h
        fu, fd = derivative(up), derivative(down)
        columns.append([(a - b) / (2 * h) for a, b in zip(fu, fd)])
    jacobian = mpmath.matrix([[columns[j][i] for j in range(2 * n)] for i in range(2 * n)])
    return [complex(e) for e in mpmath.eig(jacobian, left=False, right=False)]


def compare(ours, theirs):
    scale = max([abs(e) for e in ours + theirs] + [1e-300])
    away = [e for e in ours if abs(e) > 1e-6 * scale]
    worst = 0.0
    for e in away:
        worst = max(worst, min(abs(e - f) for f in theirs) / scale)
    return worst, len(away)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--lagrange", default=os.environ.get("LAGRANGE"))
    args = parser.parse_args()
    lagrange = find_lagrange(args.lagrange)
    mpmath.mp.dps = 40
    failed = 0
    for path in args.scenes:
        label = os.path.relpath(path)
        report = json.loads(run([lagrange, "derive", path, "--format", "json", "--no-units"]))
        if report["model"]["constraints"]:
            print(f"skip {label}: constraints (the multiplier and rolling paths are checked by tests)")
            continue
        lin = json.loads(run([lagrange, "linearize", path, "--format", "json", "--no-units"]))
        lin = lin.get("linearization", lin)
        ours = [complex(re, im) for re, im in lin["eigenvalues"]]
        theirs = sympy_eigenvalues(report, lin)
        worst, compared = compare(ours, theirs)
        ok = worst < TOLERANCE
        failed += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {label}: {compared} eigenvalues away from zero, "
              f"max rel diff {worst:.1e}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
