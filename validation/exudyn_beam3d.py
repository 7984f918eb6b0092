"""3-D cantilevers with torsion and combined loads from exudyn's beams, static solves:
the reference for softrod's full 3-D ANCF element (`Ancf3d`, tests/ancf3d_exudyn.rs).

Models compared:
- softrod `Ancf3d`: a Kirchhoff rod (no shear deformation) with a section frame:
  energy 1/2 int (EA eps^2 + EI_Y kappa_Y^2 + EI_Z kappa_Z^2 + GJ tau^2) dX, extensible.
- exudyn `ObjectBeamGeometricallyExact` (Simo-Reissner: shear deformable, extensible,
  torsion; two nodes NodeRigidBodyEP, linear interpolation, one-point strains; its
  docstring and main/src/Objects/CObjectBeamGeometricallyExact.cpp of
  github.com/jgerstmayr/EXUDYN): section stiffness diag(EA, GA_y, GA_z, GJ, EI_y, EI_z).
- exudyn `ObjectANCFBeam` (NodePointSlope23: r, r_Y, r_Z; shear deformable, its
  docstring: "OBJECT UNDER CONSTRUCTION"): solved too, written where it converges.

What is compared, and why the bound: both theories agree in the slender limit.
Simo-Reissner adds the shear deflection, in linear theory |F_perp| L / GA at the tip;
with the rod chosen here (L = 1 m, EI/(EA L^2) = 2.5e-6 and 4e-6, GA = EA/2.6) this is
at most a few 1e-5 L for the loads below (`shear_gap_estimate_m`, per case), below the
1e-4 L the Rust tests require. exudyn's element converges at second order in the
element length: the finest two meshes give a Richardson estimate
(`tip_position_extrapolated_m`) and a discretization error estimate, both written.

Boundary: the base node fully fixed (GenericJoint to ground for the geometrically exact
beam; all 9 coordinates by CoordinateConstraint for the ANCF beam).

Loads (dead, world axes, at the tip):
- tip_force: LoadForceVector on MarkerNodeRigid of the tip node;
- tip_moment: LoadTorqueVector on MarkerNodeRigid of the tip node. exudyn's torque is
  a dead moment (virtual work M . delta theta); softrod's is the potential M . phi of
  the rotation vector phi of the tip frame. The two agree for rotations about a fixed
  axis (a pure twist) and to first order in the rotation (the small case): only those
  cases carry a moment;
- section_force: a force at the point (Y, Z) of the tip section (MarkerBodyPosition of
  the last element at localPosition [L_e/2, Y, Z]; the section is rigid in exudyn's
  beam); two opposite forces at Z = +h and -h make a couple that turns with the
  section. A conservative load in both codes (softrod: the force on r + Y r_Y + Z r_Z).

Solver: mbs.SolveStatic, Newton with EigenSparse, load steps (1 small, 20 large, adaptive),
relative tolerance 1e-8, absolute 1e-10.

Run: `python validation/exudyn_beam3d.py [--out-dir reference] [--case NAME ...]`
(or through `make_references.py --only beam3d`).
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
    GenericJoint,
    LoadForceVector,
    LoadTorqueVector,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    MarkerNodeRigid,
    NodePointGround,
    NodePointSlope23,
    NodeRigidBodyEP,
    ObjectANCFBeam,
    ObjectBeamGeometricallyExact,
    ObjectGround,
)

GENERATOR = "validation/exudyn_beam3d.py"
LENGTH_M = 1.0
EA_N = 1.0e4
EI_Y_NM2 = 0.025  # bending about the section's Y axis (deflection along z)
EI_Z_NM2 = 0.04  # bending about the section's Z axis (deflection along y)
GJ_NM2 = 0.019
POISSON = 0.3
GA_N = EA_N / (2.0 * (1.0 + POISSON))  # no shear correction factor (the gap is small either way)
# exudyn's Newton fails from 64 elements on (both beams, every case here: its Jacobian of these
# stiff short elements); 8, 16, 32 converge, and the Richardson estimate from the last two is
# far inside the bound
ELEMENTS = [8, 16, 32]
# the ANCF beam takes minutes at 32 elements on the large cases with bending (more than
# 4 min on 2 cores, where the geometrically exact beam takes 1 s): 8 and 16 only there
ANCF_ELEMENTS = {"oblique_large": [8, 16], "couple_large": [8, 16]}
RELATIVE_TOLERANCE = 1e-8
ABSOLUTE_TOLERANCE = 1e-10
LOAD_STEPS_SMALL = 1
LOAD_STEPS_LARGE = 20
BASE = {"position_m": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]}


def _force(f):
    return {"type": "tip_force", "force_n": list(f)}


def _moment(m):
    return {"type": "tip_moment", "moment_nm": list(m)}


def _section_force(y, z, f):
    return {"type": "section_force", "y_m": y, "z_m": z, "force_n": list(f)}


H_ARM = 0.05
CASES = {
    "combined_small": (
        "Tip force (0, 1.2e-4, -7.5e-5) N and tip torque (1.9e-5, 0, 0) N m: bending in both planes "
        "(tip deflections 1e-3 L) and a twist of 1e-3 rad (linear range).",
        [_force([0.0, 1.2e-4, -7.5e-5]), _moment([1.9e-5, 0.0, 0.0])],
    ),
    "oblique_large": (
        "Oblique tip force (-0.01, 0.08, -0.1) N on a rod with EI_Z = 1.6 EI_Y: large 3-D bending, "
        "the deflection not in the plane of the force, torsion by coupling.",
        [_force([-0.01, 0.08, -0.1])],
    ),
    "twist_large": (
        "Tip torque 1.5 GJ/L about the axis: a uniform twist of 1.5 rad.",
        [_moment([1.5 * GJ_NM2 / LENGTH_M, 0.0, 0.0])],
    ),
    "couple_large": (
        "Tip force (0, 0, -0.04) N plus two opposite forces (0, +-0.15, 0) N at the tip section points "
        "Z = +-0.05 m (a couple turning with the section): large bending and torsion together.",
        [_force([0.0, 0.0, -0.04]), _section_force(0.0, H_ARM, [0.0, 0.15, 0.0]),
         _section_force(0.0, -H_ARM, [0.0, -0.15, 0.0])],
    ),
}

CHEAP = ["combined_small"]


def _section():
    s = exu.BeamSection()
    s.stiffnessMatrix = np.diag([EA_N, GA_N, GA_N, GJ_NM2, EI_Y_NM2, EI_Z_NM2])
    s.massPerLength = 0.0
    s.inertia = np.zeros((3, 3))
    return s


def build(kind, ne, loads):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    le = LENGTH_M / ne
    sec = _section()
    if kind == "ge":
        nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[i * le, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))
                 for i in range(ne + 1)]
        elems = [mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]],
                                                            length=le, sectionData=sec))
                 for i in range(ne)]
        mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=mbs.AddObject(ObjectGround())))
        m0 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))
        mbs.AddObject(GenericJoint(markerNumbers=[mg, m0]))
    else:
        nodes = [mbs.AddNode(NodePointSlope23(referenceCoordinates=[i * le, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]))
                 for i in range(ne + 1)]
        elems = [mbs.AddObject(ObjectANCFBeam(nodeNumbers=[nodes[i], nodes[i + 1]], length=le,
                                              sectionData=sec))
                 for i in range(ne)]
        g = mbs.AddNode(NodePointGround())
        mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=g, coordinate=0))
        for c in range(9):
            mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc]))
    mt = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))
    for ld in loads:
        if ld["type"] == "tip_force":
            mbs.AddLoad(LoadForceVector(markerNumber=mt, loadVector=ld["force_n"]))
        elif ld["type"] == "tip_moment":
            mbs.AddLoad(LoadTorqueVector(markerNumber=mt, loadVector=ld["moment_nm"]))
        elif ld["type"] == "section_force":
            mp = mbs.AddMarker(MarkerBodyPosition(bodyNumber=elems[-1], localPosition=[le / 2, ld["y_m"], ld["z_m"]]))
            mbs.AddLoad(LoadForceVector(markerNumber=mp, loadVector=ld["force_n"]))
    mbs.Assemble()
    return SC, mbs, nodes, elems


def solve(kind, ne, loads, steps):
    SC, mbs, nodes, elems = build(kind, ne, loads)
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = steps
    s.staticSolver.adaptiveStep = True
    s.staticSolver.newton.relativeTolerance = RELATIVE_TOLERANCE
    s.staticSolver.newton.absoluteTolerance = ABSOLUTE_TOLERANCE
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    try:
        ok = bool(mbs.SolveStatic(s))
    except Exception as err:  # exudyn raises on a failed solve
        C.log(f"  exudyn {kind} failed for {ne} elements: {str(err).splitlines()[0]}")
        ok = False
    tip = nodes[-1]
    p = np.asarray(mbs.GetNodeOutput(tip, exu.OutputVariableType.Position))
    if kind == "ge":
        # columns: the section axes (local x, y, z) in world coordinates
        R = np.asarray(mbs.GetNodeOutput(tip, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
    else:
        c = np.asarray(mbs.GetNodeOutput(tip, exu.OutputVariableType.Coordinates)) + \
            np.array([LENGTH_M, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        ry, rz = c[3:6], c[6:9]
        R = np.column_stack([np.cross(ry, rz) / np.linalg.norm(np.cross(ry, rz)), ry, rz])
    return ok, p, R


def rotation_vector(R):
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    th = math.acos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return w * (0.5 if th < 1e-12 else th / (2.0 * math.sin(th)))


def linear_tip(loads):
    """Linear theory at the tip (Euler-Bernoulli, extensible, torsion): displacement (m)
    and rotation (rad), and the Simo-Reissner shear deflection (m)."""
    f = np.zeros(3)
    m = np.zeros(3)
    for ld in loads:
        if ld["type"] == "tip_force":
            f += ld["force_n"]
        elif ld["type"] == "tip_moment":
            m += ld["moment_nm"]
        elif ld["type"] == "section_force":
            f += ld["force_n"]
            m += np.cross([0.0, ld["y_m"], ld["z_m"]], ld["force_n"])
    L = LENGTH_M
    u = np.array([f[0] * L / EA_N,
                  f[1] * L**3 / (3 * EI_Z_NM2) + m[2] * L**2 / (2 * EI_Z_NM2),
                  f[2] * L**3 / (3 * EI_Y_NM2) - m[1] * L**2 / (2 * EI_Y_NM2)])
    rot = np.array([m[0] * L / GJ_NM2,
                    -f[2] * L**2 / (2 * EI_Y_NM2) + m[1] * L / EI_Y_NM2,
                    f[1] * L**2 / (2 * EI_Z_NM2) + m[2] * L / EI_Z_NM2])
    shear = np.array([0.0, f[1] * L / GA_N, f[2] * L / GA_N])
    return u, rot, shear


def run_case(name, out_dir):
    description, loads = CASES[name]
    large = name.endswith("_large")
    steps = LOAD_STEPS_LARGE if large else LOAD_STEPS_SMALL
    out = {}
    times = {}
    with C.Timer() as t_all:
        for kind, elements in (("ge", ELEMENTS), ("ancf", ANCF_ELEMENTS.get(name, ELEMENTS))):
            runs = []
            for ne in elements:
                with C.Timer() as t:
                    ok, p, R = solve(kind, ne, loads, steps)
                times[f"{kind}_{ne}"] = t.elapsed
                runs.append({"elements": ne, "converged": ok, "tip_position_m": p, "tip_frame": R,
                             "tip_rotation_vector_rad": rotation_vector(R)})
                C.log(f"  exudyn beam3d {name} {kind} ne={ne:3d} ok={ok} tip=({p[0]:.10f}, {p[1]:.10f}, "
                      f"{p[2]:.10f}) {t.elapsed:.2f}s")
            conv = [r for r in runs if r["converged"]]
            entry = {"runs": runs, "not_converged_elements": [r["elements"] for r in runs if not r["converged"]]}
            if len(conv) >= 2 and conv[-1]["elements"] == 2 * conv[-2]["elements"]:
                a, b = np.asarray(conv[-2]["tip_position_m"]), np.asarray(conv[-1]["tip_position_m"])
                entry["finest_elements"] = conv[-1]["elements"]
                entry["tip_position_finest_m"] = b
                entry["tip_frame_finest"] = conv[-1]["tip_frame"]
                # second order: e(h) ~ c h^2, so p(0) ~ b + (b - a)/3
                entry["tip_position_extrapolated_m"] = b + (b - a) / 3.0
                entry["discretization_error_estimate_m"] = float(np.linalg.norm(b - a) / 3.0)
                if len(conv) >= 3 and conv[-2]["elements"] == 2 * conv[-3]["elements"]:
                    z = np.asarray(conv[-3]["tip_position_m"])
                    d1, d2 = np.linalg.norm(a - z), np.linalg.norm(b - a)
                    entry["observed_order"] = float(math.log2(d1 / d2)) if d2 > 0 else None
                    # the same extrapolation one mesh coarser: their distance bounds the
                    # error of the coarser estimate (and so, with room, of the finer one)
                    coarser = a + (a - z) / 3.0
                    entry["extrapolation_error_estimate_m"] = float(np.linalg.norm(entry["tip_position_extrapolated_m"]
                                                                                   - coarser))
            elif conv:
                entry["finest_elements"] = conv[-1]["elements"]
                entry["tip_position_finest_m"] = conv[-1]["tip_position_m"]
                entry["tip_frame_finest"] = conv[-1]["tip_frame"]
            out[kind] = entry
    if "tip_position_extrapolated_m" not in out["ge"]:
        raise RuntimeError(f"exudyn: the geometrically exact beam did not converge on two meshes for {name}")
    u, rot, shear = linear_tip(loads)
    values = {
        "geometrically_exact": out["ge"],
        "ancf_beam": out["ancf"],
        "shear_gap_estimate_m": float(np.linalg.norm(shear)),
    }
    if not large:
        values["linear_theory_tip_displacement_m"] = u
        values["linear_theory_tip_rotation_rad"] = rot
    disc = {
        "elements_geometrically_exact": ELEMENTS,
        "elements_ancf_beam": ANCF_ELEMENTS.get(name, ELEMENTS),
        "geometrically_exact": "ObjectBeamGeometricallyExact, NodeRigidBodyEP nodes (the static solver does not "
        "take Lie-group nodes), base by GenericJoint to ground",
        "ancf_beam": "ObjectANCFBeam, NodePointSlope23 nodes, crossSectionPenaltyFactor [1, 1, 1], base: 9 "
        "CoordinateConstraints",
        "section_stiffness": "diag(EA, GA_y, GA_z, GJ, EI_y, EI_z)",
        "solver": "exudyn SolveStatic, Newton, EigenSparse, adaptive load steps",
        "load_steps": steps,
        "newton_relative_tolerance": RELATIVE_TOLERANCE,
        "newton_absolute_tolerance": ABSOLUTE_TOLERANCE,
        "tip_frame_note": "columns: the section axes x, y, z of the tip in world coordinates (ANCF beam: "
        "r_Y, r_Z and their cross product normalized)",
        "extrapolation_note": "tip_position_extrapolated_m = p_h + (p_h - p_2h)/3 (second order); "
        "discretization_error_estimate_m = |p_h - p_2h|/3 (the error of p_h); "
        "extrapolation_error_estimate_m: the distance of the extrapolations from (h, 2h) and (2h, 4h)",
    }
    params = {
        "length_m": LENGTH_M,
        "ea_n": EA_N,
        "ei_y_nm2": EI_Y_NM2,
        "ei_z_nm2": EI_Z_NM2,
        "gj_nm2": GJ_NM2,
        "ga_n": GA_N,
        "base": BASE,
        "gravity_m_per_s2": [0.0, 0.0, 0.0],
        "loads": loads,
        "discretization": disc,
    }
    doc = C.document(GENERATOR, f"beam3d_{name}", description, params, values,
                     extra_versions=("exudyn",), timing_s={"total": t_all.elapsed, "per_run": times})
    path = os.path.join(out_dir, f"exudyn_beam3d_{name}.json")
    C.write_json(path, doc)
    tip = out["ge"]["tip_position_extrapolated_m"]
    return [{"case": f"beam3d_{name}", "generator": f"exudyn GE beam ne={out['ge']['finest_elements']}",
             "tip": tip, "angle": float(np.linalg.norm(out["ge"]["runs"][-1]["tip_rotation_vector_rad"])),
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
            print(f"{row['case']:30s} tip = ({t[0]:.12f}, {t[1]:.12f}, {t[2]:.12f})  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
