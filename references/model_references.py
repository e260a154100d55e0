"""Write the reference solutions of the benchmark descriptions under models/ from closed forms.

Nothing here runs an engine: A01's exact pendulum (Jacobi elliptic functions), A02's exact one-angle
reduction of the parallelogram motion (J phi'' = C sin phi, integrated at rtol 1e-13; for N = 4 and
the library's N = 40: phi(t) depends on N) and the slider-crank's closed-form kinematics, all from
nsd_core.engine.problems (where each formula is derived and cited).
Run: python -m references.model_references  (rewrites the four CSV files).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from nsd_core.engine.problems.iftomm import four_bar_exact, pendulum_exact
from nsd_core.engine.problems.slider_crank import exact as slider_exact

MODELS = Path(__file__).resolve().parents[1] / "models"


def write(name: str, header: list[str], columns: list[np.ndarray]) -> None:
    data = np.column_stack(columns)
    lines = [",".join(header)] + [",".join(repr(float(x)) for x in row) for row in data]
    (MODELS / name).write_text("\n".join(lines) + "\n")


def main() -> None:
    t = np.linspace(0.0, 2000.0, 4001)           # A01: the library's 4000 output steps
    P = pendulum_exact(t)
    write("iftomm_a01_reference.csv", ["t", "P1_x", "P1_y"], [t, P[:, 0], P[:, 1]])
    t = np.linspace(0.0, 20.0, 401)              # A02: 400 output steps over 20 s
    B = four_bar_exact(t, 4)
    write("iftomm_a02_reference.csv", ["t", "B0_x", "B0_y", "B0_vx", "B0_vy"], [t, B[:, 0], B[:, 1], B[:, 2], B[:, 3]])
    B = four_bar_exact(t, 40)                    # the library's N = 40 (phi(t) depends on N)
    write("iftomm_a02_n40_reference.csv", ["t", "B0_x", "B0_y", "B0_vx", "B0_vy"], [t, B[:, 0], B[:, 1], B[:, 2], B[:, 3]])
    t = np.linspace(0.0, 0.4, 201)               # slider-crank: r 0.1 m, l 0.35 m, 5 turns/s
    x, xd, _ = slider_exact(t, 0.1, 0.35, 2 * math.pi * 5)
    write("slider_crank_reference.csv", ["t", "slider_x", "slider_v"], [t, x, xd])


if __name__ == "__main__":
    main()
