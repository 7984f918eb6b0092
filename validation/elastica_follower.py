"""Follower-load references: the extensible elastica of a cantilever under a pressure normal
to its deformed backbone, solved as a boundary-value problem with scipy's solve_bvp.

Model (the continuum softrod's planar cable discretizes; Kirchhoff rod, extensible,
unshearable): arc coordinate X of the undeformed rod, tangent angle theta, stretch
1 + eps, eps = n . t / EA, bending moment m = EI theta'. A pressure p (N/m of deformed
length, along the left normal e_z x t) on [a, b] gives the force per undeformed length
f = p (1 + eps) (-sin theta, cos theta). Equations:
  x' = (1 + eps) cos theta,  y' = (1 + eps) sin theta,  theta' = m / EI,
  n' = -f,  m' = -(1 + eps) (cos theta n_y - sin theta n_x),
with the clamp x = y = theta = 0 at X = 0 and a free end n = 0, m = 0 at X = L.
solve_bvp (collocation, 4th order) to a tolerance of 1e-9, one piece per load interval (the
pieces mapped to [0, 1] and stacked, joined by continuity conditions), load continuation in steps.

Run: `python validation/elastica_follower.py [--out-dir reference]`.
"""

import argparse
import math
import os
import sys

import numpy as np
from scipy.integrate import solve_bvp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

GENERATOR = "validation/elastica_follower.py"
# name -> (description, pressure N/m, start m, end m, continuation steps)
CASES = {
    "follower_small": ("Follower pressure -0.5 N/m on the whole rod (linear range).", -0.5, 0.0, C.LENGTH_M, 1),
    "follower_large": ("Follower pressure -15 N/m on the whole rod (large deflection).", -15.0, 0.0, C.LENGTH_M, 10),
    "follower_outer_half_large": ("Follower pressure -30 N/m on the outer section [0.12, 0.24] m.", -30.0,
                                  C.SECTION_LENGTH_M, C.LENGTH_M, 10),
}


def segments(p, a, b):
    """(length, pressure) of the pieces [0, a], [a, b], [b, L] that are not empty."""
    cuts = [(0.0, a, 0.0), (a, b, p), (b, C.LENGTH_M, 0.0)]
    return [(hi - lo, q) for lo, hi, q in cuts if hi - lo > 1e-15]


def rhs_factory(segs):
    """Each piece mapped to tau in [0, 1]: 6 states per piece, stacked."""
    def rhs(tau, y):
        out = np.empty_like(y)
        for i, (ln, p) in enumerate(segs):
            x, yy, th, nx, ny, m = y[6 * i:6 * i + 6]
            c, s = np.cos(th), np.sin(th)
            st = 1.0 + (nx * c + ny * s) / C.EA_N
            out[6 * i:6 * i + 6] = ln * np.vstack([st * c, st * s, m / C.EI_NM2, p * st * s, -p * st * c,
                                                   -st * (c * ny - s * nx)])
        return out
    return rhs


def bc_factory(k):
    def bc(ya, yb):
        r = [ya[0], ya[1], ya[2]]
        for i in range(k - 1):  # continuity of all six states between pieces
            r += list(ya[6 * (i + 1):6 * (i + 2)] - yb[6 * i:6 * (i + 1)])
        r += [yb[6 * (k - 1) + 3], yb[6 * (k - 1) + 4], yb[6 * (k - 1) + 5]]
        return np.array(r)
    return bc


def evaluate(sol, segs, X):
    """States (6, len(X)) at arc coordinates X."""
    X = np.asarray(X, dtype=float)
    out = np.zeros((6, X.size))
    start = 0.0
    for i, (ln, _) in enumerate(segs):
        inside = (X >= start - 1e-15) & (X <= start + ln + 1e-15)
        out[:, inside] = sol.sol((X[inside] - start) / ln)[6 * i:6 * i + 6]
        start += ln
    return out


def solve(p, a, b, steps):
    segs = segments(p, a, b)
    k = len(segs)
    tau = np.linspace(0.0, 1.0, 101)
    y = np.zeros((6 * k, tau.size))
    start = 0.0
    for i, (ln, _) in enumerate(segs):
        y[6 * i] = start + ln * tau
        start += ln
    sol = None
    for j in range(1, steps + 1):
        sj = [(ln, q * j / steps) for ln, q in segs]
        sol = solve_bvp(rhs_factory(sj), bc_factory(k), tau, y, tol=1e-9, max_nodes=100000)
        if not sol.success:
            raise RuntimeError(f"solve_bvp: {sol.message}")
        tau, y = sol.x, sol.y
    return sol, segs


def run_case(name, out_dir):
    description, p, a, b, steps = CASES[name]
    with C.Timer() as t:
        sol, segs = solve(p, a, b, steps)
    tip = sol.y[-6:, -1]
    grid = np.linspace(0.0, C.LENGTH_M, 25)
    yg = evaluate(sol, segs, grid)
    loads = [{"type": "follower", "pressure_n_per_m": p, "s_start_m": a, "s_end_m": b}]
    disc = {"method": "scipy.integrate.solve_bvp (extensible elastica), one piece per load interval",
            "tol": 1e-9,
            "mesh_points": int(sol.x.size), "load_steps": steps,
            "residual_max": float(np.max(sol.rms_residuals))}
    values = {
        "tip_position_m": [tip[0], tip[1]],
        "tip_angle_rad": tip[2],
        "base_force_n": [sol.y[3, 0], sol.y[4, 0]],
        "base_moment_nm": sol.y[5, 0],
        "s_m": grid,
        "positions_m": np.stack([yg[0], yg[1]], axis=1),
        "angles_rad": yg[2],
    }
    doc = C.document(GENERATOR, name, description, C.params(loads, disc), values,
                     extra_versions=("scipy",), timing_s={"total": t.elapsed})
    path = os.path.join(out_dir, f"elastica_{name}.json")
    C.write_json(path, doc)
    return [{"case": name, "generator": "elastica (solve_bvp)", "tip": [tip[0], tip[1]], "angle": tip[2],
             "time": t.elapsed, "path": path}]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for name in CASES:
        for row in run_case(name, a.out_dir):
            print(f"{row['case']:28s} tip = ({row['tip'][0]:.12f}, {row['tip'][1]:.12f}) angle = {row['angle']:.12f}"
                  f"  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
