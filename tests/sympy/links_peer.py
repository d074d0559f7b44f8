#!/usr/bin/env python3
"""lagrange from Python against Pinocchio's articulated-body algorithm, the peer of
`lagrange-bench links --peer`.

The n-link pendulum (point masses on massless links, planar, `lang::generate`'s scene) twice:
as lagrange's `Scene.rhs()` of the scene text the bench sends, and as a Pinocchio model built
with its API (a revolute joint about z per link, the joint after it l down the link, a point
mass at each link's end as a body of zero rotational inertia, gravity along -y), whose forward
dynamics is `pinocchio.aba`, O(n). The scene's angles are absolute (from the downward
vertical), Pinocchio's relative to the parent link: q_rel[i] = theta[i] - theta[i-1], and the
scene's accelerations are the running sums of Pinocchio's.

It reads requests from standard input, one JSON object per line:

    {"n": N, "scene": TEXT, "states": K, "rows": R, "seed": S, "jac": bool, "load": bool}

and for each writes one JSON line with seconds per call, each the median of seven batches of
at least 50 ms, as wall time and (KEY_cpu) as the thread's CPU time: `rhs`, lagrange's `f(t, y)` cycling through K distinct random states (a call
at the state of the last returns the solve it cached, which would hide the cost); `rhs_same`,
the same call at one state again and again, which is what a call costs besides evaluating;
`batch`, `f.batch(Y)` on R distinct states, per state; `aba`, `pinocchio.aba` cycling through
the same K states; `jac`, `f.jac(t, y)` cycling, and `aba_derivatives`, Pinocchio's
`computeABADerivatives` on the same states (when asked); `loads`, `rhs_load` and `whole_load`,
the medians of three `lagrange.loads(text)` (parse, resolve, derive), `scene.rhs()` after it
(a copy of the derivation, lowered) and the two together: text to a callable (when asked);
and `agreement`, the
largest difference of the two q̈ over the K states relative to the largest |q̈|, so that the
timings are known to be of the same model. It measures and asserts nothing else.

It makes and uses a virtual environment of its own (tests/sympy/.venv-links, pinned NumPy,
Pinocchio, SymPy and maturin) on first run, and on every run installs this checkout's
lagrange package into it (maturin through cargo, which rebuilds only what changed), so that
what it times is the code beside it.
"""

PACKAGES = ["numpy==2.3.5", "pin==4.1.0", "sympy==1.14.0", "maturin==1.16.0"]

import os  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

from pinned import HERE, run_inside  # noqa: E402

run_inside("links", PACKAGES)

# The package's build prints to stdout, which carries this script's answers. Without build
# isolation the build backend runs `maturin` from PATH: the environment's own comes first, as
# it would in an activated environment (a fresh machine has no other).
build_env = dict(os.environ)
build_env["PATH"] = os.path.dirname(sys.executable) + os.pathsep + build_env.get("PATH", "")
subprocess.check_call(
    [sys.executable, "-m", "pip", "install", "-q", "--disable-pip-version-check", "--no-deps",
     "--no-build-isolation", "--force-reinstall", os.path.join(HERE, "..", "..", "crates", "python")],
    stdout=sys.stderr,
    env=build_env,
)

import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

import lagrange  # noqa: E402


# Calls of `f` (and `f.jac`) before they are timed.
WARM = 1100


def per_call(f, args, target=0.05, repeats=7):
    """Seconds per call of f(*a) for a in `args`, every one in turn: passes over the list
    repeated to last about `target` seconds, the median of `repeats` of those; as wall time,
    and as this thread's CPU time, which leaves out the time a neighbour on a shared machine
    held the core (but not what it did to the caches)."""
    passes = 1
    while True:
        start = time.perf_counter()
        for _ in range(passes):
            for a in args:
                f(*a)
        took = time.perf_counter() - start
        if took > target:
            break
        passes *= 10 if took < target / 10 else 2
    walls, cpus = [], []
    for _ in range(repeats):
        start, cpu = time.perf_counter(), time.thread_time()
        for _ in range(passes):
            for a in args:
                f(*a)
        calls = passes * len(args)
        walls.append((time.perf_counter() - start) / calls)
        cpus.append((time.thread_time() - cpu) / calls)
    return statistics.median(walls), statistics.median(cpus)


def chain(n, m, l, g):
    """The n-link pendulum as a Pinocchio model, and its data."""
    model = pin.Model()
    parent = 0
    down = np.array([0.0, -l, 0.0])
    for i in range(n):
        placement = pin.SE3.Identity() if i == 0 else pin.SE3(np.eye(3), down)
        joint = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i + 1}")
        # A point mass: all of its inertia is its mass at the lever, none about its centre.
        model.appendBodyToJoint(joint, pin.Inertia(m, down, np.zeros((3, 3))), pin.SE3.Identity())
        parent = joint
    model.gravity = pin.Motion(np.array([0.0, -g, 0.0]), np.zeros(3))
    return model, model.createData()


def relative(angles):
    """Absolute angles (or their rates) as Pinocchio's joint angles relative to the parent."""
    return np.concatenate([angles[:1], np.diff(angles)])


def measure(request):
    n = request["n"]
    scene = lagrange.loads(request["scene"])
    f = scene.rhs()
    values = f.parameters
    m, l, g = values["m"], values["l"], values["g"]
    model, data = chain(n, m, l, g)
    rng = np.random.default_rng(request["seed"])
    states = rng.uniform(-1.0, 1.0, (request["states"], 2 * n))
    ours = [(0.0, y) for y in states]
    tau = np.zeros(n)
    theirs = [(model, data, relative(y[:n]), relative(y[n:]), tau) for y in states]

    worst, scale = 0.0, 0.0
    for (t, y), (_, _, q, v, _) in zip(ours, theirs):
        a = f(t, y)[n:]
        b = np.cumsum(pin.aba(model, data, q, v, tau))
        worst = max(worst, float(np.max(np.abs(a - b))))
        scale = max(scale, float(np.max(np.abs(b))))

    answer = {
        "n": n,
        "agreement": worst / scale,
        "pinocchio": pin.__version__,
        "numpy": np.__version__,
    }
    # lagrange compiles a tape to machine code on its 1,000th run: the calls timed are those
    # after it, as an integration's are past its start.
    for k in range(WARM):
        f(*ours[k % len(ours)])
        if request.get("jac"):
            f.jac(*ours[k % len(ours)])
    rows = rng.uniform(-1.0, 1.0, (request["rows"], 2 * n))
    timings = [
        ("rhs", f, ours, {}),
        ("rhs_same", f, ours[:1], {}),
        ("aba", pin.aba, theirs, {}),
        ("batch", f.batch, [(rows,)], {"target": 0.2, "repeats": 5}),
    ]
    if request.get("jac"):
        timings.append(("jac", f.jac, ours, {}))
        # The peer's own derivatives of its forward dynamics, ∂q̈/∂q and ∂q̈/∂v (Carpentier
        # and Mansard's analytic derivatives of the articulated-body algorithm): what `jac`
        # gives, but for its rows q̇' = q̇.
        timings.append(("aba_derivatives", pin.computeABADerivatives, theirs, {}))
    for key, call, args, settings in timings:
        wall, cpu = per_call(call, args, **settings)
        per = len(rows) if key == "batch" else 1
        answer[key], answer[key + "_cpu"] = wall / per, cpu / per
    if request.get("load"):
        loads, rhs, whole = [], [], []
        for _ in range(3):
            start = time.perf_counter()
            loaded = lagrange.loads(request["scene"])
            middle = time.perf_counter()
            loaded.rhs()
            end = time.perf_counter()
            loads.append(middle - start)
            rhs.append(end - middle)
            whole.append(end - start)
        answer["loads"] = statistics.median(loads)
        answer["rhs_load"] = statistics.median(rhs)
        answer["whole_load"] = statistics.median(whole)
    return answer


def main():
    for line in sys.stdin:
        if line.strip():
            print(json.dumps(measure(json.loads(line))), flush=True)


if __name__ == "__main__":
    main()
