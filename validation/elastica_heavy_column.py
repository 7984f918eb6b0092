"""Heavy-column reference: the extensible elastica of a column clamped pointing up (tilted
0.01 rad from the vertical) under its own uniform weight beyond the buckling load, solved as a
boundary-value problem by shooting (scipy).

Model (as validation/elastica_follower.py: Kirchhoff rod, extensible, unshearable): arc
coordinate X of the undeformed rod, tangent angle theta, stretch 1 + eps, eps = n . t / EA,
bending moment m = EI theta'. A dead load w = (0, -q) N/m per undeformed length. Equations:
  x' = (1 + eps) cos theta,  y' = (1 + eps) sin theta,  theta' = m / EI,
  n(X) = int_X^L w = (0, -q (L - X)),  m' = -(1 + eps) (cos theta n_y - sin theta n_x),
with the clamp x = y = 0, theta = pi/2 - 0.01 at X = 0 and a free end m = 0 at X = L.
q L^3 / EI = 12 (the straight column buckles at 7.837). The tilt makes the path in q
continuous: the base moment is found by a secant iteration on m(L) = 0 (DOP853, rtol 1e-12),
following the path from q = 0 in 60 load steps, each from the last answer, so the answer is the
stable equilibrium leaning towards the tilt (+x; the straight column is an unstable
equilibrium at this load). The branch is checked: tip at x > 0.01 m, clockwise base moment.

Run: `python validation/elastica_heavy_column.py [--out-dir reference]`.
"""

import argparse
import math
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

GENERATOR = "validation/elastica_heavy_column.py"
TILT_RAD = 0.01
BASE_ANGLE_RAD = math.pi / 2 - TILT_RAD
RATIO = 12.0
STEPS = 60
NAME = "heavy_column"


def shoot(q, m0):
    """Integrates from the clamp with base moment m0; returns the states at X = L."""
    L = C.LENGTH_M

    def rhs(X, y):
        x, yy, th, m = y
        c, s = math.cos(th), math.sin(th)
        nx, ny = 0.0, -q * (L - X)  # dead load: n(X) = int_X^L w
        st = 1.0 + (nx * c + ny * s) / C.EA_N
        return [st * c, st * s, m / C.EI_NM2, -st * (c * ny - s * nx)]

    return solve_ivp(rhs, (0.0, L), [0.0, 0.0, BASE_ANGLE_RAD, m0], method="DOP853", rtol=1e-12,
                     atol=1e-14, max_step=2.5e-3, dense_output=True)


def solve(q_full):
    """Secant on m(L) = 0 for the base moment, from the last step's in each of STEPS load steps."""
    m0, sol = 0.0, None
    for j in range(1, STEPS + 1):
        q = q_full * j / STEPS
        a, b = m0, m0 - 1e-4
        fa, fb = shoot(q, a).y[3, -1], None
        for _ in range(60):
            fb = shoot(q, b).y[3, -1]
            if abs(fb) < 1e-14:
                break
            a, b, fa = b, b - fb * (b - a) / (fb - fa), fb
        if abs(fb) > 1e-12:
            raise RuntimeError(f"secant did not converge at step {j}: m(L) = {fb}")
        m0 = b
        sol = shoot(q, m0)
    return sol


def run_case(out_dir):
    q = RATIO * C.EI_NM2 / C.LENGTH_M ** 3
    with C.Timer() as t:
        sol = solve(q)
    tip = sol.y[:, -1]
    # the stable branch: leaning to the tilt's side (+x), held by a clockwise base moment
    if not (tip[0] > 0.01 and sol.y[3, 0] < 0.0):
        raise RuntimeError(f"not the leaning branch: tip {tip[:2]}, base moment {sol.y[3, 0]}")
    grid = np.linspace(0.0, C.LENGTH_M, 25)
    yg = sol.sol(grid)
    loads = [{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -q]}]
    disc = {"method": "shooting on the base moment (secant, |m(L)| < 1e-12 N m), DOP853 rtol 1e-12",
            "load_steps": STEPS}
    p = C.params(loads, disc)
    p["base"] = {"position_m": [0.0, 0.0], "angle_rad": BASE_ANGLE_RAD}
    values = {
        "tip_position_m": [tip[0], tip[1]],
        "tip_angle_rad": tip[2],
        "base_force_n": [0.0, q * C.LENGTH_M],
        "base_moment_nm": sol.y[3, 0],
        "s_m": grid,
        "positions_m": np.stack([yg[0], yg[1]], axis=1),
        "angles_rad": yg[2],
    }
    description = ("Column clamped pointing up (tilted 0.01 rad), uniform weight q L^3/EI = 12 "
                   "(buckling at 7.837): the stable, leaning equilibrium.")
    doc = C.document(GENERATOR, NAME, description, p, values, extra_versions=("scipy",),
                     timing_s={"total": t.elapsed})
    path = os.path.join(out_dir, f"elastica_{NAME}.json")
    C.write_json(path, doc)
    return [{"case": NAME, "generator": "elastica (shooting)", "tip": [tip[0], tip[1]], "angle": tip[2],
             "time": t.elapsed, "path": path}]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for row in run_case(a.out_dir):
        print(f"{row['case']:28s} tip = ({row['tip'][0]:.12f}, {row['tip'][1]:.12f}) angle = {row['angle']:.12f}"
              f"  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
