"""A family of exudyn cantilevers for the stability map of `softrod report`.

The paper's robot (two 0.12 m sections, EI = 0.025 N m^2, EA = 300 N) under a
uniform line load in -y of k times its self-weight, w = k * 0.15 kg/m * 9.81 m/s^2
(softrod::params::MASS_PER_LENGTH_KG_PER_M), for k in K_FACTORS (0.1x to 20x:
from the linear range to a tip rotation of about 75 degrees). The load is the
unknown that the estimator must find from markers sampled on these shapes, so
these are the "truth" of the stability sweep (load-magnitude axis).

Same exudyn model, clamp, Gauss rules and solver as `exudyn_cantilever.py`
(ObjectANCFCable2D, all four base coordinates fixed, LoadMassProportional for
the uniform load, SolveStatic with 20 load steps, relative tolerance 1e-8), at
64 and 128 elements (the 64-element run is a convergence check). One file per
factor, reference/exudyn_family_uniform_<k>.json, in the schema of the other
exudyn references (params.loads in softrod's SceneLoad format, values.runs[*].nodes).

Run: `python validation/exudyn_load_family.py [--out-dir reference]`
(or through `make_references.py --only family`).
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
import exudyn_cantilever as X  # noqa: E402

GENERATOR = "validation/exudyn_load_family.py"
MASS_PER_LENGTH_KG_PER_M = 0.15
K_FACTORS = [0.1, 0.3, 1.0, 3.0, 10.0, 20.0]
ELEMENTS = [64, 128]


def tag(k):
    """File-name tag of a factor: 0.1 -> '0p1', 3.0 -> '3'."""
    return f"{k:g}".replace(".", "p")


def run_factor(k, out_dir, elements=ELEMENTS):
    w = k * MASS_PER_LENGTH_KG_PER_M * C.GRAVITY
    loads = [C._uniform(w)]
    name = f"family_uniform_{tag(k)}"
    description = (f"Uniform line load {k:g} x the robot's self-weight (0.15 kg/m x 9.81 m/s^2): "
                   f"w = {w:.6g} N/m in -y.")
    runs, times = [], {}
    with C.Timer() as t_all:
        for ne in elements:
            with C.Timer() as t:
                r = X.solve(ne, loads, X.LOAD_STEPS_LARGE)
            nodes = r["nodes"]
            res = X.cable_residual(nodes, loads)
            tip = nodes[-1]
            runs.append({
                "elements": ne,
                "converged": r["converged"],
                "tip_position_m": [tip[0], tip[1]],
                "tip_angle_rad": math.atan2(tip[3], tip[2]),
                "nodes": nodes,
                "residual": {
                    "exudyn_newton_residual": r["exudyn_residual"],
                    "softrod_model_residual_max_abs": X._finite(np.max(np.abs(res))),
                },
            })
            times[str(ne)] = t.elapsed
            C.log(f"  exudyn {name} ne={ne:4d} ok={r['converged']} tip=({tip[0]:.12f}, {tip[1]:.12f}) {t.elapsed:.2f}s")
    conv = [r for r in runs if r["converged"]]
    if not conv:
        raise RuntimeError(f"exudyn: no run of {name} converged")
    finest = conv[-1]
    values = {
        "load_factor": k,
        "w_n_per_m": w,
        "tip_position_m": finest["tip_position_m"],
        "tip_angle_rad": finest["tip_angle_rad"],
        "finest_elements": finest["elements"],
        "not_converged_elements": [r["elements"] for r in runs if not r["converged"]],
        "runs": runs,
    }
    disc = {
        "element": "exudyn ObjectANCFCable2D (planar ANCF cable, cubic Hermite, nodes [x, y, dx/dX, dy/dX])",
        "gauss_points_axial": 5,
        "gauss_points_bending": 3,
        "clamp": "base node: all four coordinates fixed (CoordinateConstraint to ground)",
        "distributed_load": "uniform: LoadMassProportional with massPerLength = 1 kg/m and acceleration = w",
        "solver": "exudyn SolveStatic, Newton, EigenSparse",
        "load_steps": X.LOAD_STEPS_LARGE,
        "newton_relative_tolerance": X.RELATIVE_TOLERANCE,
        "newton_absolute_tolerance": X.ABSOLUTE_TOLERANCE,
        "elements": list(elements),
    }
    doc = C.document(GENERATOR, name, description, C.params(loads, disc), values,
                     extra_versions=("exudyn",), timing_s={"total": t_all.elapsed, "per_run": times})
    path = os.path.join(out_dir, f"exudyn_{name}.json")
    C.write_json(path, doc)
    return [{"case": name, "generator": f"exudyn ne={finest['elements']}", "tip": finest["tip_position_m"],
             "angle": finest["tip_angle_rad"], "time": t_all.elapsed, "path": path}]


def run_all(out_dir):
    rows = []
    for k in K_FACTORS:
        rows += run_factor(k, out_dir)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for row in run_all(a.out_dir):
        print(f"{row['case']:28s} tip = ({row['tip'][0]:.12f}, {row['tip'][1]:.12f}) angle = {row['angle']:.12f}  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
