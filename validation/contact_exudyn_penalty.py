"""exudyn's penalty contact of a cable with a circle, at growing stiffness.

The case of contact_elastica_down (a cantilever, L = 1 m, EI = 1 N m^2, EA = 1e4 N,
tip load (0, -2) N, a rigid circle of radius 0.02 m at (0.6, -0.15) m), modelled in
exudyn with ObjectANCFCable2D elements (the same element softrod implements) and one
ObjectContactCircleCable2D per element: a penalty contact whose gap is measured to
`SEGMENTS` straight segments per element (MarkerBodyCable2DShape) and whose force per
segment is contactStiffness x penetration. Static solve (mbs.SolveStatic) with load steps
and exudyn's discontinuous iterations for the contact's active set.

The contact force is taken from the clamp: the rod is in equilibrium under the tip load P,
the clamp's force F_clamp and the contact force, so F_contact = -(P + F_clamp), with
F_clamp the Lagrange multipliers of the base's x and y CoordinateConstraints (their sign
checked by a solve without contact, where F_clamp = -P). At stiffness k the penetration
and so the force deficit are O(1/k): the reactions approach the rigid-contact answer.

Run: `python validation/contact_exudyn_penalty.py [--out-dir reference]`.
"""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

import exudyn as exu  # noqa: E402
from exudyn.itemInterface import (  # noqa: E402
    CoordinateConstraint,
    LoadForceVector,
    MarkerBodyCable2DShape,
    MarkerBodyPosition,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    NodeGenericData,
    NodePoint2DSlope1,
    NodePointGround,
    ObjectANCFCable2D,
    ObjectContactCircleCable2D,
    ObjectGround,
)

GENERATOR = "validation/contact_exudyn_penalty.py"
NAME = "contact_exudyn_penalty"
LENGTH_M = 1.0
EI_NM2 = 1.0
EA_N = 1.0e4
TIP_LOAD_N = [0.0, -2.0]
CENTER_M = [0.6, -0.15]
RADIUS_M = 0.02
ELEMENTS = 32
SEGMENTS = 12
STIFFNESSES = [1e2, 1e3, 1e4, 1e5, 1e6, 1e7]
LOAD_STEPS = 40


def solve(k, contact=True):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ne = ELEMENTS
    le = LENGTH_M / ne
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * le, 0.0, 1.0, 0.0])) for i in range(ne + 1)]
    elems = [mbs.AddObject(ObjectANCFCable2D(length=le, massPerLength=0.0, bendingStiffness=EI_NM2, axialStiffness=EA_N,
                                             nodeNumbers=[nodes[i], nodes[i + 1]], useReducedOrderIntegration=0))
             for i in range(ne)]
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    clamps = []
    for c in range(4):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        clamps.append(mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc])))
    mt = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadForceVector(markerNumber=mt, loadVector=[TIP_LOAD_N[0], TIP_LOAD_N[1], 0.0]))
    if contact:
        og = mbs.AddObject(ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        mcirc = mbs.AddMarker(MarkerBodyPosition(bodyNumber=og, localPosition=[CENTER_M[0], CENTER_M[1], 0.0]))
        for e in elems:
            data = mbs.AddNode(NodeGenericData(initialCoordinates=[0.1] * SEGMENTS, numberOfDataCoordinates=SEGMENTS))
            mcable = mbs.AddMarker(MarkerBodyCable2DShape(bodyNumber=e, numberOfSegments=SEGMENTS))
            mbs.AddObject(ObjectContactCircleCable2D(markerNumbers=[mcirc, mcable], nodeNumber=data,
                                                     numberOfContactSegments=SEGMENTS, contactStiffness=k,
                                                     circleRadius=RADIUS_M, offset=0.0))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = LOAD_STEPS
    s.staticSolver.newton.relativeTolerance = 1e-8
    s.staticSolver.newton.absoluteTolerance = 1e-10
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.discontinuous.maxIterations = 50
    s.staticSolver.discontinuous.iterationTolerance = 1e-12
    s.staticSolver.verboseMode = 0
    s.solutionSettings.writeSolutionToFile = False
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ok = bool(mbs.SolveStatic(s))
    clamp = np.array([mbs.GetObjectOutput(clamps[c], exu.OutputVariableType.Force) for c in range(2)], dtype=float).ravel()
    q = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates) for n in nodes])
    ref = np.array([[i * le, 0.0, 1.0, 0.0] for i in range(ne + 1)])
    return ok, clamp, ref + q


def run_all(out_dir):
    t0 = time.perf_counter()
    p = np.array(TIP_LOAD_N)
    # the sign of exudyn's constraint force: without contact the clamp holds -P
    ok, clamp0, _ = solve(0.0, contact=False)
    if not ok:
        raise RuntimeError("exudyn: the solve without contact failed")
    if np.allclose(clamp0, -p, rtol=1e-8, atol=1e-12):
        sign = 1.0
    elif np.allclose(clamp0, p, rtol=1e-8, atol=1e-12):
        sign = -1.0
    else:
        raise RuntimeError(f"exudyn clamp force {clamp0} is neither P nor -P")
    runs = []
    for k in STIFFNESSES:
        ok, clamp, nodes = solve(k)
        f_contact = -(p + sign * clamp)
        runs.append({"contact_stiffness_n_per_m": k, "converged": ok,
                     "contact_force_n": f_contact.tolist(), "reaction_n": float(np.linalg.norm(f_contact)),
                     "tip_position_m": nodes[-1, :2].tolist()})
        print(f"k = {k:.0e}: converged {ok}, contact force {f_contact}, |F| = {np.linalg.norm(f_contact):.12e} N")
    params = {"length_m": LENGTH_M, "ei_nm2": EI_NM2, "ea_n": EA_N, "rod_radius_m": 0.0, "elements": ELEMENTS,
              "segments_per_element": SEGMENTS, "load_steps": LOAD_STEPS,
              "obstacle": {"shape": "circle", "center_m": CENTER_M, "radius_m": RADIUS_M},
              "tip_load_n": TIP_LOAD_N, "clamp_force_sign": sign}
    doc = C.document(GENERATOR, NAME, "exudyn ObjectContactCircleCable2D (penalty) at growing contact stiffness, "
                     "static solve; the contact force from the clamp's reaction", params, {"runs": runs},
                     extra_versions=("exudyn",), timing_s=time.perf_counter() - t0)
    path = os.path.join(out_dir, f"{NAME}.json")
    C.write_json(path, doc)
    return [{"case": NAME, "generator": "exudyn penalty contact", "tip": runs[-1]["tip_position_m"], "angle": 0.0,
             "time": time.perf_counter() - t0, "path": path}]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "reference"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    run_all(a.out_dir)


if __name__ == "__main__":
    main()
