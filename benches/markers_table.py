"""Prints the README table "Cost in the number of markers" (Markdown) from
criterion's results of `cargo bench -j 1 --bench estimate_markers`: the
medians per backend and marker count, each row's ratio to the row before
(10x the markers: linear work is 10x) and the log-log slope over
100-10 000 markers. Run from the crate root after the bench.
"""
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from fit_exponent import ROOT, median_s  # noqa: E402
from table import fmt  # noqa: E402

BACKENDS = ["newton", "sqp"]
MARKERS = [10, 100, 1000, 10000]
GROUPS = [
    ("estimate_markers_warm", "warm step, alpha = 31"),
    ("estimate_markers_first", "first step, alpha by the evidence, + resultant covariance"),
]


def median(group, backend, m):
    est = ROOT / group / backend / f"{m}mk" / "new" / "estimates.json"
    return median_s(est) if est.exists() else None


def main():
    head = "| markers | " + " | ".join(f"{b}: {what}" for g, what in GROUPS for b in BACKENDS) + " |"
    print(head)
    print("|---" * (1 + len(GROUPS) * len(BACKENDS)) + "|")
    prev = {}
    for m in MARKERS:
        cells = []
        for g, _ in GROUPS:
            for b in BACKENDS:
                t = median(g, b, m)
                p = prev.get((g, b))
                ratio = f" (×{t / p:.1f})" if t and p else ""
                cells.append(fmt(t) + ratio)
                prev[(g, b)] = t
        print(f"| {m} | " + " | ".join(cells) + " |")
    slopes = []
    for g, _ in GROUPS:
        for b in BACKENDS:
            pts = [(math.log(m), math.log(t)) for m in MARKERS[1:] if (t := median(g, b, m))]
            if len(pts) >= 2:
                n = len(pts)
                mx = sum(x for x, _ in pts) / n
                my = sum(y for _, y in pts) / n
                s = sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)
                slopes.append(f"{s:.2f}")
            else:
                slopes.append("")
    print("| slope 100–10 000 | " + " | ".join(slopes) + " |")


if __name__ == "__main__":
    main()
