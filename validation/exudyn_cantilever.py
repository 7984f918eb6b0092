"""Cantilever references from exudyn's ANCF cable (ObjectANCFCable2D), static solves.

Model (same as softrod's planar cable): nodes NodePoint2DSlope1 with
coordinates [x, y, dx/dX, dy/dX], cubic Hermite interpolation, axial strain
eps = |r'| - 1, material curvature K = ((r' x r'') . e3) / |r'|^2,
delta W_e = int (EA eps delta eps + EI K delta K) dX. exudyn integrates the
axial term with 5 Gauss points (order 9) and the bending term with 3 (order 5)
when `useReducedOrderIntegration = 0` (the default, used here).

Boundary: all four coordinates of the base node fixed (r_0 = 0, r_0' = (1, 0)),
as softrod's clamp, by CoordinateConstraint to a NodePointGround.

Loads:
- tip force: LoadForceVector on a MarkerNodePosition of the tip node (dead load);
- tip moment: LoadTorqueVector [0, 0, M] on a MarkerBodyRigid of the last element
  at local position [Le, 0, 0]. exudyn's rotation Jacobian of the cable is
  d omega_z / dq = (r'_x S'_i e_y - r'_y S'_i e_x) / |r'|^2 = d atan2(r'_y, r'_x)/dq,
  so the torque does the virtual work M delta theta, theta = atan2(r'_y, r'_x) at the
  tip: the same work-conjugate angle as softrod's tip moment (W = M theta);
- uniform line load and self-weight: LoadMassProportional on a MarkerBodyMass of every
  element (uniform load q: massPerLength = 1 kg/m and the "acceleration" [0, -q, 0]);
- non-uniform line loads (linear, Gaussian): point forces w(X_g) * w_g * Le/2 at the
  5 Gauss-Legendre points X_g of every element (LoadForceVector on MarkerBodyPosition
  with localPosition [x_g, 0, 0]). Exact for the linear profile (degree 1 x cubic).

Solver: mbs.SolveStatic, Newton with the EigenSparse linear solver, load steps
(one for the small loads, 20 for the large ones), relative tolerance 1e-8
(1e-10 fails at 64 and 128 elements for the large tip force: the Newton stalls on
round-off). The achieved residual is recorded
twice: exudyn's own (`conv.residual`), and independently as the norm of the
generalized-force imbalance of softrod's energy (`softrod_model_residual`),
evaluated by `cable_residual` below with the same Gauss rules; that second
number also checks that exudyn's element is the model softrod implements.

Run: `python validation/exudyn_cantilever.py [--out-dir reference] [--case NAME ...]`.
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
    LoadTorqueVector,
    MarkerBodyMass,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    NodePoint2DSlope1,
    NodePointGround,
    ObjectANCFCable2D,
)

GENERATOR = "validation/exudyn_cantilever.py"
ELEMENTS = [2, 4, 8, 16, 32, 64, 128]
RELATIVE_TOLERANCE = 1e-8
ABSOLUTE_TOLERANCE = 1e-10
LOAD_GAUSS_POINTS = 5
LOAD_STEPS_SMALL = 1
LOAD_STEPS_LARGE = 20


# ---------------------------------------------------------------------------
# exudyn model
# ---------------------------------------------------------------------------

def build(ne, loads):
    """Build the exudyn system; return (SC, mbs, node indices)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    L = C.LENGTH_M
    Le = L / ne
    sw = C.self_weight(loads)
    uniform = [ld for ld in loads if ld["type"] == "distributed" and ld["profile"] == "uniform"]
    if sw is not None and uniform:
        raise ValueError("a uniform load together with self-weight is not supported")
    rho_a = sw[0] if sw is not None else (1.0 if uniform else 0.0)
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * Le, 0.0, 1.0, 0.0])) for i in range(ne + 1)]
    elems = [
        mbs.AddObject(
            ObjectANCFCable2D(
                length=Le,
                massPerLength=rho_a,
                bendingStiffness=C.EI_NM2,
                axialStiffness=C.EA_N,
                nodeNumbers=[nodes[i], nodes[i + 1]],
                useReducedOrderIntegration=0,
            )
        )
        for i in range(ne)
    ]
    # clamp: all four coordinates of the base node
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in range(4):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc]))
    # loads
    if sw is not None or uniform:
        acc = [sw[1][0], sw[1][1], 0.0] if sw is not None else [uniform[0]["w_n_per_m"][0], uniform[0]["w_n_per_m"][1], 0.0]
        for e in elems:
            mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=e))
            mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=acc))
    nonuniform = [ld for ld in loads if ld["type"] == "distributed" and ld["profile"] != "uniform"]
    if nonuniform:
        xg, wg = np.polynomial.legendre.leggauss(LOAD_GAUSS_POINTS)
        for i, e in enumerate(elems):
            for x, w in zip(xg, wg):
                xl = 0.5 * Le * (x + 1.0)
                wx, wy = C.line_load(nonuniform, i * Le + xl)
                f = 0.5 * Le * w
                mp = mbs.AddMarker(MarkerBodyPosition(bodyNumber=e, localPosition=[xl, 0.0, 0.0]))
                mbs.AddLoad(LoadForceVector(markerNumber=mp, loadVector=[f * wx, f * wy, 0.0]))
    fx, fy = C.tip_force(loads)
    if fx != 0.0 or fy != 0.0:
        mt = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
        mbs.AddLoad(LoadForceVector(markerNumber=mt, loadVector=[fx, fy, 0.0]))
    M = C.tip_moment(loads)
    if M != 0.0:
        mr = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[-1], localPosition=[Le, 0.0, 0.0]))
        mbs.AddLoad(LoadTorqueVector(markerNumber=mr, loadVector=[0.0, 0.0, M]))
    mbs.Assemble()
    return SC, mbs, nodes


def solve(ne, loads, load_steps, rel_tol=RELATIVE_TOLERANCE):
    SC, mbs, nodes = build(ne, loads)
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = load_steps
    s.staticSolver.newton.relativeTolerance = rel_tol
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
    q = np.array(
        [mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates, configuration=exu.ConfigurationType.Current) for n in nodes]
    )
    ref = np.array([[i * C.LENGTH_M / ne, 0.0, 1.0, 0.0] for i in range(ne + 1)])
    coords = ref + q  # exudyn's Coordinates are displacements from the reference
    return {
        "converged": ok and (conv is None or bool(conv.newtonConverged)),
        "nodes": coords,
        "exudyn_residual": float(conv.residual) if conv is not None else None,
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


def cable_residual(nodes, loads, ea=C.EA_N, ei=C.EI_NM2, n_axial=5, n_bend=3, n_load=LOAD_GAUSS_POINTS):
    """Generalized-force residual grad U - Q_ext of softrod's energy at `nodes` (N, N m).

    Returns the residual on the free (non-base) coordinates, shape (ne, 4).
    """
    nodes = np.asarray(nodes, dtype=float)
    ne = len(nodes) - 1
    Le = C.LENGTH_M / ne
    # element coordinates: (ne, 4 shape fns, 2 comps)
    qe = np.stack([nodes[:-1, 0:2], nodes[:-1, 2:4], nodes[1:, 0:2], nodes[1:, 2:4]], axis=1)
    g = np.zeros((ne, 4, 2))
    # axial
    xi, w = _gauss01(n_axial)
    _, d1, d2 = _hermite(xi, Le)
    rp = np.einsum("ag,eac->egc", d1, qe)
    nr = np.linalg.norm(rp, axis=2)
    eps = nr - 1.0
    g += np.einsum("eg,ag,egc->eac", ea * eps * w * Le / nr, d1, rp)
    # bending
    xi, w = _gauss01(n_bend)
    _, d1, d2 = _hermite(xi, Le)
    rp = np.einsum("ag,eac->egc", d1, qe)
    rpp = np.einsum("ag,eac->egc", d2, qe)
    gg = np.sum(rp * rp, axis=2)
    cr = rp[:, :, 0] * rpp[:, :, 1] - rp[:, :, 1] * rpp[:, :, 0]
    kap = cr / gg
    coef = ei * kap * w * Le  # (e, g)
    dk_x = (np.einsum("ag,eg->eag", d1, rpp[:, :, 1]) - np.einsum("ag,eg->eag", d2, rp[:, :, 1])) / gg[:, None, :] - 2 * np.einsum(
        "ag,eg->eag", d1, cr * rp[:, :, 0]
    ) / (gg**2)[:, None, :]
    dk_y = (-np.einsum("ag,eg->eag", d1, rpp[:, :, 0]) + np.einsum("ag,eg->eag", d2, rp[:, :, 0])) / gg[:, None, :] - 2 * np.einsum(
        "ag,eg->eag", d1, cr * rp[:, :, 1]
    ) / (gg**2)[:, None, :]
    g[:, :, 0] += np.einsum("eg,eag->ea", coef, dk_x)
    g[:, :, 1] += np.einsum("eg,eag->ea", coef, dk_y)
    # line loads (uniform, linear, Gaussian, self-weight) by an n_load-point rule
    xi, w = _gauss01(n_load)
    s, _, _ = _hermite(xi, Le)
    X = (np.arange(ne)[:, None] + xi[None, :]) * Le
    wx, wy = C.line_load(loads, X)
    wx = np.broadcast_to(wx, X.shape)
    wy = np.broadcast_to(wy, X.shape)
    g[:, :, 0] -= np.einsum("ag,eg->ea", s * w * Le, wx)
    g[:, :, 1] -= np.einsum("ag,eg->ea", s * w * Le, wy)
    # assemble to nodes
    G = np.zeros((ne + 1, 4))
    G[:-1, 0:2] += g[:, 0, :]
    G[:-1, 2:4] += g[:, 1, :]
    G[1:, 0:2] += g[:, 2, :]
    G[1:, 2:4] += g[:, 3, :]
    # tip loads
    fx, fy = C.tip_force(loads)
    G[-1, 0] -= fx
    G[-1, 1] -= fy
    M = C.tip_moment(loads)
    tx, ty = nodes[-1, 2], nodes[-1, 3]
    G[-1, 2] -= M * (-ty) / (tx * tx + ty * ty)
    G[-1, 3] -= M * tx / (tx * tx + ty * ty)
    return G[1:]


def newton_correction(nodes, loads, h=1e-7):
    """One Newton step of softrod's model from `nodes`: returns the correction dq (ne, 4).

    The tangent is a central finite difference of `cable_residual`, built with a
    colouring of the banded structure (free nodes three apart never share an
    element), so it costs 2 x 12 residual evaluations. |dq| estimates how far
    exudyn's converged nodes are from the exact discrete equilibrium.
    """
    from scipy.sparse import lil_matrix
    from scipy.sparse.linalg import spsolve

    nodes = np.asarray(nodes, dtype=float)
    ne = len(nodes) - 1
    n = 4 * ne
    K = lil_matrix((n, n))
    for start in range(3):
        for c in range(4):
            free = np.arange(1 + start, ne + 1, 3)  # node indices perturbed together
            qp = nodes.copy()
            qm = nodes.copy()
            qp[free, c] += h
            qm[free, c] -= h
            d = (cable_residual(qp, loads) - cable_residual(qm, loads)) / (2 * h)  # (ne, 4)
            for k in free:
                col = 4 * (k - 1) + c
                for j in range(max(1, k - 1), min(ne, k + 1) + 1):
                    K[4 * (j - 1):4 * j, col] = d[j - 1][:, None]
    R = cable_residual(nodes, loads).ravel()
    return -spsolve(K.tocsc(), R).reshape(ne, 4)


# ---------------------------------------------------------------------------
# Cases
# ---------------------------------------------------------------------------

def run_case(name, out_dir, elements=ELEMENTS):
    description, loads = C.CASES[name]
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
            dq = newton_correction(nodes, loads) if r["converged"] else np.full((ne, 4), np.nan)
            run = {
                "elements": ne,
                "converged": r["converged"],
                "tip_position_m": [tip[0], tip[1]],
                "tip_angle_rad": math.atan2(tip[3], tip[2]),
                "nodes": nodes,
                "residual": {
                    "exudyn_newton_residual": r["exudyn_residual"],
                    "softrod_model_residual_max_abs": _finite(np.max(np.abs(res))),
                    "softrod_model_residual_norm2": _finite(np.linalg.norm(res)),
                    "newton_correction_tip_position_m": _finite(np.linalg.norm(dq[-1, 0:2])),
                    "newton_correction_max_abs": _finite(np.max(np.abs(dq))),
                },
            }
            runs.append(run)
            times[str(ne)] = t.elapsed
            C.log(f"  exudyn {name} ne={ne:4d} ok={r['converged']} tip=({tip[0]:.12f}, {tip[1]:.12f}) "
                  f"res={run['residual']['softrod_model_residual_max_abs']:.2e} "
                  f"dtip={run['residual']['newton_correction_tip_position_m']:.1e} {t.elapsed:.2f}s")
    conv = [r for r in runs if r["converged"]]
    if not conv:
        raise RuntimeError(f"exudyn: no run of {name} converged")
    finest = conv[-1]
    values = {
        "tip_position_m": finest["tip_position_m"],
        "tip_angle_rad": finest["tip_angle_rad"],
        "finest_elements": finest["elements"],
        "not_converged_elements": [r["elements"] for r in runs if not r["converged"]],
        "runs": runs,
    }
    if name.endswith("_small"):
        values["linear_theory_tip_deflection_m"] = C.linear_tip_deflection(loads)
    disc = {
        "element": "exudyn ObjectANCFCable2D (planar ANCF cable, cubic Hermite, nodes [x, y, dx/dX, dy/dX])",
        "strains": "eps = |r'| - 1, kappa = (r' x r'')_z / |r'|^2 (material curvature)",
        "gauss_points_axial": 5,
        "gauss_points_bending": 3,
        "useReducedOrderIntegration": 0,
        "clamp": "base node: all four coordinates fixed (CoordinateConstraint to ground)",
        "distributed_load": _load_note(loads),
        "tip_moment": "LoadTorqueVector on MarkerBodyRigid at the tip (local [Le, 0, 0]); work-conjugate to atan2(r'_y, r'_x)",
        "tip_force": "LoadForceVector on MarkerNodePosition of the tip node (dead load)",
        "solver": "exudyn SolveStatic, Newton, EigenSparse",
        "load_steps": steps,
        "newton_relative_tolerance": RELATIVE_TOLERANCE,
        "newton_absolute_tolerance": ABSOLUTE_TOLERANCE,
        "elements": list(elements),
        "residual_note": "exudyn_newton_residual: exudyn's own convergence measure; softrod_model_residual_*: "
        "|grad U - Q_ext| on the free coordinates of softrod's energy (5/3 Gauss points), N and N m mixed; "
        "newton_correction_*: size of one Newton step of softrod's model from exudyn's nodes (finite-difference "
        "tangent), an estimate of exudyn's distance from the exact discrete equilibrium (m)",
    }
    doc = C.document(GENERATOR, name, description, C.params(loads, disc), values,
                     extra_versions=("exudyn",), timing_s={"total": t_all.elapsed, "per_run": times})
    path = os.path.join(out_dir, f"exudyn_{name}.json")
    C.write_json(path, doc)
    return [{"case": name, "generator": f"exudyn ne={finest['elements']}", "tip": finest["tip_position_m"],
             "angle": finest["tip_angle_rad"], "time": t_all.elapsed, "path": path}]


def _finite(v):
    """float, or None for a run that did not converge (JSON has no NaN)."""
    v = float(v)
    return v if math.isfinite(v) else None


def _load_note(loads):
    kinds = {ld.get("profile") for ld in loads if ld["type"] == "distributed"}
    notes = []
    if "uniform" in kinds:
        notes.append("uniform: LoadMassProportional with massPerLength = 1 kg/m and acceleration = w (exact integral)")
    if any(ld["type"] == "self_weight" for ld in loads):
        notes.append("self-weight: LoadMassProportional (massPerLength, gravity) (exact integral)")
    if kinds & {"linear", "gaussian"}:
        notes.append(f"non-uniform: point forces w(X_g) w_g Le/2 at the {LOAD_GAUSS_POINTS} Gauss-Legendre points of "
                     "every element (LoadForceVector on MarkerBodyPosition at local [x_g, 0, 0])")
    return "; ".join(notes) if notes else "none"


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
