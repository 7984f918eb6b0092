"""Prints the README performance tables (Markdown) from criterion's results.

Run the benches first (`cargo bench --bench statics -- --warm-up-time 1
--measurement-time 3` and `cargo bench --bench estimate`), then, from the
crate root: `python3 benches/table.py`. Reads
target/criterion/<group>/[<backend>/]<parameter>/new/estimates.json
(medians); exponents are least-squares slopes of log t against log n for
n >= 100 (the logic of benches/fit_exponent.py). A cell is empty when that
benchmark has not been run; `†` marks a cold step that did not converge
or a warm-step benchmark in which some steps did not converge (the time to
the answer is shown; benches/estimate.rs leaves a `not_converged` file).
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from fit_exponent import ROOT, fit, median_s, medians  # noqa: E402

BACKENDS = ["newton", "sqp"]
ELEMENTS = [5, 10, 20, 40, 80, 160]
MARKERS = [2, 3, 5, 8, 11]
SCALING = [100, 200, 500, 1000, 2000]


def fmt(t):
    """A duration (s) with three significant digits and a unit."""
    if t is None:
        return ""
    for unit, f in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if t >= f or unit == "ns":
            v = t / f
            return f"{v:.0f} {unit}" if v >= 100 else f"{v:.1f} {unit}" if v >= 10 else f"{v:.2f} {unit}"


def cell(path):
    """Formatted median of the benchmark at `path` (a directory), or ''."""
    est = path / "new" / "estimates.json"
    if not est.exists():
        return ""
    mark = " †" if (path / "not_converged").exists() else ""
    return fmt(median_s(est)) + mark


def exponent(rows):
    p = fit(rows, 100)
    return "" if p is None else f"{p:.2f}"


def statics():
    groups = [
        ("one Newton step: residual + tangent + banded factorization + solve", "newton_step"),
        ("cold static solve, default scene", "static_solve_cold"),
        ("warm static solve after a 0.5 kPa change", "static_solve_warm"),
    ]
    data = {g: dict(medians(g)) for _, g in groups}
    ns = sorted({n for d in data.values() for n in d})
    if not ns:
        return
    print("| what | " + " | ".join(f"{n} el" for n in ns) + " | fit exponent (100–2000) |")
    print("|---|" + "---|" * (len(ns) + 1))
    for label, g in groups:
        d = data[g]
        cells = [fmt(d.get(n)) for n in ns]
        print(f"| {label} (`{g}`) | " + " | ".join(cells) + f" | {exponent(sorted(d.items()))} |")
    print()


def grid(group, title):
    base = ROOT / group
    if not base.is_dir():
        return
    for b in BACKENDS:
        if not (base / b).is_dir():
            continue
        print(f"| {title}, `{b}` (`{group}`) | " + " | ".join(f"{m} markers" for m in MARKERS) + " |")
        print("|---|" + "---|" * len(MARKERS))
        for n in ELEMENTS:
            cells = [cell(base / b / f"{n}el_{m}mk") for m in MARKERS]
            if any(cells):
                print(f"| {n} el | " + " | ".join(cells) + " |")
        print()


def scaling():
    group = "estimate_warm_scaling"
    if not (ROOT / group).is_dir():
        return
    print("| warm step, 5 markers (`estimate_warm_scaling`) | "
          + " | ".join(f"{n} el" for n in SCALING) + " | fit exponent (100–2000, † left out) |")
    print("|---|" + "---|" * (len(SCALING) + 1))
    for b in BACKENDS:
        # the fit leaves out sizes with non-converged steps (†)
        rows = [(n, t) for n, t in medians(f"{group}/{b}")
                if not (ROOT / group / b / str(n) / "not_converged").exists()]
        cells = [cell(ROOT / group / b / str(n)) for n in SCALING]
        print(f"| `{b}` | " + " | ".join(cells) + f" | {exponent(rows)} |")
    print()


def single(group, params, title):
    base = ROOT / group
    if not base.is_dir():
        return
    print(f"| {title} (`{group}`) | " + " | ".join(params) + " |")
    print("|---|" + "---|" * len(params))
    for b in BACKENDS:
        if (base / b).is_dir():
            print(f"| `{b}` | " + " | ".join(cell(base / b / p) for p in params) + " |")
    print()


def bounded():
    group = "estimate_warm_step_bounded"
    base = ROOT / group
    if not base.is_dir():
        return
    params = ["20el_5mk", "80el_5mk"]
    print(f"| sqp warm step, 5 markers (`{group}`) | " + " | ".join(p.replace("el_5mk", " el") for p in params) + " |")
    print("|---|" + "---|" * len(params))
    free = ROOT / "estimate_warm_step" / "sqp"
    print("| no bounds (`estimate_warm_step`) | " + " | ".join(cell(free / p) for p in params) + " |")
    print("| one active bound, w_y ≥ −0.3 N/m at mid-length | "
          + " | ".join(cell(base / "sqp" / p) for p in params) + " |")
    print()


if __name__ == "__main__":
    statics()
    grid("estimate_warm_step", "warm streaming step (new noisy frame)")
    bounded()
    scaling()
    grid("estimate_cold_step", "cold step (fresh estimator, α given)")
    single("estimate_alpha_search", ["20el_5mk"], "first step with the α search (the default rule, the evidence)")
