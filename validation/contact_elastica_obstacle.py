"""Large-deflection cantilever against a frictionless point obstacle: elastica shooting.

The continuum model softrod's planar cable discretizes (the extensible elastica
without shear): undeformed arc s in [0, L], tangent angle theta(s), stretch
1 + eps with eps = (n . t) / EA, bending moment m = EI theta'(s), and
    r' = (1 + eps) (cos theta, sin theta),    m' + (r' x n)_z = 0,
n(s) the internal force (the resultant of the loads beyond s): n = P for s > s_c
and n = P + R nu for s < s_c, P the dead tip load, R >= 0 the contact force and
nu the obstacle's outward normal at the contact. Clamp at s = 0 (r = 0,
theta = 0), free tip m(L) = 0.

The obstacle is a rigid circle (centre c, radius rho) and the rod radius is 0,
so at contact r(s_c) = c + rho nu and nu is normal to the rod, nu . t(s_c) = 0.
Unknowns (m(0), s_c, R, phi) with nu = (cos phi, sin phi); equations: m(L) = 0,
the two components of r(s_c) - c - rho nu = 0, and nu . t(s_c) = 0 (the contact
point is unknown). Integrated with scipy's solve_ivp (DOP853, rtol 1e-13,
atol 1e-15) in two pieces split at s_c, solved by scipy.optimize.fsolve
(xtol 1e-14) from the linear-theory guess. The result is checked for contact
only at s_c: the minimum distance of the rod to the circle over all s (on a fine
grid) must be >= 0 to 1e-9, else the configuration is refused.

Run: `python validation/contact_elastica_obstacle.py [--out-dir reference]`.
"""

import argparse
import math
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

GENERATOR = "validation/contact_elastica_obstacle.py"
LENGTH_M = 1.0
EI_NM2 = 1.0
EA_N = 1.0e4
RTOL = 1e-13
ATOL = 1e-15
CASES = {
    # tip load straight down, obstacle under the middle of the rod
    "contact_elastica_down": {"tip_load_n": [0.0, -2.0], "center_m": [0.6, -0.15], "radius_m": 0.02},
    # an oblique tip load, the obstacle nearer the tip
    "contact_elastica_oblique": {"tip_load_n": [-0.8, -3.0], "center_m": [0.7, -0.3], "radius_m": 0.05},
}


def rhs(n):
    def f(s, y):
        x, yy, th, m = y
        t = np.array([math.cos(th), math.sin(th)])
        eps = (n @ t) / EA_N
        rp = (1.0 + eps) * t
        return [rp[0], rp[1], m / EI_NM2, -(rp[0] * n[1] - rp[1] * n[0])]
    return f


def shoot(unknowns, p, dense=False):
    m0, sc, r, phi = unknowns
    nu = np.array([math.cos(phi), math.sin(phi)])
    n1 = p + r * nu
    sc = min(max(sc, 1e-6), LENGTH_M - 1e-6)
    a = solve_ivp(rhs(n1), (0.0, sc), [0.0, 0.0, 0.0, m0], method="DOP853", rtol=RTOL, atol=ATOL, dense_output=dense)
    b = solve_ivp(rhs(p), (sc, LENGTH_M), a.y[:, -1], method="DOP853", rtol=RTOL, atol=ATOL, dense_output=dense)
    return a, b


def residual(unknowns, p, c, rho):
    m0, sc, r, phi = unknowns
    a, b = shoot(unknowns, p)
    xc, yc, thc, _ = a.y[:, -1]
    nu = np.array([math.cos(phi), math.sin(phi)])
    return [
        b.y[3, -1],
        xc - c[0] - rho * nu[0],
        yc - c[1] - rho * nu[1],
        nu[0] * math.cos(thc) + nu[1] * math.sin(thc),
    ]


def solve_case(spec):
    p = np.array(spec["tip_load_n"], dtype=float)
    c = np.array(spec["center_m"], dtype=float)
    rho = spec["radius_m"]
    # continuation in the load from a small one (linear theory as the first guess)
    sc0 = c[0]
    guess = [0.0, sc0, 0.0, math.pi / 2]
    sol = None
    for frac in np.linspace(0.0, 1.0, 41)[1:]:
        pf = frac * p
        sol, info, ier, msg = fsolve(residual, guess, args=(pf, c, rho), xtol=1e-14, full_output=True)
        guess = sol
    res = residual(sol, p, c, rho)
    a, b = shoot(sol, p, dense=True)
    # no penetration anywhere: distance from the circle along the whole rod
    ss = np.linspace(0.0, LENGTH_M, 20001)
    pts = np.array([a.sol(s)[:2] if s <= sol[1] else b.sol(s)[:2] for s in ss])
    dmin = float(np.min(np.linalg.norm(pts - c, axis=1) - rho))
    if dmin < -1e-9 or sol[2] < 0.0:
        raise RuntimeError(f"not a contact equilibrium: min distance {dmin}, R {sol[2]}")
    tip = b.y[:, -1]
    return {
        "reaction_n": float(sol[2]),
        "contact_s_m": float(sol[1]),
        "contact_normal": [math.cos(sol[3]), math.sin(sol[3])],
        "contact_point_m": [float(v) for v in a.y[:2, -1]],
        "base_moment_nm": float(sol[0]),
        "tip_position_m": [float(tip[0]), float(tip[1])],
        "tip_angle_rad": float(tip[2]),
        "min_distance_m": dmin,
        "shooting_residual_nm": float(np.max(np.abs(res))),
        "fsolve_ier": int(ier),
    }


def run_all(out_dir):
    rows = []
    for name, spec in CASES.items():
        t0 = time.perf_counter()
        v = solve_case(spec)
        params = {"length_m": LENGTH_M, "ei_nm2": EI_NM2, "ea_n": EA_N, "rod_radius_m": 0.0,
                  "obstacle": {"shape": "circle", "center_m": spec["center_m"], "radius_m": spec["radius_m"]},
                  "tip_load_n": spec["tip_load_n"], "ivp": {"method": "DOP853", "rtol": RTOL, "atol": ATOL}}
        doc = C.document(GENERATOR, name, "Extensible elastica cantilever on a frictionless circular obstacle, "
                         "shooting with the contact point unknown", params, v, timing_s=time.perf_counter() - t0)
        path = os.path.join(out_dir, f"{name}.json")
        C.write_json(path, doc)
        print(f"{name}: R = {v['reaction_n']:.12e} N at s = {v['contact_s_m']:.12f} m, "
              f"residual {v['shooting_residual_nm']:.1e}, min distance {v['min_distance_m']:.2e}")
        rows.append({"case": name, "generator": "elastica shooting", "tip": v["tip_position_m"],
                     "angle": v["tip_angle_rad"], "time": time.perf_counter() - t0, "path": path})
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    run_all(a.out_dir)


if __name__ == "__main__":
    main()
