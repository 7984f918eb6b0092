"""Propped cantilever: a clamped beam on a rigid point support under a small tip load.

Closed form (Euler-Bernoulli, small deflection): a cantilever of length L clamped at
x = 0, a frictionless support at x = a (a <= L) touching the unloaded beam from below,
a tip load P downward. Compatibility at the support (the deflection of the free
cantilever under P at a equals the lift of the reaction R there),
    P a^2 (3L - a) / (6 EI) = R a^3 / (3 EI)   =>   R = P (3L - a) / (2a),
independent of EI. The support stays in contact (R > 0) for every a in (0, L].
The tip deflection, for the record: w(L) = P L^3/(3EI) - R a^2 (3L - a)/(6EI).

softrod models the support as a circle of radius `support_radius_m` whose top touches
the straight rod at x = a (rod radius 0); its test takes the linear limit by a small
load (tip deflection about 1e-5 L, so the geometric nonlinearity changes R/P by about
1e-10) and checks R/P at two loads a factor 10 apart.

Run: `python validation/contact_propped_cantilever.py [--out-dir reference]`.
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

GENERATOR = "validation/contact_propped_cantilever.py"
LENGTH_M = 1.0
EI_NM2 = 1.0
EA_N = 1.0e4
SUPPORT_RADIUS_M = 1.0e-3
TIP_LOAD_N = 3.0e-5
SUPPORTS_M = [0.25, 0.5, 0.75, 1.0]


def reaction(p, length, a):
    return p * (3.0 * length - a) / (2.0 * a)


def tip_deflection(p, length, a, ei):
    r = reaction(p, length, a)
    return p * length**3 / (3.0 * ei) - r * a**2 * (3.0 * length - a) / (6.0 * ei)


def run_all(out_dir):
    t0 = time.perf_counter()
    values = {
        "supports": [
            {
                "a_m": a,
                "reaction_n": reaction(TIP_LOAD_N, LENGTH_M, a),
                "reaction_per_load": reaction(1.0, LENGTH_M, a),
                "tip_deflection_m": tip_deflection(TIP_LOAD_N, LENGTH_M, a, EI_NM2),
            }
            for a in SUPPORTS_M
        ]
    }
    params = {
        "length_m": LENGTH_M,
        "ei_nm2": EI_NM2,
        "ea_n": EA_N,
        "tip_load_n": TIP_LOAD_N,
        "support_radius_m": SUPPORT_RADIUS_M,
        "rod_radius_m": 0.0,
        "formula": "R = P (3L - a) / (2a)",
    }
    doc = C.document(GENERATOR, "contact_propped_cantilever",
                     "Propped cantilever, closed form (Euler-Bernoulli, small deflection)",
                     params, values, timing_s=time.perf_counter() - t0)
    path = os.path.join(out_dir, "contact_propped_cantilever.json")
    C.write_json(path, doc)
    rows = []
    for s in values["supports"]:
        print(f"propped cantilever a = {s['a_m']:.3f} m: R = {s['reaction_n']:.10e} N")
    rows.append({"case": "contact_propped", "generator": "closed form", "tip": [LENGTH_M, values["supports"][1]["tip_deflection_m"]],
                 "angle": 0.0, "time": time.perf_counter() - t0, "path": path})
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    run_all(a.out_dir)


if __name__ == "__main__":
    main()
