"""The fixed cost of one `scene.simulate` call from Python: the call's wall time less the
integration's own (`Results.wall_seconds`), per scene, the median of repeats in this one run;
and the same runs as one `scene.batch` call, per run (the median of 5 batches).

    python crates/python/bench/overhead.py [--repeats 30]
"""

import argparse
import statistics
import time
from pathlib import Path

import lagrange

ROOT = Path(__file__).resolve().parents[3]
SCENES = [
    ("simple pendulum, t = 10", "examples/classics/simple_pendulum.lag", {"until": 10.0}),
    ("double pendulum, t = 10", "examples/classics/double_pendulum.lag", {"until": 10.0}),
    ("heavy top, t = 0.1", "examples/space/heavy_top.lag", {"until": 0.1}),
]


def measure(scene, settings, repeats):
    """Median wall time of a call, and median integration time inside it, in seconds."""
    walls, integrations = [], []
    for _ in range(repeats):
        started = time.perf_counter()
        run = scene.simulate(**settings)
        walls.append(time.perf_counter() - started)
        integrations.append(run.wall_seconds)
    return statistics.median(walls), statistics.median(integrations)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30)
    args = parser.parse_args()
    print("| scene | call | integration | fixed cost | batch of the same, per run |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for label, path, settings in SCENES:
        scene = lagrange.load(ROOT / path)
        scene.simulate(**settings)  # the first call, which may compile, is not counted
        wall, integration = measure(scene, settings, args.repeats)
        batch = "—"
        if hasattr(scene, "batch"):
            values = {"g": [9.81] * args.repeats}
            batches = []
            for _ in range(5):
                started = time.perf_counter()
                scene.batch(values, **settings)
                batches.append((time.perf_counter() - started) / args.repeats)
            batch = f"{statistics.median(batches) * 1e3:.3f} ms"
        print(
            f"| {label} | {wall * 1e3:.3f} ms | {integration * 1e3:.3f} ms "
            f"| {(wall - integration) * 1e3:.3f} ms | {batch} |"
        )


if __name__ == "__main__":
    main()
