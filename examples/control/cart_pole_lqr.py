"""The cart-pole of cart_pole.lag balanced by an LQR, end to end.

lagrange linearizes the scene about upright (A and B exactly and in numbers), python-control
designs the gain K of F = -K·x that minimises the integral of x'·Q·x + F'·R·F, and lagrange
simulates the closed loop from the scene's tilted start with the law driving the input F.

Run it from anywhere, with the lagrange package and python-control installed:

    python3 examples/control/cart_pole_lqr.py

It prints A, B, K, the closed loop's poles, where the run ends, and the `lagrange simulate`
command that runs (and, with --plot or --animate, draws) the same closed loop.
"""

from pathlib import Path

import numpy as np

import lagrange

SCENE = Path(__file__).with_name("cart_pole.lag")

# Weights on (x, theta, x', theta') and on F: the angle counts most, and a newton of force
# costs as much as a tenth of a metre of the cart's place.
Q = np.diag([1.0, 10.0, 1.0, 1.0])
R = np.array([[0.01]])

UNTIL = 10.0
SAMPLES = 201


def load():
    """The scene, with the dimension check off: the gains are bare numbers in the law."""
    return lagrange.load(str(SCENE), units=False)


def design(scene):
    """The linearization about upright and the LQR gain K, a row of 4 over the state."""
    import control

    lin = scene.linearize()
    assert lin.state == ["x", "theta", "x'", "theta'"] and lin.inputs == ["F"]
    gain, _, _ = control.lqr(lin.to_control(), Q, R)
    return lin, np.asarray(gain)[0]


def law(gain, digits=None, state=("x", "theta", "x'", "theta'")):
    """F = -K·x as a scene expression: every bit of each gain (repr), or `digits` significant
    digits of it, to be read."""
    shown = repr if digits is None else (lambda k: f"{k:.{digits}g}")
    terms = " + ".join(f"{shown(-float(k))}*{name}" for k, name in zip(gain, state))
    return terms.replace("+ -", "- ")


def closed_loop(scene, gain, until=UNTIL, samples=SAMPLES):
    """lagrange's run of the closed loop from the scene's start: t, x, theta, x', theta', F."""
    return scene.simulate(
        until=until,
        method="dop853",
        tolerance=1e-12,
        output=["x", "theta", "x'", "theta'", "F"],
        input={"F": law(gain)},
        samples=samples,
    )


def main():
    scene = load()
    lin, gain = design(scene)
    np.set_printoptions(precision=6, suppress=True)
    print("state", lin.state, "input", lin.inputs)
    print("A exactly", lin.A_sym.tolist())
    print("B exactly", lin.B_sym.tolist())
    print("A =\n", lin.A)
    print("B =\n", lin.B)
    print("K =", gain)
    poles = np.linalg.eigvals(lin.A - lin.B @ gain[np.newaxis, :])
    print("closed-loop poles:", np.sort_complex(poles))
    run = closed_loop(scene, gain)
    print(
        f"t = {run['t'][-1]:g} s: theta = {run['theta'][-1]:.3e}, x = {run['x'][-1]:.3e}, "
        f"largest |F| = {np.abs(run['F']).max():.3f} N"
    )
    print("The same closed loop from the command line, the gains to 6 digits:")
    print(
        f"lagrange simulate examples/control/cart_pole.lag --no-units --until {UNTIL:g} "
        f'--input "F={law(gain, 6)}" --output x,theta --plot cart_pole.svg'
    )


if __name__ == "__main__":
    main()
