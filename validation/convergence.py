"""Convergence study: softrod and exudyn tip error against the element count.

For every case of `common.CASES` and n = 2, 4, ..., 128 elements (n/2 in each of
the reference's two sections) this script writes a softrod scene, runs the
softrod CLI (`softrod solve SCENE --out FILE`) in two configurations

  (a) softrod defaults: 5 Gauss points for the axial and 5 for the bending
      integral, clamp `position_and_direction` (base stretch free);
  (b) exudyn-equivalent: 5 axial / 3 bending Gauss points, clamp `full`
      (all four base coordinates fixed, as in `exudyn_cantilever.py`);

and, to tell the two changes apart, (c) 5/5 with clamp `full` and (d) 5/3 with
clamp `position_and_direction` (in the JSON and the README table, not charted);

and measures the tip error |tip - tip_elastica| against the extensible elastica
(`reference/elastica_<case>.json`, the continuum limit of the same rod model).
exudyn's error is taken from its runs in `reference/exudyn_<case>.json`.

Writes, into validation/figures/ (or --out-dir):
- convergence.{png,svg}: one log-log panel per case, softrod (a), softrod (b)
  and exudyn on the same axes, with an O(h^4) guide line;
- convergence.json: every error, the softrod (b) - exudyn tip distance, the
  solver reports and the observed orders.
With --update-readme it also rewrites the observed-order table in
validation/README.md (between the `convergence-table` markers).

Observed order: least-squares slope of log(error) against log(h) (h = L/n)
over the asymptotic range, chosen per series by three rules:
1. the floor: a point is at the floor, and so is every finer point of the
   series, if its error is below ROUNDOFF_M (1e-13 m, round-off of a 0.24 m
   coordinate after a banded solve), or if it is less than FLATTEN_FACTOR (4)
   times smaller than the error at half as many elements (local order below 2:
   the series has flattened onto the Newton stopping error), or, for exudyn, if
   its own estimate of that error (`newton_correction_tip_position_m`) exceeds
   10 % of the error;
2. pre-asymptotic points are dropped: n >= FIT_FROM[case], 4 (n = 2 is one
   element per section) except 16 for the Gaussian bump (1 cm wide: from 2 to
   8 elements the error is that of the 5-point load rule resolving the bump,
   falling 10 to 1000 times per halving);
3. of what remains, the MAX_FIT_POINTS (3: two halvings) finest points are
   fitted. With 2 points the order is a two-point estimate (flagged), with
   fewer there is none.

Run: `validation/.venv/bin/python validation/convergence.py [--update-readme]`
(builds softrod with `cargo build --release` if target/release/softrod is missing).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import common as C  # noqa: E402

ELEMENTS = [2, 4, 8, 16, 32, 64, 128]
ROUNDOFF_M = 1e-13  # below this a tip error is round-off
FLATTEN_FACTOR = 4.0  # error must fall by at least this per halving of h (local order >= 2)
EXUDYN_CORRECTION_SHARE = 0.1  # exudyn points whose Newton-correction estimate exceeds this share are at the floor
FIT_FROM = {case: (16 if case.startswith("gaussian") else 4) for case in C.CASES}
MAX_FIT_POINTS = 3

CONFIGS = {
    "softrod_a": {
        "label": "softrod (a) defaults: 5/5 Gauss, clamp position_and_direction",
        "short": "softrod (a): 5/5 Gauss, base stretch free",
        "bending_gauss_points": 5,
        "clamp": "position_and_direction",
    },
    "softrod_b": {
        "label": "softrod (b) exudyn-equivalent: 5/3 Gauss, clamp full",
        "short": "softrod (b): 5/3 Gauss, clamp full",
        "bending_gauss_points": 3,
        "clamp": "full",
    },
    # diagnostics (JSON and README table, not charted): which of the two changes matters
    "softrod_c": {
        "label": "softrod (c): 5/5 Gauss, clamp full",
        "short": "softrod (c): 5/5 Gauss, clamp full",
        "bending_gauss_points": 5,
        "clamp": "full",
    },
    "softrod_d": {
        "label": "softrod (d): 5/3 Gauss, clamp position_and_direction",
        "short": "softrod (d): 5/3 Gauss, base stretch free",
        "bending_gauss_points": 3,
        "clamp": "position_and_direction",
    },
}

SVG_META = {"Date": None}
PNG_META = {"Software": None}
README_BEGIN = "<!-- convergence-table:begin (written by validation/convergence.py --update-readme) -->"
README_END = "<!-- convergence-table:end -->"


def softrod_binary(path):
    if path is not None:
        if not os.path.exists(path):
            raise SystemExit(f"{path}: no such softrod binary")
        return path
    path = os.path.join(ROOT, "target", "release", "softrod")
    if not os.path.exists(path):
        C.log(f"{path} missing: cargo build --release")
        subprocess.run(["cargo", "build", "--release"], cwd=ROOT, check=True)
    return path


def scene(params, n, config, name):
    """A softrod scene for the reference's sections and loads, n elements split evenly."""
    secs = params["sections"]
    if n % len(secs):
        raise ValueError(f"{n} elements do not split evenly over {len(secs)} sections")
    base = params["base"]
    return {
        "name": name,
        "description": f"validation/convergence.py: {name}",
        "robot": {
            "element": "planar_cable",
            "sections": [
                {"length_m": s["length_m"], "ea_n": s["ea_n"], "ei_nm2": s["ei_nm2"], "elements": n // len(secs)}
                for s in secs
            ],
            "axial_gauss_points": 5,
            "bending_gauss_points": config["bending_gauss_points"],
        },
        "base": {"position_m": base["position_m"], "angle_rad": base["angle_rad"], "clamp": config["clamp"]},
        "gravity_m_per_s2": [0.0, 0.0],
        "loads": params["loads"],
    }


def run_softrod(exe, sc, tmp):
    sp = os.path.join(tmp, sc["name"] + ".json")
    op = os.path.join(tmp, sc["name"] + ".out.json")
    with open(sp, "w") as f:
        json.dump(sc, f, indent=1)
    r = subprocess.run([exe, "solve", sp, "--out", op], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"softrod failed on {sp}: {r.stderr.strip()}")
    with open(op) as f:
        return json.load(f)


def floor_mask(err, correction=None):
    """True where a point is at the floor (rule 1 of the module docstring)."""
    mask = []
    hit = False
    for i, e in enumerate(err):
        if not hit:
            if e is None or e < ROUNDOFF_M:
                hit = True
            elif i > 0 and err[i - 1] is not None and err[i - 1] < FLATTEN_FACTOR * e:
                hit = True
            elif correction is not None and correction[i] is not None and correction[i] > EXUDYN_CORRECTION_SHARE * e:
                hit = True
        mask.append(hit)
    return mask


def observed_order(ne, err, fit_from, correction=None):
    """Least-squares slope of log(err) vs log(h), h = L/n, over the asymptotic range."""
    floor = floor_mask(err, correction)
    pts = [(n, e) for n, e, f in zip(ne, err, floor) if not f and n >= fit_from][-MAX_FIT_POINTS:]
    out = {"order": None, "fit_elements": [n for n, _ in pts], "at_floor": floor}
    if len(pts) < 2:
        return out
    x = np.log(C.LENGTH_M / np.array([n for n, _ in pts], dtype=float))
    y = np.log(np.array([e for _, e in pts]))
    out["order"] = float(np.polyfit(x, y, 1)[0])
    return out


def local_orders(ne, err):
    """log2(err_n / err_2n) for consecutive element counts (None where undefined)."""
    out = []
    for (n0, e0), (n1, e1) in zip(zip(ne, err), zip(ne[1:], err[1:])):
        ok = e0 and e1 and e0 > 0 and e1 > 0
        out.append(math.log(e0 / e1) / math.log(n1 / n0) if ok else None)
    return out


def compute(exe, ref_dir):
    results = {}
    with tempfile.TemporaryDirectory(prefix="softrod_convergence_") as tmp:
        for case in C.CASES:
            with open(os.path.join(ref_dir, f"exudyn_{case}.json")) as f:
                ex = json.load(f)
            with open(os.path.join(ref_dir, f"elastica_{case}.json")) as f:
                el = json.load(f)
            if ex["params"]["loads"] != el["params"]["loads"] or ex["params"]["sections"] != el["params"]["sections"]:
                raise ValueError(f"{case}: exudyn and elastica references describe different problems")
            tip_el = el["values"]["tip_position_m"]
            runs = {r["elements"]: r for r in ex["values"]["runs"]}
            res = {"elastica_tip_position_m": tip_el, "elements": ELEMENTS, "series": {}}
            ex_err = []
            for n in ELEMENTS:
                r = runs.get(n)
                ex_err.append(math.dist(r["tip_position_m"], tip_el) if r is not None and r["converged"] else None)
            corr = [runs[n]["residual"]["newton_correction_tip_position_m"] if n in runs else None for n in ELEMENTS]
            res["series"]["exudyn"] = {"tip_error_m": ex_err, "newton_correction_tip_position_m": corr}
            for key, cfg in CONFIGS.items():
                errs, tips, reports = [], [], []
                for n in ELEMENTS:
                    out = run_softrod(exe, scene(ex["params"], n, cfg, f"{case}_{key}_{n}"), tmp)
                    rep = out["report"]
                    tips.append(out["tip_position_m"])
                    # the status is {"converged": "<criterion>"} or a failure variant
                    converged = isinstance(rep["status"], dict) and "converged" in rep["status"]
                    errs.append(math.dist(out["tip_position_m"], tip_el) if converged else None)
                    reports.append({k: rep.get(k) for k in ("status", "iterations", "load_steps",
                                                            "residual_norm_n", "residual_tolerance_n")})
                res["series"][key] = {"tip_error_m": errs, "tip_position_m": tips, "report": reports}
            # softrod (b) against exudyn's discrete answer at the same n
            res["softrod_b_minus_exudyn_tip_m"] = [
                math.dist(t, runs[n]["tip_position_m"]) if n in runs and runs[n]["converged"] else None
                for n, t in zip(ELEMENTS, res["series"]["softrod_b"]["tip_position_m"])
            ]
            for key, s in res["series"].items():
                s["observed_order"] = observed_order(ELEMENTS, s["tip_error_m"], FIT_FROM[case],
                                                     s.get("newton_correction_tip_position_m"))
                s["local_order"] = local_orders(ELEMENTS, s["tip_error_m"])
            results[case] = res
            o = {k: s["observed_order"]["order"] for k, s in res["series"].items()}
            C.log(f"{case:26s} orders " + "  ".join(f"{k}={'-' if v is None else f'{v:.2f}'}" for k, v in o.items())
                  + f"  max|b-exudyn|={max(x for x in res['softrod_b_minus_exudyn_tip_m'] if x is not None):.1e} m")
    return results


STYLE = {
    "softrod_a": dict(color="tab:blue", marker="o", ms=4.5, lw=1.6, ls="-"),
    "softrod_b": dict(color="tab:orange", marker="s", ms=7, lw=0, mfc="none", mew=1.4),
    "exudyn": dict(color="black", marker="x", ms=5, lw=1.0, ls=":"),
}


def plot(results, out_dir):
    plt.rcParams["svg.hashsalt"] = "softrod"
    cases = list(results)
    ncol = 4
    nrow = math.ceil(len(cases) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.0 * ncol, 3.3 * nrow + 0.9), sharex=True)
    ne = np.array(ELEMENTS, dtype=float)
    labels = {"softrod_a": CONFIGS["softrod_a"]["short"], "softrod_b": CONFIGS["softrod_b"]["short"],
              "exudyn": "exudyn ObjectANCFCable2D (5/3 Gauss, clamp full)"}
    for ax, case in zip(axes.flat, cases):
        res = results[case]
        ymin = math.inf
        ymax = 0.0
        for key in ("softrod_a", "exudyn", "softrod_b"):
            s = res["series"][key]
            err = np.array([np.nan if e is None else max(e, 1e-18) for e in s["tip_error_m"]])
            o = s["observed_order"]["order"]
            lab = labels[key] + ("" if o is None else f"  [p = {o:.2f}]")
            ax.loglog(ne, err, label=lab, **STYLE[key])
            ymin = min(ymin, np.nanmin(err))
            ymax = max(ymax, np.nanmax(err))
        # guides over each series' fitted range: O(h^4) a factor 3 below softrod (a),
        # O(h^3) a factor 3 above softrod (b); none where a series has no fit
        for key, power, fac, ls in (("softrod_a", 4, 1 / 3.0, "--"), ("softrod_b", 3, 3.0, "-.")):
            s = res["series"][key]
            fit = s["observed_order"]["fit_elements"]
            if s["observed_order"]["order"] is None:
                continue
            n0, n1 = fit[0], fit[-1]
            e0 = s["tip_error_m"][ELEMENTS.index(n0)]
            nn = np.array([n0, n1], dtype=float)
            ax.loglog(nn, fac * e0 * (nn / n0) ** -power, color="0.35", lw=1.2, ls=ls,
                      label=f"O(h$^{power}$) guide")
        ax.axhspan(1e-30, ROUNDOFF_M, color="0.9", zorder=0, lw=0)
        ax.set_ylim(max(ymin / 5, 1e-18), ymax * 5)
        ax.set_title(case, fontsize=10)
        ax.grid(True, which="major", alpha=0.35)
        ax.tick_params(labelsize=8)
        ax.set_xticks(ELEMENTS)
        ax.set_xticklabels([str(n) for n in ELEMENTS])
        ax.minorticks_off()
        # per-panel orders as text (the legend carries only the styles)
        txt = "\n".join(
            f"{k}: p = {'-' if s['observed_order']['order'] is None else format(s['observed_order']['order'], '.2f')}"
            for k, s in (("(a)", res["series"]["softrod_a"]), ("(b)", res["series"]["softrod_b"]),
                         ("exudyn", res["series"]["exudyn"])))
        ax.text(0.03, 0.04, txt, transform=ax.transAxes, fontsize=7.5, va="bottom", ha="left",
                bbox=dict(boxstyle="round,pad=0.25", fc="white", ec="0.7", alpha=0.9))
    for ax in axes.flat[len(cases):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("elements n (h = L/n)", fontsize=9)
    for ax in axes[:, 0]:
        ax.set_ylabel("|tip - tip_elastica| [m]", fontsize=9)
    handles = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab.split("  [p")[0], h)
    order = [labels["softrod_a"], labels["softrod_b"], labels["exudyn"], "O(h$^4$) guide", "O(h$^3$) guide"]
    fig.suptitle(
        f"Tip error |tip − tip_elastica| against the element count; grey band: below {ROUNDOFF_M:.0e} m (round-off); "
        "p = observed order (least-squares slope in h over the asymptotic range)", fontsize=10.5, y=0.995)
    fig.legend([handles[k] for k in order if k in handles], [k for k in order if k in handles], loc="upper center",
               ncol=3, fontsize=9.5, frameon=False, bbox_to_anchor=(0.5, 0.978))
    fig.tight_layout(rect=(0, 0, 1, 0.935))
    for ext, meta in (("png", PNG_META), ("svg", SVG_META)):
        fig.savefig(os.path.join(out_dir, f"convergence.{ext}"), dpi=110, metadata=meta)
    plt.close(fig)


def fmt_order(s):
    o = s["observed_order"]
    if o["order"] is None:
        return "—"
    f = o["fit_elements"]
    return f"{o['order']:.2f} ({', '.join(str(n) for n in f)}){' †' if len(f) == 2 else ''}"


def order_table(results):
    lines = [
        "| case | softrod (a) 5/5 Gauss, base stretch free | softrod (b) 5/3 Gauss, clamp full | exudyn | "
        "max \\|(b) − exudyn\\| [m] | (c) 5/5, clamp full | (d) 5/3, base stretch free |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, res in results.items():
        d = max(x for x in res["softrod_b_minus_exudyn_tip_m"] if x is not None)
        lines.append(f"| `{case}` | " + " | ".join(fmt_order(res["series"][k]) for k in ("softrod_a", "softrod_b", "exudyn"))
                     + f" | {d:.1e} | " + " | ".join(fmt_order(res["series"][k]) for k in ("softrod_c", "softrod_d")) + " |")
    return "\n".join(lines)


def error_table(results):
    lines = ["| case | series | " + " | ".join(f"n={n}" for n in ELEMENTS) + " |",
             "|---|---|" + "---|" * len(ELEMENTS)]
    for case, res in results.items():
        for key, lab in (("softrod_a", "(a)"), ("softrod_b", "(b)"), ("exudyn", "exudyn"), ("softrod_c", "(c)"),
                         ("softrod_d", "(d)")):
            errs = res["series"][key]["tip_error_m"]
            lines.append(f"| `{case}` | {lab} | " + " | ".join("—" if e is None else f"{e:.1e}" for e in errs) + " |")
    return "\n".join(lines)


def update_readme(path, results):
    with open(path) as f:
        text = f.read()
    if README_BEGIN not in text or README_END not in text:
        raise SystemExit(f"{path}: markers {README_BEGIN!r} / {README_END!r} not found")
    head, rest = text.split(README_BEGIN, 1)
    _, tail = rest.split(README_END, 1)
    body = (README_BEGIN + "\n\nObserved order p (fitted element counts in brackets):\n\n" + order_table(results)
            + "\n\nTip error |tip − tip_elastica| in m:\n\n<details><summary>all errors</summary>\n\n"
            + error_table(results) + "\n\n</details>\n\n" + README_END)
    with open(path, "w") as f:
        f.write(head + body + tail)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--softrod", default=None, help="softrod binary (default: target/release/softrod, built if missing)")
    ap.add_argument("--ref-dir", default=os.path.join(ROOT, "reference"))
    ap.add_argument("--out-dir", default=os.path.join(HERE, "figures"))
    ap.add_argument("--update-readme", action="store_true", help="rewrite the order table in validation/README.md")
    ap.add_argument("--readme", default=os.path.join(HERE, "README.md"))
    a = ap.parse_args(argv)
    exe = softrod_binary(a.softrod)
    os.makedirs(a.out_dir, exist_ok=True)
    results = compute(exe, a.ref_dir)
    doc = {
        "generator": "validation/convergence.py",
        "versions": C.versions(("matplotlib",)),
        "description": "Tip error |tip - tip_elastica| (m) against the element count for softrod in two "
                       "configurations and exudyn; observed orders by least squares in log-log.",
        "elements": ELEMENTS,
        "configurations": {k: {kk: v for kk, v in c.items() if kk != "short"} for k, c in CONFIGS.items()},
        "order_fit": {"roundoff_m": ROUNDOFF_M, "flatten_factor": FLATTEN_FACTOR,
                      "exudyn_correction_share": EXUDYN_CORRECTION_SHARE, "fit_from_elements": FIT_FROM,
                      "max_points": MAX_FIT_POINTS,
                      "h": "L / n", "method": "least-squares slope of log(error) vs log(h)"},
        "cases": results,
    }
    C.write_json(os.path.join(a.out_dir, "convergence.json"), doc)
    plot(results, a.out_dir)
    print(order_table(results))
    if a.update_readme:
        update_readme(a.readme, results)
        print(f"updated {a.readme}")
    print(f"wrote convergence.{{png,svg,json}} to {os.path.abspath(a.out_dir)}")


if __name__ == "__main__":
    main()
