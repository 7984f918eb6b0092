"""The soft parallel robot in exudyn, static solves: the reference for softrod's
parallel robot with full 3-D legs (`softrod::parallel`, tests/parallel_exudyn.rs).

The robot (softrod's params::parallel, weightless here): three legs of length L = 0.12 m
clamped at z = 0 on the base circle of radius 0.06 m at the angles 90 + 120 i degrees,
hanging down to the platform circle of radius 0.04 m, straight in the reference; EA = 300 N,
EI = 0.025 N m^2 (both axes), GJ = EI/1.5; each leg's end rigidly joined to a rigid platform
whose centre is the centre of the platform circle.

exudyn model: each leg a chain of ObjectBeamGeometricallyExact (Simo-Reissner; two
NodeRigidBodyEP nodes per element, linear interpolation, one-point strains) with the section
stiffness diag(EA, GA, GA, GJ, EI, EI); its base node fixed by a GenericJoint to ground; the
platform an ObjectRigidBody (NodeRigidBodyEP) and each leg's end node joined to it by a
GenericJoint (all six axes) between MarkerBodyRigid (the platform point, the joint frame the
leg's section frame) and MarkerNodeRigid (the leg's end node).

What is compared, and why the bound: softrod's legs are Kirchhoff rods (no shear
deformation). The geometrically exact beam adds the shear deflection, F L / GA per leg, which
for these short, thick legs (12 EI/(GA L^2) = 0.2 with an elastomer's GA = EA/3) would be a
fifth of the bending deflection: a different theory. GA is set to 1000 EA here, the Kirchhoff
limit of exudyn's beam (shear/bending 7e-5 of the lateral deflection; the per-leg F L / GA is
written per case as `shear_gap_estimate_m`). exudyn's element converges at second order in the element length:
the finest two meshes give a Richardson estimate (`platform_position_extrapolated_m`) and a
discretization error estimate, both written.

Loads (dead, world axes, at the platform centre; no gravity): an axial load (0, 0, -2) N
(a 200 g payload's weight), a lateral load (0.2, 0, 0) N, a torque (0, 0, 5e-3) N m
(LoadForceVector / LoadTorqueVector on MarkerBodyRigid of the platform). exudyn's torque is a
dead moment; softrod's is the potential M . psi of the platform's rotation vector: the same
for a rotation about a fixed axis, and the torque case turns the platform about z only (by
symmetry, to round-off).

Solver: mbs.SolveStatic, Newton with EigenSparse, adaptive load steps (5), relative tolerance
1e-8, absolute 1e-10.

Run: `python validation/exudyn_parallel.py [--out-dir reference] [--case NAME ...]`
(or through `make_references.py --only parallel`).
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
    GenericJoint,
    LoadForceVector,
    LoadTorqueVector,
    MarkerBodyRigid,
    MarkerNodeRigid,
    NodeRigidBodyEP,
    ObjectBeamGeometricallyExact,
    ObjectGround,
    ObjectRigidBody,
)
from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters  # noqa: E402

GENERATOR = "validation/exudyn_parallel.py"
LEGS = 3
BASE_RADIUS_M = 0.06
PLATFORM_RADIUS_M = 0.04
LEG_LENGTH_M = 0.12
EA_N = 300.0
EI_NM2 = 0.025
GJ_NM2 = EI_NM2 / 1.5
GA_N = 1000.0 * EA_N
PLATFORM_MASS_KG = 0.05  # does not load a weightless static solve; the body needs one
# exudyn's Newton fails at 32 elements per leg on the lateral case (these stiff short elements
# with a stiff GA); 4, 8, 16 converge on every case
ELEMENTS = [4, 8, 16]
RELATIVE_TOLERANCE = 1e-8
ABSOLUTE_TOLERANCE = 1e-10
LOAD_STEPS = 5
RETRY_TOLERANCES = [RELATIVE_TOLERANCE, 1e-7, 1e-6]
VERBOSE = False

CASES = {
    "axial": ("Axial load (0, 0, -2) N at the platform centre (a 200 g payload).",
              {"force_n": [0.0, 0.0, -2.0], "moment_nm": [0.0, 0.0, 0.0]}),
    "lateral": ("Lateral load (0.2, 0, 0) N at the platform centre.",
                {"force_n": [0.2, 0.0, 0.0], "moment_nm": [0.0, 0.0, 0.0]}),
    "torque": ("Torque (0, 0, 5e-3) N m about the vertical axis at the platform centre.",
               {"force_n": [0.0, 0.0, 0.0], "moment_nm": [0.0, 0.0, 5e-3]}),
}
CHEAP = list(CASES)


def geometry():
    gap = BASE_RADIUS_M - PLATFORM_RADIUS_M
    h = math.sqrt(LEG_LENGTH_M**2 - gap**2)
    legs = []
    for i in range(LEGS):
        a = math.pi / 2 + 2 * math.pi * i / LEGS
        c, s = math.cos(a), math.sin(a)
        b = np.array([BASE_RADIUS_M * c, BASE_RADIUS_M * s, 0.0])
        p = np.array([PLATFORM_RADIUS_M * c, PLATFORM_RADIUS_M * s, -h])
        t = (p - b) / LEG_LENGTH_M
        e2 = np.cross([0.0, 0.0, 1.0], t)
        e2 /= np.linalg.norm(e2)
        e3 = np.cross(t, e2)
        legs.append((b, p, np.column_stack([t, e2, e3])))
    return h, legs


def _section():
    s = exu.BeamSection()
    s.stiffnessMatrix = np.diag([EA_N, GA_N, GA_N, GJ_NM2, EI_NM2, EI_NM2])
    s.massPerLength = 0.0
    s.inertia = np.zeros((3, 3))
    return s


def solve(ne, load, rel_tol=None):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    h, legs = geometry()
    sec = _section()
    le = LEG_LENGTH_M / ne
    ground = mbs.AddObject(ObjectGround())
    centre = np.array([0.0, 0.0, -h])
    nb = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=list(centre) + [1.0, 0.0, 0.0, 0.0]))
    body = mbs.AddObject(ObjectRigidBody(physicsMass=PLATFORM_MASS_KG,
                                         physicsInertia=[1e-4, 1e-4, 2e-4, 0.0, 0.0, 0.0],
                                         nodeNumber=nb))
    for b, p, R in legs:
        ep = list(RotationMatrix2EulerParameters(R))
        t = R[:, 0]
        nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=list(b + k * le * t) + ep))
                 for k in range(ne + 1)]
        for k in range(ne):
            mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[k], nodes[k + 1]], length=le,
                                                        sectionData=sec))
        mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=list(b)))
        m0 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))
        # ground frame rotated to the leg's section frame: both joint frames agree in the reference
        mbs.AddObject(GenericJoint(markerNumbers=[mg, m0], rotationMarker0=R))
        mp = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=list(p - centre)))
        mt = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))
        mbs.AddObject(GenericJoint(markerNumbers=[mp, mt], rotationMarker0=R))
    mc = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddLoad(LoadForceVector(markerNumber=mc, loadVector=load["force_n"]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mc, loadVector=load["moment_nm"]))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = LOAD_STEPS
    s.staticSolver.adaptiveStep = True
    s.staticSolver.newton.relativeTolerance = rel_tol or RELATIVE_TOLERANCE
    s.staticSolver.newton.absoluteTolerance = ABSOLUTE_TOLERANCE
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 2 if VERBOSE else 0
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    try:
        ok = bool(mbs.SolveStatic(s, showHints=VERBOSE))
    except Exception as err:  # exudyn raises on a failed solve
        C.log(f"  exudyn parallel failed for {ne} elements: {str(err).splitlines()[0]}")
        ok = False
    x = np.asarray(mbs.GetNodeOutput(nb, exu.OutputVariableType.Position))
    R = np.asarray(mbs.GetNodeOutput(nb, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
    return ok, x, R


def rotation_vector(R):
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    th = math.acos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return w * (0.5 if th < 1e-12 else th / (2.0 * math.sin(th)))


def run_case(name, out_dir):
    description, load = CASES[name]
    runs = []
    times = {}
    with C.Timer() as t_all:
        for ne in ELEMENTS:
            with C.Timer() as t:
                # exudyn's Newton stalls near round-off on some meshes: looser tolerances then
                for tol in RETRY_TOLERANCES:
                    ok, x, R = solve(ne, load, tol)
                    if ok:
                        break
            times[str(ne)] = t.elapsed
            psi = rotation_vector(R)
            runs.append({"elements_per_leg": ne, "converged": ok, "newton_relative_tolerance": tol, "platform_position_m": x,
                         "platform_rotation_vector_rad": psi})
            C.log(f"  exudyn parallel {name} ne={ne:3d} ok={ok} x=({x[0]:.10f}, {x[1]:.10f}, {x[2]:.10f}) "
                  f"psi=({psi[0]:.3e}, {psi[1]:.3e}, {psi[2]:.3e}) {t.elapsed:.2f}s")
    conv = [r for r in runs if r["converged"]]
    if len(conv) < 3 or [r["elements_per_leg"] for r in conv] != ELEMENTS:
        raise RuntimeError(f"exudyn: the parallel robot did not converge on every mesh for {name}")
    z, a, b = (np.asarray(r["platform_position_m"]) for r in conv)
    pz, pa, pb = (np.asarray(r["platform_rotation_vector_rad"]) for r in conv)
    d1, d2 = np.linalg.norm(a - z), np.linalg.norm(b - a)
    f = np.asarray(load["force_n"])
    values = {
        "runs": runs,
        "platform_position_finest_m": b,
        "platform_position_extrapolated_m": b + (b - a) / 3.0,
        "discretization_error_estimate_m": float(np.linalg.norm(b - a) / 3.0),
        "extrapolation_error_estimate_m": float(np.linalg.norm((b + (b - a) / 3.0) - (a + (a - z) / 3.0))),
        "observed_order": float(math.log2(d1 / d2)) if d2 > 0 else None,
        "platform_rotation_vector_extrapolated_rad": pb + (pb - pa) / 3.0,
        "rotation_error_estimate_rad": float(np.linalg.norm(pb - pa) / 3.0),
        "rotation_extrapolation_error_estimate_rad": float(np.linalg.norm((pb + (pb - pa) / 3.0)
                                                                          - (pa + (pa - pz) / 3.0))),
        "shear_gap_estimate_m": float(np.linalg.norm(f) / LEGS * LEG_LENGTH_M / GA_N),
    }
    h, legs = geometry()
    params = {
        "legs": LEGS,
        "base_radius_m": BASE_RADIUS_M,
        "platform_radius_m": PLATFORM_RADIUS_M,
        "leg_length_m": LEG_LENGTH_M,
        "platform_reference_m": [0.0, 0.0, -h],
        "ea_n": EA_N,
        "ei_nm2": EI_NM2,
        "gj_nm2": GJ_NM2,
        "ga_n": GA_N,
        "gravity_m_per_s2": [0.0, 0.0, 0.0],
        "load": load,
        "discretization": {
            "elements_per_leg": ELEMENTS,
            "legs": "ObjectBeamGeometricallyExact, NodeRigidBodyEP nodes, base by GenericJoint to ground",
            "platform": "ObjectRigidBody (NodeRigidBodyEP), each leg end by GenericJoint (6 axes) on "
            "MarkerBodyRigid / MarkerNodeRigid",
            "section_stiffness": "diag(EA, GA, GA, GJ, EI, EI)",
            "solver": "exudyn SolveStatic, Newton, EigenSparse, adaptive load steps",
            "load_steps": LOAD_STEPS,
            "newton_relative_tolerance": RELATIVE_TOLERANCE,
            "newton_absolute_tolerance": ABSOLUTE_TOLERANCE,
            "extrapolation_note": "x_extrapolated = x_h + (x_h - x_2h)/3 (second order); "
            "discretization_error_estimate_m = |x_h - x_2h|/3; extrapolation_error_estimate_m: the "
            "distance of the extrapolations from (h, 2h) and (2h, 4h)",
        },
    }
    doc = C.document(GENERATOR, f"parallel_{name}", description, params, values,
                     extra_versions=("exudyn",), timing_s={"total": t_all.elapsed, "per_run": times})
    path = os.path.join(out_dir, f"exudyn_parallel_{name}.json")
    C.write_json(path, doc)
    return [{"case": f"parallel_{name}", "generator": f"exudyn GE beam ne={ELEMENTS[-1]}",
             "tip": values["platform_position_extrapolated_m"],
             "angle": float(np.linalg.norm(values["platform_rotation_vector_extrapolated_rad"])),
             "time": t_all.elapsed, "path": path}]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    ap.add_argument("--case", nargs="*", default=list(CASES))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for name in a.case:
        for row in run_case(name, a.out_dir):
            t = row["tip"]
            print(f"{row['case']:30s} platform = ({t[0]:.12f}, {t[1]:.12f}, {t[2]:.12f})  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
