"""The Whipple bicycle, timed beside SymPy in one run.

lagrange: `lagrange linearize examples/bicycle/whipple.lag --set v=5`, the whole process (parse,
derive the nonlinear model with its five kept constraints, linearize, reduce, eigenvalues).
SymPy: its own test of the same benchmark (`sympy.physics.mechanics.tests.test_kane3`,
`test_bicycle`: Kane's method with the dependent speeds, then the linearization compared with
the paper's matrices), run as it ships.

    python tests/sympy/bicycle_compare.py --lagrange target/release/lagrange

Prints each wall time and their ratio. Not run by CI: SymPy takes minutes here.
"""

import argparse
import pathlib
import subprocess
import time


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lagrange", required=True, help="the lagrange binary")
    args = parser.parse_args()
    root = pathlib.Path(__file__).resolve().parents[2]
    scene = root / "examples" / "bicycle" / "whipple.lag"

    start = time.perf_counter()
    subprocess.run([args.lagrange, "linearize", str(scene), "--set", "v=5"], check=True,
                   stdout=subprocess.DEVNULL)
    ours = time.perf_counter() - start
    print(f"lagrange linearize (whole process): {ours:.2f} s")

    from sympy.physics.mechanics.tests import test_kane3

    start = time.perf_counter()
    test_kane3.test_bicycle()
    theirs = time.perf_counter() - start
    print(f"SymPy test_bicycle (KanesMethod, linearize): {theirs:.2f} s")
    print(f"ratio SymPy / lagrange: {theirs / ours:.1f}")


if __name__ == "__main__":
    main()
