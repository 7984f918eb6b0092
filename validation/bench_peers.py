"""softrod against its peers, timed side by side on the same problems (optional; not in CI).

Forward: exudyn's `SolveStatic` on the ANCF cable (ObjectANCFCable2D) of every
cantilever reference case (`exudyn_cantilever.py`: the same model, clamp of all
four base coordinates, 5 axial and 3 bending Gauss points, the same loads and
exudyn's settings there: Newton with EigenSparse, relative tolerance 1e-8, one
load step for the small cases and 20 for the large ones) at 4-128 elements,
against softrod's cold static solve of the same discretization in-process
(`examples/peer_times.rs`, which also checks the same tips come out).

First estimate: eq. (25) posed in CasADi and solved by IPOPT (exact Hessian
by automatic differentiation, IPOPT's default tolerance 1e-8), on the
problems `peer_times` writes: the report's references at 20 elements, 5
markers at L k / 5 with 0.01 mm seeded noise, the distributed unknown load
w(X) = S(X) F with the penalty alpha F^T B F (B = int S^T S dX), the same
alpha (the value softrod's default alpha rule, the evidence, chose), from the same start (straight
rod, F = 0). The unknowns are the free node coordinates and F; the
equality constraints are the equilibrium grad U(q) - B F = 0 on the free
coordinates, U the cable energy (axial 1/2 EA (|r'| - 1)^2 by 5 Gauss
points, bending 1/2 EI K^2, K = (r' x r'')/|r'|^2 by 3), as softrod's and
exudyn's element. softrod's time is that of a fresh estimator's first step
at the given alpha, for each backend.

Times are medians of repeated runs (exudyn: the model built outside the
timed call, the solution file off, so that only the solve is timed; its time
with the default solution file, ~3 ms more per call, is kept beside it as
`exudyn_default_settings_s` and shown in parentheses in the table; CasADi: the NLP built once, only the solver call timed). Writes
`peers.json` and `peers.png` (the ratios) into --out-dir and prints the
README table.

Setup (a separate environment; the pins are in requirements-peers.txt):
    python3 -m venv .venv-peers && .venv-peers/bin/pip install -r validation/requirements-peers.txt
    .venv-peers/bin/python validation/bench_peers.py [--out-dir validation/figures]
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

CASES = [
    "uniform_small",
    "uniform_large",
    "linear_small",
    "linear_large",
    "gaussian_small",
    "gaussian_large",
    "tip_force_small",
    "tip_force_large",
    "tip_moment_small",
    "tip_moment_large",
    "self_weight_moment_small",
    "self_weight_moment_large",
]
ELEMENTS = [4, 8, 16, 32, 64, 128]


def median_time(run, min_runs=3, budget_s=0.5, max_runs=50):
    times = []
    start = time.perf_counter()
    while len(times) < min_runs or (time.perf_counter() - start < budget_s and len(times) < max_runs):
        t = time.perf_counter()
        run()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), len(times)


# ---------------------------------------------------------------------------
# softrod
# ---------------------------------------------------------------------------

def softrod_times(path=None):
    if path:
        with open(path) as f:
            return json.load(f)
    cmd = ["cargo", "run", "--release", "--quiet", "--features", "report", "--example", "peer_times", "--", ROOT]
    out = subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


# ---------------------------------------------------------------------------
# exudyn
# ---------------------------------------------------------------------------

def exudyn_forward(cases, elements):
    """exudyn's SolveStatic, timed twice per case and size: computing only
    (`median_s`: the solution file off, `solutionSettings.writeSolutionToFile
    = False`; the ratio the table shows) and with exudyn's default of writing
    the solution file (`default_settings_s`, what the runs before 2026-11-30
    20:30 timed: the file costs exudyn ~3 ms per call, which dominated its
    small-load times)."""
    import exudyn as exu

    import common as C
    import exudyn_cantilever as X

    def settings(steps, write_file):
        s = exu.SimulationSettings()
        s.staticSolver.numberOfLoadSteps = steps
        s.staticSolver.newton.relativeTolerance = X.RELATIVE_TOLERANCE
        s.staticSolver.newton.absoluteTolerance = X.ABSOLUTE_TOLERANCE
        s.staticSolver.newton.maxIterations = 50
        s.staticSolver.verboseMode = 0
        s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        s.solutionSettings.writeSolutionToFile = write_file
        return s

    rows = []
    for case in cases:
        _, loads = C.CASES[case]
        steps = X.LOAD_STEPS_LARGE if case.endswith("_large") else X.LOAD_STEPS_SMALL
        for ne in elements:
            row = {"case": case, "elements": ne, "load_steps": steps}
            for write_file, key in ((False, "median_s"), (True, "default_settings_s")):
                s = settings(steps, write_file)
                times = []
                ok = True
                tip = None
                budget = time.perf_counter()
                while len(times) < 3 or (time.perf_counter() - budget < 0.5 and len(times) < 20):
                    _, mbs, nodes = X.build(ne, loads)  # not timed
                    t = time.perf_counter()
                    try:
                        ok = bool(mbs.SolveStatic(s)) and ok
                    except Exception:  # some exudyn versions raise on a failed solve
                        ok = False
                    times.append(time.perf_counter() - t)
                    c = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Coordinates, configuration=exu.ConfigurationType.Current)
                    tip = [C.LENGTH_M + c[0], c[1]]
                row[key] = float(np.median(times))
                if not write_file:
                    row.update({"converged": ok, "tip_m": tip, "runs": len(times)})
                    # the Newton steps and Jacobians of one more (untimed)
                    # solve, by the solver object SolveStatic wraps
                    _, mbs, _ = X.build(ne, loads)
                    solver = exu.MainSolverStatic()
                    solver.SolveSystem(mbs, s)
                    row["newton_steps"] = int(solver.it.newtonStepsCount)
                    row["jacobians"] = int(solver.it.newtonJacobiCount)
                else:
                    row["converged"] = row["converged"] and ok
            rows.append(row)
            C.log(f"exudyn {case} {ne}: {row['median_s'] * 1e3:.2f} ms (with the solution file {row['default_settings_s'] * 1e3:.2f} ms)")
    return rows


# ---------------------------------------------------------------------------
# CasADi + IPOPT: eq. (25)
# ---------------------------------------------------------------------------

def _gauss01(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _shape(xi, le):
    return np.array([1 - 3 * xi**2 + 2 * xi**3, le * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3, le * (xi**3 - xi**2)])


def _d1(xi, le):
    return np.array([(-6 * xi + 6 * xi**2) / le, 1 - 4 * xi + 3 * xi**2, (6 * xi - 6 * xi**2) / le, 3 * xi**2 - 2 * xi])


def _d2(xi, le):
    return np.array([(-6 + 12 * xi) / le**2, (-4 + 6 * xi) / le, (6 - 12 * xi) / le**2, (6 * xi - 2) / le])


def casadi_estimate(p, ipopt_options=None):
    """Eq. (25) for problem `p` of peer_times.json in CasADi/IPOPT: (time, result)."""
    import casadi as ca

    n = p["elements"]
    per = n // len(p["sections"])
    els = []
    for s in p["sections"]:
        els += [(s["length_m"] / per, s["ea_n"], s["ei_nm2"])] * per
    nq = 4 * (n + 1)
    u = ca.SX.sym("u", 4 * n)
    F = ca.SX.sym("F", nq)
    q = ca.vertcat(ca.DM([0.0, 0.0, 1.0, 0.0]), u)  # clamp: base at the origin along x
    xa, wa = _gauss01(p["axial_gauss_points"])
    xb, wb = _gauss01(p["bending_gauss_points"])
    energy = 0
    B = np.zeros((nq, nq))
    xg, wg = _gauss01(5)
    for e, (le, ea, ei) in enumerate(els):
        slots = [q[4 * e : 4 * e + 2], q[4 * e + 2 : 4 * e + 4], q[4 * e + 4 : 4 * e + 6], q[4 * e + 6 : 4 * e + 8]]
        for xi, w in zip(xa, wa):
            d = _d1(xi, le)
            rp = sum(d[a] * slots[a] for a in range(4))
            eps = ca.sqrt(rp[0] ** 2 + rp[1] ** 2) - 1.0
            energy += 0.5 * ea * eps**2 * w * le
        for xi, w in zip(xb, wb):
            d, dd = _d1(xi, le), _d2(xi, le)
            rp = sum(d[a] * slots[a] for a in range(4))
            rpp = sum(dd[a] * slots[a] for a in range(4))
            kappa = (rp[0] * rpp[1] - rp[1] * rpp[0]) / (rp[0] ** 2 + rp[1] ** 2)
            energy += 0.5 * ei * kappa**2 * w * le
        # the load Gram matrix B = int S^T S dX (exact: degree 6, 5 points)
        idx = [4 * e, 4 * e + 2, 4 * e + 4, 4 * e + 6]
        for xi, w in zip(xg, wg):
            s = _shape(xi, le)
            for a in range(4):
                for b in range(4):
                    for c in range(2):
                        B[idx[a] + c, idx[b] + c] += s[a] * s[b] * w * le
    # markers: r(s) = S(s) q
    total = sum(le for le, _, _ in els)
    sigma = p["noise_sigma_m"]
    misfit = 0
    for m in p["markers"]:
        s_m = m["s_m"]
        e = min(int(s_m / els[0][0]), n - 1)
        le = els[e][0]
        xi = (s_m - e * le) / le
        sh = _shape(xi, le)
        r = sh[0] * q[4 * e : 4 * e + 2] + sh[1] * q[4 * e + 2 : 4 * e + 4] + sh[2] * q[4 * e + 4 : 4 * e + 6] + sh[3] * q[4 * e + 6 : 4 * e + 8]
        y = np.array(m["position_m"])
        misfit += ((r[0] - y[0]) ** 2 + (r[1] - y[1]) ** 2) / sigma**2
    Bs = ca.DM(B)
    penalty = p["alpha"] * ca.dot(F, ca.mtimes(Bs, F))
    grad_u = ca.gradient(energy, u)
    g = grad_u - ca.mtimes(Bs, F)[4:]
    x = ca.vertcat(u, F)
    opts = {"print_time": 0, "ipopt.print_level": 0, "ipopt.sb": "yes"}
    opts.update(ipopt_options or {})
    solver = ca.nlpsol("est", "ipopt", {"x": x, "f": misfit + penalty, "g": g}, opts)
    le0 = els[0][0]
    u0 = np.concatenate([[i * le0, 0.0, 1.0, 0.0] for i in range(1, n + 1)])
    x0 = np.concatenate([u0, np.zeros(nq)])
    out = {}

    def run():
        out["sol"] = solver(x0=x0, lbg=0.0, ubg=0.0)

    t, runs = median_time(run, min_runs=3, budget_s=1.0, max_runs=20)
    sol = out["sol"]
    stats = solver.stats()
    xs = np.array(sol["x"]).ravel()
    f_est = xs[4 * n :]
    return t, {
        "median_s": t,
        "runs": runs,
        "success": bool(stats.get("success", False)),
        "return_status": stats.get("return_status"),
        "iterations": int(stats.get("iter_count", -1)),
        "objective": float(sol["f"]),
        "f": f_est.tolist(),
        "length_m": total,
    }


# ---------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------

def chart(doc, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for case in CASES:
        rows = [r for r in doc["forward"] if r["case"] == case and r.get("ratio")]
        if rows:
            a1.plot([r["elements"] for r in rows], [r["ratio"] for r in rows], marker="o", label=case)
    a1.axhline(30, color="k", ls="--", lw=1, label="target 30x")
    a1.set_xscale("log", base=2)
    a1.set_yscale("log")
    a1.set_xlabel("elements")
    a1.set_ylabel("exudyn SolveStatic time (no solution file) / softrod cold solve time")
    a1.set_title("forward static solve")
    a1.legend(fontsize=6, ncol=2)
    labels, vals, cols = [], [], []
    for p in doc["estimate"]:
        for b, col in (("newton", "C0"), ("sqp", "C1")):
            r = p["ratios"].get(b)
            if r:
                labels.append(f"{p['reference'].replace('exudyn_', '')}\n{b}")
                vals.append(r)
                cols.append(col)
    a2.bar(range(len(vals)), vals, color=cols)
    a2.axhline(10, color="k", ls="--", lw=1, label="target 10x")
    a2.set_xticks(range(len(vals)))
    a2.set_xticklabels(labels, fontsize=6)
    a2.set_yscale("log")
    a2.set_ylabel("CasADi/IPOPT time / softrod time")
    a2.set_title("first estimate, eq. (25), 20 elements, 5 markers")
    a2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def grid(doc, key, cell):
    """A case x elements table of `cell(row)` over the forward rows that have `key`."""
    lines = ["| case | " + " | ".join(f"{n} el" for n in ELEMENTS) + " |", "|---|" + "---|" * len(ELEMENTS)]
    for case in CASES:
        cells = []
        for n in ELEMENTS:
            r = next((r for r in doc["forward"] if r["case"] == case and r["elements"] == n), None)
            cells.append(cell(r) if r is not None and r.get(key) else "")
        lines.append(f"| {case} | " + " | ".join(cells) + " |")
    return lines


def table(doc):
    lines = grid(
        doc,
        "ratio",
        lambda r: f"{r['ratio']:.0f}x ({r['ratio_default_settings']:.0f}x)" + ("" if r["converged_both"] else " (!)"),
    )
    lines += ["", "Newton iterations, exudyn / softrod, and the time ratio per iteration:", ""]
    lines += grid(
        doc,
        "ratio_per_iteration",
        lambda r: f"{r['exudyn_newton_steps']} / {r['softrod_newton_iterations']}: {r['ratio_per_iteration']:.0f}x",
    )
    lines.append("")
    lines.append("| first estimate (20 el, 5 markers) | alpha | CasADi/IPOPT | softrod newton | softrod sqp | ratio newton | ratio sqp | max rel. diff of F (newton) |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for p in doc["estimate"]:
        c = p["casadi"]
        nw, sq = p["backends"]["newton"], p["backends"]["sqp"]
        lines.append(
            f"| {p['reference']} | {p['alpha']:.3g} | {c['median_s'] * 1e3:.1f} ms ({c['iterations']} it, {c['return_status']}) | "
            f"{nw['median_s'] * 1e3:.2f} ms | {sq['median_s'] * 1e3:.2f} ms | {p['ratios']['newton']:.0f}x | {p['ratios']['sqp']:.0f}x | {p['f_rel_diff_newton']:.1e} |"
        )
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out-dir", default=os.path.join(HERE, "figures"))
    ap.add_argument("--softrod-json", help="peer_times output to use instead of running cargo")
    ap.add_argument("--case", nargs="*", default=CASES)
    ap.add_argument("--elements", nargs="*", type=int, default=ELEMENTS)
    ap.add_argument("--skip-casadi", action="store_true")
    args = ap.parse_args(argv)

    import common as C

    soft = softrod_times(args.softrod_json)
    ex = exudyn_forward(args.case, args.elements)
    forward = []
    for r in ex:
        s = next((s for s in soft["forward"] if s["case"] == r["case"] and s["elements"] == r["elements"]), None)
        if s is None:
            continue
        tip_diff = float(np.hypot(*(np.array(s["tip_m"]) - np.array(r["tip_m"])))) if s["tip_m"] and r["tip_m"] else None
        forward.append(
            {
                **{k: r[k] for k in ("case", "elements", "load_steps")},
                "exudyn_s": r["median_s"],
                "exudyn_default_settings_s": r["default_settings_s"],
                "softrod_s": s["median_s"],
                "softrod_newton_iterations": s["newton_iterations"],
                "exudyn_newton_steps": r["newton_steps"],
                "exudyn_jacobians": r["jacobians"],
                # time per Newton iteration, exudyn's over softrod's: what the
                # ratio would be at equal iteration counts
                "ratio_per_iteration": (r["median_s"] / max(r["newton_steps"], 1))
                / (s["median_s"] / max(s["newton_iterations"], 1)),
                "ratio": r["median_s"] / s["median_s"],
                "ratio_default_settings": r["default_settings_s"] / s["median_s"],
                "converged_both": bool(r["converged"] and s["converged"]),
                "tip_difference_m": tip_diff,
            }
        )
    estimates = []
    for p in soft["estimate"]:
        entry = {k: p[k] for k in ("reference", "elements", "alpha", "noise_sigma_m", "markers", "backends")}
        for b in entry["backends"].values():
            b.pop("q", None)
        if args.skip_casadi:
            entry["casadi"] = None
            entry["ratios"] = {}
        else:
            _, c = casadi_estimate(p)
            f_nw = np.array(p["backends"]["newton"]["f"])
            entry["casadi"] = c
            entry["f_rel_diff_newton"] = float(np.linalg.norm(np.array(c["f"]) - f_nw) / max(np.linalg.norm(f_nw), 1e-300))
            entry["ratios"] = {b: c["median_s"] / p["backends"][b]["median_s"] for b in ("newton", "sqp")}
            C.log(f"casadi {p['reference']}: {c['median_s'] * 1e3:.1f} ms, {c['iterations']} it; ratios {entry['ratios']}")
        for b in entry["backends"].values():
            b.pop("f", None)
        if entry["casadi"]:
            entry["casadi"].pop("f", None)
        estimates.append(entry)
    extra = ["exudyn", "casadi"] if not args.skip_casadi else ["exudyn"]
    doc = {
        "generator": "validation/bench_peers.py",
        "versions": C.versions(extra),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "load_average": list(os.getloadavg())},
        "note": "medians of repeated runs; compare ratios (one run, one machine), not absolute times",
        "forward": forward,
        "estimate": estimates,
    }
    os.makedirs(args.out_dir, exist_ok=True)
    C.write_json(os.path.join(args.out_dir, "peers.json"), doc)
    if not args.skip_casadi:
        chart(doc, os.path.join(args.out_dir, "peers.png"))
    print(table(doc) if not args.skip_casadi else json.dumps(forward, indent=1))


if __name__ == "__main__":
    main()
