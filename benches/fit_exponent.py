"""Fit cost ~ n^p to criterion medians: python3 benches/fit_exponent.py GROUP [MIN_N]

Reads target/criterion/GROUP/<n>/new/estimates.json (median), prints a table
and the least-squares slope of log(time) against log(n) for n >= MIN_N.
GROUP may include a function level, e.g. `estimate_warm_scaling/sqp`.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path("target/criterion")


def median_s(path):
    """Criterion's median (s) from an estimates.json."""
    return json.loads(path.read_text())["median"]["point_estimate"] * 1e-9


def medians(group, root=ROOT):
    """[(n, median s)] for the numeric parameters under GROUP, sorted by n."""
    rows = []
    base = root / group
    if not base.is_dir():
        return rows
    for d in base.iterdir():
        est = d / "new" / "estimates.json"
        if d.name.isdigit() and est.exists():
            rows.append((int(d.name), median_s(est)))
    rows.sort()
    return rows


def fit(rows, min_n=100):
    """Least-squares slope of log t against log n over n >= min_n (None if < 2 points)."""
    pts = [(math.log(n), math.log(t)) for n, t in rows if n >= min_n]
    if len(pts) < 2:
        return None
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)


if __name__ == "__main__":
    group = sys.argv[1]
    min_n = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    rows = medians(group)
    print("| elements | median |")
    print("|---|---|")
    for n, t in rows:
        print(f"| {n} | {t * 1e6:.1f} µs |")
    p = fit(rows, min_n)
    print(f"log-log fit exponent for n >= {min_n}: {p:.3f}" if p is not None else "too few points to fit")
