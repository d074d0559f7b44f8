"""FMUs of lagrange scenes checked with FMPy, as CI runs it (.ci/run).

For each scene: `lagrange export --fmu`, FMPy's validator and the checks of FMU Manipulation
Toolbox (`fmutool -check`: the XML schema and its semantic checks) with no problem, then FMPy's
runs as Co-Simulation (the FMU's own DOP853) and as Model Exchange (FMPy's CVode), each compared
with `lagrange simulate` of the same scene at the same times. Exits 1 when any of them fails.

    python tests/fmu/check_fmu.py --lagrange target/release/lagrange SCENE:UNTIL ...
"""

import argparse
import csv
import io
import os
import subprocess
import sys
import tempfile

import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

TOLERANCE = 1e-10
AGREEMENT = 1e-6
SAMPLES = 200


def compared(fmu):
    """The FMU's continuous states, in the order of their derivatives, then the energies, by
    name: what `simulate --output` records under the same names (it takes expressions, not
    the names of the scene's `output` lines)."""
    description = read_model_description(fmu)
    states = [d.variable.derivative.name for d in description.derivatives]
    outputs = [o.variable.name for o in description.outputs]
    assert outputs[-2:] == ["KE", "PE"], outputs
    return states + ["KE", "PE"]


def toolbox_check(fmu):
    """FMU Manipulation Toolbox's `fmutool -input FMU -check`, through its entry point in this
    interpreter (wherever pip put the script): (passed, what it printed)."""
    code = ("import sys; from fmu_manipulation_toolbox.cli.fmutool import fmutool; "
            "sys.argv = ['fmutool', '-input', sys.argv[1], '-check']; sys.exit(fmutool())")
    run = subprocess.run([sys.executable, "-c", code, fmu], capture_output=True, text=True)
    return run.returncode == 0, run.stdout + run.stderr


def simulate(lagrange, scene, until, names, inputs, parameters):
    """`lagrange simulate` of the scene, with `inputs` (name → value) held and `parameters`
    (name → value) set: times and the named columns, at SAMPLES + 1 points."""
    held = [f"--input={name}={value!r}" for name, value in inputs.items()]
    held += [f"--set={name}={value!r}" for name, value in parameters.items()]
    run = subprocess.run(
        [lagrange, "simulate", scene, "--until", repr(until), "--tolerance", repr(TOLERANCE),
         "--samples", str(SAMPLES + 1), "--output", ",".join(names), *held],
        check=True, capture_output=True, text=True)
    rows = list(csv.reader(io.StringIO(run.stdout)))
    header, body = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
    return body[:, 0], {name: body[:, header.index(name)] for name in names}


def worst_difference(times, reference, result, names):
    """The largest |difference| over the names at the reference's times, relative to the
    size of the value where it exceeds 1."""
    worst = 0.0
    for name in names:
        got = np.interp(times, result["time"], result[name])
        scale = np.maximum(1.0, np.abs(reference[name]))
        worst = max(worst, float(np.max(np.abs(got - reference[name]) / scale)))
    return worst


def check(lagrange, scene, until, folder):
    name = os.path.splitext(os.path.basename(scene))[0]
    fmu = os.path.join(folder, name + ".fmu")
    subprocess.run([lagrange, "export", scene, "--fmu", fmu, "--tolerance", repr(TOLERANCE)],
                   check=True, capture_output=True, text=True)
    problems = validate_fmu(fmu)
    if problems:
        print(f"{scene}: FMPy's validator found problems:", *problems, sep="\n  ")
        return False
    passed, report = toolbox_check(fmu)
    if not passed:
        print(f"{scene}: fmutool -check found problems:\n{report}")
        return False
    print(f"{scene}: FMPy's validator and fmutool -check find no problem")
    names = compared(fmu)
    variables = read_model_description(fmu).modelVariables
    inputs = [v.name for v in variables if v.causality == "input"]
    parameters = [v for v in variables if v.causality == "parameter"]
    first, last = parameters[0], parameters[-1]
    ok = True
    # As declared; with the last parameter 5% larger (where the start depends on it, the
    # FMU's start follows), and the first (where derived parameters follow it, as in
    # tests/scenes/derived_length_pendulum.lag, the FMU's follow); and with each input held
    # at a value of its own. The FMU takes them as start values, `simulate` with --set and
    # --input.
    cases = [({}, {}), ({}, {last.name: 1.05 * float(last.start)})]
    if first.name != last.name:
        cases.append(({}, {first.name: 1.05 * float(first.start)}))
    if inputs:
        cases.append(({name: 0.5 + i for i, name in enumerate(inputs)}, {}))
    for held, parameters in cases:
        times, reference = simulate(lagrange, scene, until, names, held, parameters)
        for interface, extra in [("CoSimulation", {}),
                                 ("ModelExchange", {"solver": "CVode",
                                                    "relative_tolerance": TOLERANCE})]:
            result = simulate_fmu(fmu, fmi_type=interface, stop_time=until,
                                  output_interval=until / SAMPLES, output=names,
                                  start_values={**held, **parameters}, **extra)
            worst = worst_difference(times, reference, result, names)
            verdict = "ok" if worst <= AGREEMENT else "FAILED"
            given = "".join(f", {k} = {v:.6g}" for k, v in {**held, **parameters}.items())
            print(f"{scene}{given} as {interface}: largest difference from simulate "
                  f"{worst:.1e} over {len(names) - 2} states, KE and PE to t = {until} s: "
                  f"{verdict}")
            ok = ok and worst <= AGREEMENT
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--lagrange", required=True, help="the lagrange binary")
    parser.add_argument("scenes", nargs="+", help="SCENE.lag:UNTIL, the run's end in seconds")
    args = parser.parse_args()
    ok = True
    with tempfile.TemporaryDirectory() as folder:
        for item in args.scenes:
            scene, until = item.rsplit(":", 1)
            ok = check(args.lagrange, scene, float(until), folder) and ok
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
