"""Planar elastica of the clamped cantilever by shooting (scipy).

Equations (X the arc coordinate of the undeformed rod, ' = d/dX):

    n(X)   = F_tip + int_X^L w(s) ds            (dead loads: known in closed form)
    N      = n . t,  t = (cos th, sin th)        axial force
    eps    = N / EA                              (eps = 0: inextensible)
    r'     = (1 + eps) t
    th'    = m / EI                              m: bending moment
    m'     = -(r' x n)_z
    r(0) = 0, th(0) = 0, m(L) = M_tip.

This is the continuum limit of softrod's energy 1/2 int (EA eps^2 + EI kappa^2) dX
with eps = |r'| - 1 and kappa = th' (the rate of the tangent angle per undeformed
length, = (r' x r'')_z / |r'|^2), and of its tip moment, which does the work
M * th(L). The unknown base moment m(0) is found by a secant iteration on
m(L) - M_tip = 0, with load continuation (10 steps) for the large cases, one
step for the small ones.
Integration: DOP853, rtol = 1e-12, atol = 1e-14, max step 2.5 mm (resolves the
0.01 m Gaussian bump).

For a pure tip moment N = 0 everywhere, so extensible and inextensible answers
coincide with the circular arc th = M X / EI; `check_circular_arc` checks it.

Run: `python validation/elastica.py [--out-dir reference] [--case NAME ...]`.
"""

import argparse
import math
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root_scalar

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

GENERATOR = "validation/elastica.py"
RTOL = 1e-12
ATOL = 1e-14
MAX_STEP = 0.0025
CONTINUATION_STEPS = 10  # large cases; the small ones need one step
N_SHAPE = 49


def _rhs_factory(loads, lam, ea, ei):
    fx, fy = C.tip_force(loads)
    resultant = C.resultant_function(loads)

    def rhs(X, s):
        _, _, th, m = s
        rx, ry = resultant(X)
        nx = lam * (fx + rx)
        ny = lam * (fy + ry)
        c, sn = math.cos(th), math.sin(th)
        eps = 0.0 if ea is None else (nx * c + ny * sn) / ea
        dx = (1.0 + eps) * c
        dy = (1.0 + eps) * sn
        return [dx, dy, m / ei, -(dx * ny - dy * nx)]

    return rhs


def _integrate(loads, lam, m0, ea, ei, t_eval=None):
    sol = solve_ivp(
        _rhs_factory(loads, lam, ea, ei),
        (0.0, C.LENGTH_M),
        [0.0, 0.0, 0.0, m0],
        method="DOP853",
        rtol=RTOL,
        atol=ATOL,
        max_step=MAX_STEP,
        t_eval=t_eval,
    )
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol


def solve(loads, extensible=True, ea=C.EA_N, ei=C.EI_NM2, steps=CONTINUATION_STEPS):
    """Return dict with tip position, tip angle, base moment and a sampled shape.

    `steps`: load-continuation steps (the small cases need only one or two).
    """
    ea_ = ea if extensible else None
    mt = C.tip_moment(loads)
    m0 = 0.0
    m0_prev = None
    for k in range(1, steps + 1):
        lam = k / steps

        def resid(m):
            return _integrate(loads, lam, m, ea_, ei).y[3, -1] - lam * mt

        # predictor: linear extrapolation of the previous two steps
        guess = m0 if m0_prev is None else 2 * m0 - m0_prev
        x1 = guess + 1e-3 * abs(guess) + 1e-7
        r = root_scalar(resid, x0=guess, x1=x1, method="secant", xtol=1e-15, rtol=1e-14, maxiter=100)
        if not r.converged:
            raise RuntimeError(f"shooting did not converge at load factor {lam}: {r.flag}")
        m0_prev, m0 = m0, r.root
    X = np.linspace(0.0, C.LENGTH_M, N_SHAPE)
    sol = _integrate(loads, 1.0, m0, ea_, ei, t_eval=X)
    end = _integrate(loads, 1.0, m0, ea_, ei)
    x, y, th, m = end.y[:, -1]
    return {
        "tip_position_m": [x, y],
        "tip_angle_rad": th,
        "base_moment_nm": m0,
        "shooting_residual_nm": m - mt,
        "shape": {"X_m": X, "x_m": sol.y[0], "y_m": sol.y[1], "theta_rad": sol.y[2]},
    }


def continuation_steps(name):
    return CONTINUATION_STEPS if name.endswith("_large") else 1


def check_circular_arc(M, ei=C.EI_NM2, L=C.LENGTH_M):
    """Closed-form tip of the pure-moment cantilever (circular arc)."""
    th = M * L / ei
    R = ei / M
    return [R * math.sin(th), R * (1.0 - math.cos(th))], th


def run_case(name, out_dir):
    description, loads = C.CASES[name]
    steps = continuation_steps(name)
    with C.Timer() as t:
        ext = solve(loads, extensible=True, steps=steps)
        inx = solve(loads, extensible=False, steps=steps)
    values = {
        "model": "extensible (N = EA eps, r' = (1+eps) t); the 'inextensible' block has eps = 0",
        "tip_position_m": ext["tip_position_m"],
        "tip_angle_rad": ext["tip_angle_rad"],
        "base_moment_nm": ext["base_moment_nm"],
        "shooting_residual_nm": ext["shooting_residual_nm"],
        "shape": ext["shape"],
        "inextensible": {k: inx[k] for k in ("tip_position_m", "tip_angle_rad", "base_moment_nm", "shooting_residual_nm")},
    }
    if name.endswith("_small"):
        values["linear_theory_tip_deflection_m"] = C.linear_tip_deflection(loads)
    only_moment = all(ld["type"] == "tip_moment" for ld in loads)
    if only_moment:
        pos, th = check_circular_arc(C.tip_moment(loads))
        values["circular_arc"] = {
            "tip_position_m": pos,
            "tip_angle_rad": th,
            "max_abs_difference_extensible_m": max(abs(a - b) for a, b in zip(pos, ext["tip_position_m"])),
            "max_abs_difference_inextensible_m": max(abs(a - b) for a, b in zip(pos, inx["tip_position_m"])),
        }
    disc = {
        "method": "shooting on the base moment m(0), secant iteration, load continuation",
        "continuation_steps": steps,
        "integrator": "scipy solve_ivp DOP853",
        "rtol": RTOL,
        "atol": ATOL,
        "max_step_m": MAX_STEP,
        "shape_samples": N_SHAPE,
    }
    doc = C.document(GENERATOR, name, description, C.params(loads, disc), values, timing_s=t.elapsed)
    path = os.path.join(out_dir, f"elastica_{name}.json")
    C.write_json(path, doc)
    return [
        {
            "case": name,
            "generator": "elastica",
            "tip": ext["tip_position_m"],
            "angle": ext["tip_angle_rad"],
            "time": t.elapsed,
            "path": path,
        }
    ]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    ap.add_argument("--case", nargs="*", default=list(C.CASES))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for name in a.case:
        for row in run_case(name, a.out_dir):
            print(f"{row['case']:28s} tip = ({row['tip'][0]:.12f}, {row['tip'][1]:.12f}) angle = {row['angle']:.12f}  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
