"""Chart the reference solutions: deflected shapes per case, exudyn convergence.

Reads reference/*.json and writes, into validation/figures/ (PNG and SVG):
- shape_<case>.{png,svg}: the elastica (extensible), exudyn's ANCF cable at the
  finest and at 2 and 4 elements (Hermite-interpolated between the nodes), and the
  scikit-fem strips' centerlines (slender, and the thick one for charting).
  Large cases are drawn as x-y shapes at equal scale; small cases as the
  deflection y(X) in mm against the undeformed arc coordinate X.
- shapes_overview.{png,svg}: all cases in one grid.
- exudyn_convergence.{png,svg}: |tip_exudyn - tip_elastica| against the element count.

Run: `python validation/plot_references.py [--ref-dir reference] [--out-dir validation/figures]`.
"""

import argparse
import glob
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import common as C  # noqa: E402

SVG_META = {"Date": None}  # reproducible SVGs
PNG_META = {"Software": None}


def load(ref_dir):
    out = {}
    for p in sorted(glob.glob(os.path.join(ref_dir, "*.json"))):
        with open(p) as f:
            out[os.path.basename(p)[:-5]] = json.load(f)
    return out


def hermite_curve(nodes, per_element=16):
    """Sample the cubic Hermite interpolant of ANCF nodes [x, y, x', y']: returns X, x, y."""
    nodes = np.asarray(nodes)
    ne = len(nodes) - 1
    Le = C.LENGTH_M / ne
    xi = np.linspace(0.0, 1.0, per_element + 1)
    s = np.array([1 - 3 * xi**2 + 2 * xi**3, Le * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3, Le * (xi**3 - xi**2)])
    Xs, xs, ys = [], [], []
    for e in range(ne):
        a, b = nodes[e], nodes[e + 1]
        q = np.array([a[0:2], a[2:4], b[0:2], b[2:4]])  # (4, 2)
        r = s.T @ q
        start = 0 if e == 0 else 1
        Xs.append((e + xi[start:]) * Le)
        xs.append(r[start:, 0])
        ys.append(r[start:, 1])
    return np.concatenate(Xs), np.concatenate(xs), np.concatenate(ys)


def draw_case(ax, refs, case):
    small = case.endswith("_small")
    el = refs.get(f"elastica_{case}")
    ex = refs.get(f"exudyn_{case}")

    def put(X, x, y, **kw):
        if small:
            ax.plot(np.asarray(X), 1e3 * np.asarray(y), **kw)
        else:
            ax.plot(x, y, **kw)

    if el is not None:
        sh = el["values"]["shape"]
        put(sh["X_m"], sh["x_m"], sh["y_m"], color="black", lw=2.2, label="elastica (extensible)")
    if ex is not None:
        runs = {r["elements"]: r for r in ex["values"]["runs"] if r["converged"]}
        for ne, style in ((2, dict(color="tab:red", ls=":", lw=1.2)), (4, dict(color="tab:orange", ls="--", lw=1.2))):
            if ne in runs:
                X, x, y = hermite_curve(runs[ne]["nodes"])
                put(X, x, y, label=f"exudyn ANCF, {ne} el.", **style)
        fin = runs[ex["values"]["finest_elements"]]
        nodes = np.asarray(fin["nodes"])
        idx = np.linspace(0, len(nodes) - 1, 17).astype(int)
        Xn = np.linspace(0.0, C.LENGTH_M, len(nodes))[idx]
        put(Xn, nodes[idx, 0], nodes[idx, 1], color="tab:blue", ls="none", marker="o", ms=4,
            label=f"exudyn ANCF, {fin['elements']} el. (nodes)")
    for strip, style in (("slender", dict(color="tab:green", ls="-.", lw=1.2)), ("thick", dict(color="tab:purple", ls="-.", lw=1.0))):
        sk = refs.get(f"skfem_{strip}_{case}")
        if sk is not None:
            cl = sk["values"]["centerline"]
            put(cl["X_m"], cl["x_m"], cl["y_m"], label=f"scikit-fem {strip} strip", **style)
    ax.set_title(case.replace("_", " "), fontsize=10)
    if small:
        ax.set_xlabel("X [m]")
        ax.set_ylabel("y [mm]")
    else:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)


def save(fig, out_dir, stem):
    fig.savefig(os.path.join(out_dir, stem + ".png"), dpi=120, metadata=PNG_META)
    fig.savefig(os.path.join(out_dir, stem + ".svg"), metadata=SVG_META)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref-dir", default=os.path.join(HERE, "..", "reference"))
    ap.add_argument("--out-dir", default=os.path.join(HERE, "figures"))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    plt.rcParams["svg.hashsalt"] = "softrod"  # deterministic SVG ids
    refs = load(a.ref_dir)
    cases = [c for c in C.CASES if any(k.endswith(c) for k in refs)]
    written = []
    for case in cases:
        fig, ax = plt.subplots(figsize=(6.4, 4.8))
        draw_case(ax, refs, case)
        ax.legend(fontsize=8)
        fig.suptitle(C.CASES[case][0], fontsize=8)
        fig.tight_layout()
        save(fig, a.out_dir, f"shape_{case}")
        written.append(f"shape_{case}")
    # overview
    n = len(cases)
    cols = 4
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.4 * rows))
    for ax, case in zip(np.ravel(axes), cases):
        draw_case(ax, refs, case)
    for ax in np.ravel(axes)[n:]:
        ax.axis("off")
    handles, labels = np.ravel(axes)[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    save(fig, a.out_dir, "shapes_overview")
    written.append("shapes_overview")
    # exudyn convergence
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for case in C.CASES:
        ex, el = refs.get(f"exudyn_{case}"), refs.get(f"elastica_{case}")
        if ex is None or el is None:
            continue
        runs = [r for r in ex["values"]["runs"] if r["converged"]]
        ne = [r["elements"] for r in runs]
        err = [max(math.dist(r["tip_position_m"], el["values"]["tip_position_m"]), 1e-17) for r in runs]
        ax.loglog(ne, err, marker="o", ms=3, ls="-" if case.endswith("_large") else "--", label=case,
                  color=plt.cm.tab20(list(C.CASES).index(case) % 20))
    ax.set_xlabel("elements")
    ax.set_ylabel("|tip exudyn - tip elastica| [m]")
    ax.set_title("exudyn ANCF cable vs extensible elastica")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    save(fig, a.out_dir, "exudyn_convergence")
    written.append("exudyn_convergence")
    print(f"wrote {len(written)} figures (PNG + SVG) to {os.path.abspath(a.out_dir)}")


if __name__ == "__main__":
    main()
