"""The pinned environment of a peer benchmark: `run_inside(name, packages)` re-runs the calling
script inside tests/sympy/.venv-NAME, creating it with `packages` first if it is missing, so
that each peer measures the same versions wherever it runs. Standard library only: it is
imported before the environment exists.
"""

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def run_inside(name, packages):
    """Returns when already inside the environment; otherwise replaces this process by the
    same script run with the environment's Python."""
    venv = os.path.join(HERE, f".venv-{name}")
    python = os.path.join(venv, "bin", "python")
    if os.path.realpath(sys.prefix) == os.path.realpath(venv):
        return
    if not os.path.exists(python):
        subprocess.check_call([sys.executable, "-m", "venv", venv])
        subprocess.check_call([python, "-m", "pip", "install", "-q", *packages])
    os.execv(python, [python, *sys.argv])
