"""A time-varying LQR along the cart-pole's fall, from `linearize --along`.

The cart-pole of cart_pole.lag, let go from its tilt with no force, falls: a nominal motion
that no linearization about upright describes for long. lagrange linearizes along it (A(t) and
B(t) at every sample, and the state-transition matrix Φ over it); the Riccati equation
-P' = A'P + PA - PBR⁻¹B'P + Q, integrated backwards along the samples, gives the gains
K(t) = R⁻¹B'P(t) of dF = -K(t)·dx that hold the cart-pole near the fall, and Φ of the closed
loop A - B·K shows how much less a small error of the start has grown by the end.

Run it from anywhere, with the lagrange package (python-control too, for one sample's
state space):

    python3 examples/control/cart_pole_along.py
"""

from pathlib import Path

import numpy as np

import lagrange

SCENE = Path(__file__).with_name("cart_pole.lag")

# Weights on (x, theta, x', theta') and on F, as cart_pole_lqr.py weighs them, and the weight
# of the end state.
Q = np.diag([1.0, 10.0, 1.0, 1.0])
R = np.array([[0.01]])
FINAL = np.diag([10.0, 100.0, 10.0, 10.0])

UNTIL = 0.5
SAMPLES = 501


def rk4_steps(f, y, times):
    """y at each of `times` (increasing or decreasing) by one RK4 step between neighbours,
    f(k, s, y) the slope a fraction s of the way from sample k to the next."""
    out = [y]
    for k in range(len(times) - 1):
        h = times[k + 1] - times[k]
        k1 = f(k, 0.0, y)
        k2 = f(k, 0.5, y + h / 2 * k1)
        k3 = f(k, 0.5, y + h / 2 * k2)
        k4 = f(k, 1.0, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(y)
    return out


def between(m, k, s):
    """A sample's matrix a fraction s of the way to the next one, linear between them."""
    return m[k] + s * (m[k + 1] - m[k])


def gains(along):
    """K(t) at every sample, from the Riccati equation integrated from the end backwards."""
    a, b = along.A[::-1], along.B[::-1]
    r_inv = np.linalg.inv(R)

    def slope(k, s, p):
        ak, bk = between(a, k, s), between(b, k, s)
        return -(ak.T @ p + p @ ak - p @ bk @ r_inv @ bk.T @ p + Q)

    p = rk4_steps(slope, FINAL, along.t[::-1])[::-1]
    return np.array([r_inv @ along.B[k].T @ p[k] for k in range(len(along))])


def closed_loop_transition(along, k_gains):
    """Φ of dx' = (A - B·K)·dx over the fall."""
    closed = along.A - along.B @ k_gains
    phi = rk4_steps(lambda k, s, y: between(closed, k, s) @ y, np.eye(4), along.t)
    return phi[-1]


def main():
    scene = lagrange.load(str(SCENE))
    along = scene.linearize_along(until=UNTIL, samples=SAMPLES)
    k_gains = gains(along)
    closed = closed_loop_transition(along, k_gains)
    opened = np.linalg.norm(along.transition, 2)
    held = np.linalg.norm(closed, 2)
    print(f"{len(along)} samples of the fall from t = {along.t[0]} to {along.t[-1]}")
    # Adding 0 shows −0 (of −M⁻¹·C with no damping) as 0.
    print("A at the start:\n", np.round(along.A[0], 4) + 0.0)
    print("A at the end:\n", np.round(along.A[-1], 4) + 0.0)
    print("K at the start:", np.round(k_gains[0][0], 3))
    print(f"largest growth of a small error of the start: {opened:.3f} open, {held:.3f} held")
    try:
        import control
    except ImportError:
        print("python-control is not installed: skipping control.ss of one sample")
    else:
        poles = control.poles(along.to_control(0))
        print("poles of the frozen A at the start:", np.round(np.sort_complex(poles), 4))
    return opened, held


if __name__ == "__main__":
    main()
