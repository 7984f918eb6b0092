"""Fit cost ~ n^p to criterion medians: python3 benches/fit_exponent.py GROUP [MIN_N]

Reads target/criterion/GROUP/<n>/new/estimates.json (median), prints a table
and the least-squares slope of log(time) against log(n) for n >= MIN_N.
"""
import json
import math
import pathlib
import sys

group = sys.argv[1]
min_n = int(sys.argv[2]) if len(sys.argv) > 2 else 100
root = pathlib.Path("target/criterion") / group
rows = []
for d in root.iterdir():
    est = d / "new" / "estimates.json"
    if d.name.isdigit() and est.exists():
        rows.append((int(d.name), json.loads(est.read_text())["median"]["point_estimate"] * 1e-9))
rows.sort()
print(f"| elements | median |")
print(f"|---|---|")
for n, t in rows:
    print(f"| {n} | {t * 1e6:.1f} µs |")
fit = [(math.log(n), math.log(t)) for n, t in rows if n >= min_n]
mx = sum(x for x, _ in fit) / len(fit)
my = sum(y for _, y in fit) / len(fit)
p = sum((x - mx) * (y - my) for x, y in fit) / sum((x - mx) ** 2 for x, _ in fit)
print(f"log-log fit exponent for n >= {min_n}: {p:.3f}")
