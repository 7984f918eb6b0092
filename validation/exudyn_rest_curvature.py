"""Rest-curvature reference from exudyn's ANCF cable (ObjectANCFCable2D, `referenceCurvature`).

A clamped cantilever (0.24 m, EA = 300 N, EI = 0.025 N m^2, 16 elements) whose rest
curvature varies along it: element e has exudyn's constant `referenceCurvature`
kappa0_e = KAPPA_A + KAPPA_B * X_mid(e), X_mid the element's midpoint (a staircase
that follows the ramp 4 + 20 X 1/m). exudyn's bending work is
delta W = int EI (K - kappa0_e) delta K dX with K = (r' x r'')_z / |r'|^2 (the
material curvature), the same energy softrod's planar cable has with a rest-curvature
profile that jumps at the nodes (`rest_curvature_profile` with each node's arc
position written twice). Loads: tip force and tip moment (dead), as in
exudyn_cantilever.py. Gauss rules: 5 axial, 3 bending (exudyn's default).

Run: `python validation/exudyn_rest_curvature.py [--out-dir reference]`.
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

import exudyn as exu  # noqa: E402
from exudyn.itemInterface import (  # noqa: E402
    CoordinateConstraint,
    LoadForceVector,
    LoadTorqueVector,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    NodePoint2DSlope1,
    NodePointGround,
    ObjectANCFCable2D,
)

GENERATOR = "validation/exudyn_rest_curvature.py"
ELEMENTS = 16
KAPPA_A = 4.0  # 1/m
KAPPA_B = 20.0  # 1/m^2
# name -> (description, tip force (N), tip moment (N m), load steps)
CASES = {
    "unloaded": ("Rest curvature staircase on the ramp 4 + 20 X 1/m, no load.", [0.0, 0.0], 0.0, 1),
    "loaded": ("Rest curvature staircase on the ramp 4 + 20 X 1/m, tip force (0.1, -0.3) N and tip moment "
               "-0.004 N m.", [0.1, -0.3], -0.004, 20),
}


def kappa0(ne):
    le = C.LENGTH_M / ne
    return [KAPPA_A + KAPPA_B * (e + 0.5) * le for e in range(ne)]


def solve(ne, force, moment, steps):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    le = C.LENGTH_M / ne
    # start from the unloaded shape of the staircase (circular arcs, inextensible)
    start = [[0.0, 0.0, 1.0, 0.0]]
    x = y = th = 0.0
    for k in kappa0(ne):
        x += (math.sin(th + k * le) - math.sin(th)) / k
        y += (math.cos(th) - math.cos(th + k * le)) / k
        th += k * le
        start.append([x, y, math.cos(th), math.sin(th)])
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * le, 0.0, 1.0, 0.0],
                                           initialCoordinates=[start[i][0] - i * le, start[i][1],
                                                               start[i][2] - 1.0, start[i][3]]))
             for i in range(ne + 1)]
    elems = [
        mbs.AddObject(ObjectANCFCable2D(length=le, massPerLength=0.0, bendingStiffness=C.EI_NM2,
                                        axialStiffness=C.EA_N, referenceCurvature=k,
                                        nodeNumbers=[nodes[i], nodes[i + 1]], useReducedOrderIntegration=0))
        for i, k in enumerate(kappa0(ne))
    ]
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in range(4):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc]))
    mt = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadForceVector(markerNumber=mt, loadVector=[force[0], force[1], 0.0]))
    mr = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[-1], localPosition=[le, 0.0, 0.0]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mr, loadVector=[0.0, 0.0, moment]))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = steps
    s.staticSolver.newton.relativeTolerance = 1e-10
    s.staticSolver.newton.absoluteTolerance = 1e-9
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ok = bool(mbs.SolveStatic(s))
    conv = mbs.sys["staticSolver"].conv
    q = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates,
                                    configuration=exu.ConfigurationType.Current) for n in nodes])
    ref = np.array([[i * le, 0.0, 1.0, 0.0] for i in range(ne + 1)])
    return ok and bool(conv.newtonConverged), ref + q, float(conv.residual)


def run_case(name, out_dir):
    description, force, moment, steps = CASES[name]
    with C.Timer() as t:
        ok, nodes, res = solve(ELEMENTS, force, moment, steps)
    if not ok:
        raise RuntimeError(f"exudyn: {name} did not converge")
    tip = nodes[-1]
    k0 = kappa0(ELEMENTS)
    le = C.LENGTH_M / ELEMENTS
    loads = []
    if force != [0.0, 0.0]:
        loads.append({"type": "tip_force", "force_n": force})
    if moment != 0.0:
        loads.append({"type": "tip_moment", "moment_nm": moment})
    # the same rest curvature as softrod's profile: each node's arc position twice
    s_m, kappa = [], []
    for e in range(ELEMENTS):
        s_m += [e * le, (e + 1) * le]
        kappa += [k0[e], k0[e]]
    section = {"length_m": C.LENGTH_M, "ea_n": C.EA_N, "ei_nm2": C.EI_NM2, "elements": ELEMENTS,
               "rest_curvature_profile": {"s_m": s_m, "kappa_per_m": kappa}}
    disc = {
        "element": "exudyn ObjectANCFCable2D, referenceCurvature per element",
        "elements": ELEMENTS,
        "gauss_points_axial": 5,
        "gauss_points_bending": 3,
        "solver": "exudyn SolveStatic, Newton, EigenSparse",
        "load_steps": steps,
        "newton_relative_tolerance": 1e-10,
    }
    values = {
        "tip_position_m": [tip[0], tip[1]],
        "tip_angle_rad": math.atan2(tip[3], tip[2]),
        "nodes": nodes,
        "residual": {"exudyn_newton_residual": res},
    }
    doc = C.document(GENERATOR, f"rest_curvature_{name}", description,
                     C.params(loads, disc, sections=[section]), values,
                     extra_versions=("exudyn",), timing_s={"total": t.elapsed})
    path = os.path.join(out_dir, f"exudyn_rest_curvature_{name}.json")
    C.write_json(path, doc)
    return [{"case": f"rest_curvature_{name}", "generator": f"exudyn ne={ELEMENTS}", "tip": [tip[0], tip[1]],
             "angle": values["tip_angle_rad"], "time": t.elapsed, "path": path}]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for name in CASES:
        for row in run_case(name, a.out_dir):
            print(f"{row['case']:28s} tip = ({row['tip'][0]:.12f}, {row['tip'][1]:.12f}) angle = {row['angle']:.12f}")


if __name__ == "__main__":
    main()
