"""The picture in docs/fmu.md and the README: the double pendulum exported as an FMU and run
by FMPy, as Co-Simulation and as Model Exchange, with `lagrange simulate` beside them.

    cargo build --release
    python examples/fmu/plot.py --lagrange target/release/lagrange

Needs fmpy and matplotlib (pip install fmpy matplotlib); CI does not run it.
"""

import argparse
import csv
import io
import os
import subprocess
import tempfile

import matplotlib

matplotlib.use("svg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "classics", "double_pendulum.lag")
UNTIL = 10.0


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--lagrange", required=True, help="the lagrange binary")
    parser.add_argument("--out", default=os.path.join(HERE, "double_pendulum_fmu.svg"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        fmu = os.path.join(folder, "double_pendulum.fmu")
        subprocess.run([args.lagrange, "export", SCENE, "--fmu", fmu], check=True)
        cs = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=UNTIL, output_interval=0.01,
                          output=["theta1", "theta2"])
        me = simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode",
                          relative_tolerance=1e-10, stop_time=UNTIL, output_interval=0.01,
                          output=["theta1", "theta2"])
    run = subprocess.run([args.lagrange, "simulate", SCENE, "--until", str(UNTIL),
                          "--samples", "1001", "--output", "theta1,theta2"],
                         check=True, capture_output=True, text=True)
    rows = list(csv.reader(io.StringIO(run.stdout)))
    reference = np.array([[float(x) for x in r] for r in rows[1:]])

    plt.rcParams["svg.hashsalt"] = "lagrange"
    figure, axis = plt.subplots(figsize=(8, 4.6))
    for name, colour in [("theta1", "tab:blue"), ("theta2", "tab:orange")]:
        axis.plot(cs["time"], cs[name], color=colour, lw=2.5, alpha=0.45,
                  label=f"{name}, FMU as Co-Simulation (its DOP853)")
        axis.plot(me["time"], me[name], color=colour, lw=1, ls="--",
                  label=f"{name}, FMU as Model Exchange (FMPy's CVode)")
    column = {"theta1": 1, "theta2": 2}
    for name in column:
        axis.plot(reference[::25, 0], reference[::25, column[name]], "k.", ms=3,
                  label="lagrange simulate" if name == "theta1" else None)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("angle (rad)")
    axis.set_title("Double pendulum: lagrange export --fmu, simulated by FMPy")
    axis.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3)
    figure.tight_layout()
    figure.savefig(args.out, metadata={"Date": None})
    print("wrote", args.out)


if __name__ == "__main__":
    main()
