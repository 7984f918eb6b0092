"""Spatial cantilever references from exudyn's 3-D ANCF cable (ObjectANCFCable), static solves.

Model (the same as softrod's SpatialCable): nodes NodePointSlope1 with coordinates
[x, y, z, dx/dX, dy/dX, dz/dX], cubic Hermite interpolation, axial strain
eps = |r'| - 1, curvature vector kappa = (r' x r'') / |r'|^2, isotropic bending,
no torsion, delta W_e = int (EA eps delta eps + EI kappa . delta kappa) dX.
exudyn integrates the axial term with 5 Gauss points (order 9) and the bending
term with 3 (order 5) when `useReducedOrderIntegration = 0` (the default, used here).

What was checked that exudyn's element is softrod's model:
- the docstring of ObjectANCFCable (exudyn 1.13.6: "see ObjectANCFCable2D, which is
  almost identical to 3D case"; no torsion) and its source,
  main/src/Objects/CObjectANCFCable.cpp of github.com/jgerstmayr/EXUDYN (read at the
  1.11.0 tag): axial strain rxNorm - 1 at the order-9 Gauss points, curvature
  rx.CrossProduct(rxx) / rxNorm2 at the order-5 points, elastic forces
  EA eps d(eps)/dq + EI kappa . d(kappa)/dq;
- numerically, on every solution written here: exudyn's own output variables
  StrainLocal and CurvatureLocal at the Gauss points against eps and kappa computed
  by numpy from the nodes (`strain_check_max_abs`, round-off), and the residual
  grad U - Q_ext of softrod's energy at exudyn's nodes (`softrod_model_residual_*`,
  by `cable_residual` below: independent numpy, same Gauss rules), which is at
  exudyn's Newton tolerance; one Newton step of that residual from exudyn's nodes
  (`newton_correction_*`, finite-difference tangent) estimates how far exudyn's
  nodes are from the exact discrete equilibrium.

Boundary: all six coordinates of the base node fixed (r_0 = 0, r_0' = (1, 0, 0)),
softrod's Clamp::Full, by CoordinateConstraint to a NodePointGround.

Loads (dead, world axes): tip force by LoadForceVector on a MarkerNodePosition of
the tip node; a uniform line load w by LoadMassProportional on a MarkerBodyMass of
every element (massPerLength = 1 kg/m, "acceleration" w: the exact integral).
exudyn's 3-D cable takes no torque (its AngularVelocity access is not implemented:
the cable has no torsion), so there is no moment case here; softrod's moment is
tested against the closed-form circle instead.

Solver: mbs.SolveStatic, Newton with the EigenSparse linear solver, load steps (one
for the small loads, 20 for the large ones), relative tolerance 1e-8 (1e-10 stalls
on round-off at 32+ elements), absolute 1e-10.

Run: `python validation/exudyn_spatial_cable.py [--out-dir reference] [--case NAME ...]`
(or through `make_references.py --only spatial`).
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
    LoadMassProportional,
    MarkerBodyMass,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    NodePointGround,
    NodePointSlope1,
    ObjectANCFCable,
)

GENERATOR = "validation/exudyn_spatial_cable.py"
ELEMENTS = [2, 4, 8, 16, 32, 64]
RELATIVE_TOLERANCE = 1e-8
ABSOLUTE_TOLERANCE = 1e-10
LOAD_STEPS_SMALL = 1
LOAD_STEPS_LARGE = 20
GAUSS_AXIAL = 5
GAUSS_BENDING = 3
BASE = {"position_m": [0.0, 0.0, 0.0], "angle_rad": 0.0, "direction": [1.0, 0.0, 0.0]}


def _tip(f):
    return {"type": "tip_force", "force_n": list(f)}


def _uniform(w):
    return {"type": "distributed", "profile": "uniform", "w_n_per_m": list(w)}


# name -> (description, loads). Same robot as common.py (L = 0.24 m, two sections,
# EI = 0.025 N m^2 in both planes, EA = 300 N), base along +x. "small": the linear
# range; "large": tip rotation of 60 degrees or more.
CASES = {
    "tip_force_z_small": ("Tip force 0.005 N in -z, out of the xy-plane (linear range).", [_tip([0.0, 0.0, -0.005])]),
    "tip_force_z_large": ("Tip force 2 N in -z, out of the xy-plane (large deflection).", [_tip([0.0, 0.0, -2.0])]),
    "tip_force_oblique_small": (
        "Oblique tip force (0, 0.003, -0.004) N (linear range).",
        [_tip([0.0, 0.003, -0.004])],
    ),
    "tip_force_oblique_large": (
        "Oblique tip force (-0.3, 1.2, -1.6) N, with an axial component (large deflection).",
        [_tip([-0.3, 1.2, -1.6])],
    ),
    "uniform_small": ("Uniform line load (0, 0.03, -0.04) N/m (linear range).", [_uniform([0.0, 0.03, -0.04])]),
    "uniform_large": ("Uniform line load (0, 12, -16) N/m (large deflection).", [_uniform([0.0, 12.0, -16.0])]),
    "twisted_large": (
        "Uniform line load 10 N/m in -z plus a tip force 1.5 N in +y: the bending plane turns along the rod, "
        "a non-planar shape (large deflection).",
        [_uniform([0.0, 0.0, -10.0]), _tip([0.0, 1.5, 0.0])],
    ),
}

# what `make_references.py --only cheap` runs (CI)
CHEAP = ["twisted_large"]


def _tip_force(loads):
    f = np.zeros(3)
    for ld in loads:
        if ld["type"] == "tip_force":
            f += ld["force_n"]
    return f


def _line_load(loads):
    w = np.zeros(3)
    for ld in loads:
        if ld["type"] == "distributed":
            assert ld["profile"] == "uniform"
            w += ld["w_n_per_m"]
    return w


# ---------------------------------------------------------------------------
# exudyn model
# ---------------------------------------------------------------------------

def build(ne, loads):
    """Build the exudyn system; return (SC, mbs, node indices, element indices)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    Le = C.LENGTH_M / ne
    w = _line_load(loads)
    nodes = [mbs.AddNode(NodePointSlope1(referenceCoordinates=[i * Le, 0.0, 0.0, 1.0, 0.0, 0.0]))
             for i in range(ne + 1)]
    elems = [
        mbs.AddObject(
            ObjectANCFCable(
                length=Le,
                massPerLength=1.0 if np.any(w != 0.0) else 0.0,
                bendingStiffness=C.EI_NM2,
                axialStiffness=C.EA_N,
                nodeNumbers=[nodes[i], nodes[i + 1]],
                useReducedOrderIntegration=0,
            )
        )
        for i in range(ne)
    ]
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in range(6):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc]))
    if np.any(w != 0.0):
        for e in elems:
            mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=e))
            mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=list(w)))
    f = _tip_force(loads)
    if np.any(f != 0.0):
        mt = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
        mbs.AddLoad(LoadForceVector(markerNumber=mt, loadVector=list(f)))
    mbs.Assemble()
    return SC, mbs, nodes, elems


def solve(ne, loads, load_steps):
    SC, mbs, nodes, elems = build(ne, loads)
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = load_steps
    s.staticSolver.newton.relativeTolerance = RELATIVE_TOLERANCE
    s.staticSolver.newton.absoluteTolerance = ABSOLUTE_TOLERANCE
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    try:
        ok = bool(mbs.SolveStatic(s))
    except Exception as err:  # exudyn raises on a failed solve in some versions
        C.log(f"  exudyn failed for {ne} elements: {err}")
        ok = False
    conv = mbs.sys["staticSolver"].conv if "staticSolver" in mbs.sys else None
    q = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates, configuration=exu.ConfigurationType.Current)
                  for n in nodes])
    ref = np.array([[i * C.LENGTH_M / ne, 0.0, 0.0, 1.0, 0.0, 0.0] for i in range(ne + 1)])
    coords = ref + q  # exudyn's Coordinates are displacements from the reference
    # exudyn's own strains at the Gauss points of both rules, against numpy's
    Le = C.LENGTH_M / ne
    worst = 0.0
    for rule, kind in ((GAUSS_AXIAL, "axial"), (GAUSS_BENDING, "bending")):
        xi, _ = _gauss01(rule)
        for e in range(ne):
            eps, kap = strains(coords[e], coords[e + 1], xi, Le)
            for g, x in enumerate(xi):
                lp = [x * Le, 0.0, 0.0]
                if kind == "axial":
                    ex = mbs.GetObjectOutputBody(elems[e], exu.OutputVariableType.StrainLocal, localPosition=lp)
                    worst = max(worst, abs(float(np.ravel(ex)[0]) - eps[g]))
                else:
                    ex = np.asarray(mbs.GetObjectOutputBody(elems[e], exu.OutputVariableType.CurvatureLocal,
                                                            localPosition=lp))
                    worst = max(worst, float(np.max(np.abs(ex - kap[g]))) * Le)
    return {
        "converged": ok and (conv is None or bool(conv.newtonConverged)),
        "nodes": coords,
        "exudyn_residual": float(conv.residual) if conv is not None else None,
        "strain_check_max_abs": worst,
    }


# ---------------------------------------------------------------------------
# Independent residual of softrod's model (numpy), same Gauss rules
# ---------------------------------------------------------------------------

def _hermite(xi, Le):
    s = np.array([1 - 3 * xi**2 + 2 * xi**3, Le * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3, Le * (xi**3 - xi**2)])
    d1 = np.array([(-6 * xi + 6 * xi**2) / Le, 1 - 4 * xi + 3 * xi**2, (6 * xi - 6 * xi**2) / Le, 3 * xi**2 - 2 * xi])
    d2 = np.array([(-6 + 12 * xi) / Le**2, (-4 + 6 * xi) / Le, (6 - 12 * xi) / Le**2, (6 * xi - 2) / Le])
    return s, d1, d2  # each (4, ngauss)


def _gauss01(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _element_slots(nodes):
    """(ne, 4 shape functions, 3 components) from (ne + 1, 6) nodes."""
    return np.stack([nodes[:-1, 0:3], nodes[:-1, 3:6], nodes[1:, 0:3], nodes[1:, 3:6]], axis=1)


def strains(node_a, node_b, xi, Le):
    """eps (ng,) and kappa (ng, 3) of one element at the local coordinates xi."""
    qe = _element_slots(np.array([node_a, node_b]))[0]
    _, d1, d2 = _hermite(xi, Le)
    rp = d1.T @ qe
    rpp = d2.T @ qe
    g = np.sum(rp * rp, axis=1)
    return np.sqrt(g) - 1.0, np.cross(rp, rpp) / g[:, None]


def cable_residual(nodes, loads, ea=C.EA_N, ei=C.EI_NM2):
    """Generalized-force residual grad U - Q_ext of softrod's energy at `nodes` (N, N m).

    U = 1/2 int (EA eps^2 + EI |kappa|^2) dX, 5 axial and 3 bending Gauss points.
    With a = r', b = r'', d = a.a, kappa = a x b / d:
    d(1/2 |kappa|^2)/da = ((b x kappa) - 2 |kappa|^2 a)/d, d/db = (kappa x a)/d.
    Returns the residual on the free (non-base) coordinates, shape (ne, 6).
    """
    nodes = np.asarray(nodes, dtype=float)
    ne = len(nodes) - 1
    Le = C.LENGTH_M / ne
    qe = _element_slots(nodes)
    g = np.zeros((ne, 4, 3))
    # axial
    xi, w = _gauss01(GAUSS_AXIAL)
    _, d1, _ = _hermite(xi, Le)
    rp = np.einsum("ag,eac->egc", d1, qe)
    nr = np.linalg.norm(rp, axis=2)
    g += np.einsum("eg,ag,egc->eac", ea * (nr - 1.0) * w * Le / nr, d1, rp)
    # bending
    xi, w = _gauss01(GAUSS_BENDING)
    _, d1, d2 = _hermite(xi, Le)
    rp = np.einsum("ag,eac->egc", d1, qe)
    rpp = np.einsum("ag,eac->egc", d2, qe)
    d = np.sum(rp * rp, axis=2)
    kap = np.cross(rp, rpp) / d[:, :, None]
    kk = np.sum(kap * kap, axis=2)
    ga = (np.cross(rpp, kap) - 2.0 * kk[:, :, None] * rp) / d[:, :, None]
    gb = np.cross(kap, rp) / d[:, :, None]
    c = ei * w * Le
    g += np.einsum("g,ag,egc->eac", c, d1, ga) + np.einsum("g,ag,egc->eac", c, d2, gb)
    # uniform line load: int S^T w dX = w * int s_k dX (exact with 5 points)
    xi, w5 = _gauss01(5)
    s, _, _ = _hermite(xi, Le)
    g -= np.einsum("a,c->ac", s @ (w5 * Le), _line_load(loads))[None, :, :]
    G = np.zeros((ne + 1, 6))
    G[:-1, 0:3] += g[:, 0, :]
    G[:-1, 3:6] += g[:, 1, :]
    G[1:, 0:3] += g[:, 2, :]
    G[1:, 3:6] += g[:, 3, :]
    G[-1, 0:3] -= _tip_force(loads)
    return G[1:]


def newton_correction(nodes, loads, h=1e-7):
    """One Newton step of softrod's model from `nodes` (finite-difference tangent,
    nodes three apart perturbed together): the correction dq, shape (ne, 6)."""
    from scipy.sparse import lil_matrix
    from scipy.sparse.linalg import spsolve

    nodes = np.asarray(nodes, dtype=float)
    ne = len(nodes) - 1
    n = 6 * ne
    K = lil_matrix((n, n))
    for start in range(3):
        for c in range(6):
            free = np.arange(1 + start, ne + 1, 3)
            qp = nodes.copy()
            qm = nodes.copy()
            qp[free, c] += h
            qm[free, c] -= h
            d = (cable_residual(qp, loads) - cable_residual(qm, loads)) / (2 * h)
            for k in free:
                col = 6 * (k - 1) + c
                for j in range(max(1, k - 1), min(ne, k + 1) + 1):
                    K[6 * (j - 1):6 * j, col] = d[j - 1][:, None]
    R = cable_residual(nodes, loads).ravel()
    return -spsolve(K.tocsc(), R).reshape(ne, 6)


def linear_tip_deflection(loads, ei=C.EI_NM2, L=C.LENGTH_M):
    """Euler-Bernoulli tip displacement (m) of the small cases, a 3-vector:
    P L^3/(3 EI) for a transverse tip force, q L^4/(8 EI) for a uniform load,
    per transverse component (isotropic bending); axial terms P L/EA, q L^2/(2 EA)."""
    f = _tip_force(loads)
    w = _line_load(loads)
    u = f * L**3 / (3 * ei) + w * L**4 / (8 * ei)
    u[0] = f[0] * L / C.EA_N + w[0] * L**2 / (2 * C.EA_N)
    return u


# ---------------------------------------------------------------------------
# Cases
# ---------------------------------------------------------------------------

def run_case(name, out_dir, elements=ELEMENTS):
    description, loads = CASES[name]
    large = name.endswith("_large")
    steps = LOAD_STEPS_LARGE if large else LOAD_STEPS_SMALL
    runs = []
    times = {}
    with C.Timer() as t_all:
        for ne in elements:
            with C.Timer() as t:
                r = solve(ne, loads, steps)
            nodes = r["nodes"]
            res = cable_residual(nodes, loads)
            tip = nodes[-1]
            dq = newton_correction(nodes, loads) if r["converged"] else np.full((ne, 6), np.nan)
            run = {
                "elements": ne,
                "converged": r["converged"],
                "tip_position_m": tip[0:3],
                "tip_tangent": tip[3:6] / np.linalg.norm(tip[3:6]),
                "nodes": nodes,
                "residual": {
                    "exudyn_newton_residual": r["exudyn_residual"],
                    "softrod_model_residual_max_abs": _finite(np.max(np.abs(res))),
                    "softrod_model_residual_norm2": _finite(np.linalg.norm(res)),
                    "newton_correction_tip_position_m": _finite(np.linalg.norm(dq[-1, 0:3])),
                    "newton_correction_max_abs": _finite(np.max(np.abs(dq))),
                    "strain_check_max_abs": _finite(r["strain_check_max_abs"]),
                },
            }
            runs.append(run)
            times[str(ne)] = t.elapsed
            C.log(f"  exudyn spatial {name} ne={ne:3d} ok={r['converged']} tip=({tip[0]:.10f}, {tip[1]:.10f}, "
                  f"{tip[2]:.10f}) res={run['residual']['softrod_model_residual_max_abs']:.1e} "
                  f"dtip={run['residual']['newton_correction_tip_position_m']:.1e} "
                  f"strains={r['strain_check_max_abs']:.1e} {t.elapsed:.2f}s")
    conv = [r for r in runs if r["converged"]]
    if not conv:
        raise RuntimeError(f"exudyn: no run of {name} converged")
    finest = conv[-1]
    tt = finest["tip_tangent"]
    values = {
        "tip_position_m": finest["tip_position_m"],
        "tip_angle_rad": math.acos(max(-1.0, min(1.0, tt[0]))),
        "finest_elements": finest["elements"],
        "not_converged_elements": [r["elements"] for r in runs if not r["converged"]],
        "runs": runs,
    }
    if not large:
        values["linear_theory_tip_displacement_m"] = linear_tip_deflection(loads)
    disc = {
        "element": "exudyn ObjectANCFCable (spatial ANCF cable, cubic Hermite, nodes [x, y, z, dx/dX, dy/dX, dz/dX])",
        "strains": "eps = |r'| - 1, kappa = (r' x r'') / |r'|^2 (curvature vector, isotropic bending, no torsion)",
        "gauss_points_axial": GAUSS_AXIAL,
        "gauss_points_bending": GAUSS_BENDING,
        "useReducedOrderIntegration": 0,
        "clamp": "base node: all six coordinates fixed (CoordinateConstraint to ground)",
        "distributed_load": "uniform: LoadMassProportional with massPerLength = 1 kg/m and acceleration = w "
        "(exact integral)" if np.any(_line_load(loads) != 0.0) else "none",
        "tip_force": "LoadForceVector on MarkerNodePosition of the tip node (dead load)",
        "solver": "exudyn SolveStatic, Newton, EigenSparse",
        "load_steps": steps,
        "newton_relative_tolerance": RELATIVE_TOLERANCE,
        "newton_absolute_tolerance": ABSOLUTE_TOLERANCE,
        "elements": list(elements),
        "tip_angle_note": "tip_angle_rad: angle between the tip tangent and the base tangent (+x)",
        "residual_note": "exudyn_newton_residual: exudyn's own convergence measure; softrod_model_residual_*: "
        "|grad U - Q_ext| on the free coordinates of softrod's energy (5/3 Gauss points), N and N m mixed; "
        "newton_correction_*: one Newton step of softrod's model from exudyn's nodes (m); strain_check_max_abs: "
        "max over the Gauss points of |exudyn StrainLocal - eps| and L_e |exudyn CurvatureLocal - kappa| "
        "(eps, kappa by numpy from the nodes)",
    }
    params = C.params(loads, disc)
    params["base"] = BASE
    params["gravity_m_per_s2"] = [0.0, 0.0, 0.0]
    doc = C.document(GENERATOR, f"spatial_{name}", description, params, values,
                     extra_versions=("exudyn",), timing_s={"total": t_all.elapsed, "per_run": times})
    path = os.path.join(out_dir, f"exudyn_spatial_{name}.json")
    C.write_json(path, doc)
    tip = finest["tip_position_m"]
    return [{"case": f"spatial_{name}", "generator": f"exudyn 3-D ne={finest['elements']}", "tip": tip,
             "angle": values["tip_angle_rad"], "time": t_all.elapsed, "path": path}]


def _finite(v):
    """float, or None for a run that did not converge (JSON has no NaN)."""
    v = float(v)
    return v if math.isfinite(v) else None


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
