"""Regenerate (or check) every reference file under reference/.

    python validation/make_references.py [--venv] [--only cheap|exudyn|family|spatial|beam3d|parallel|elastica|skfem|contact]
                                         [--out-dir DIR] [--check]

--venv     create validation/.venv if absent, pip-install validation/requirements.txt
           into it (again whenever requirements.txt changes) and re-run this script
           with the venv's Python.
--only     cheap: one planar exudyn case, one spatial exudyn case, one 3-D beam case and
           one scikit-fem case (what CI runs); exudyn / elastica / skfem: that generator
           only (exudyn includes the load family of exudyn_load_family.py, the spatial
           cable of exudyn_spatial_cable.py and the 3-D beams of exudyn_beam3d.py;
           family, spatial, beam3d: those only; contact: the contact references of
           validation/contact_*.py).
--out-dir  where to write the JSON files (default: reference/).
--check    generate into a temporary directory and compare with the committed files
           in --out-dir: every number (outside "versions" and "timing_s") must agree to
           a relative tolerance of 1e-9 (plus 1e-15 absolute, for round-off zeros),
           everything else exactly; solver diagnostics (residuals, iteration counts)
           are only checked for presence unless --strict. Exit code 1 on a mismatch.
           Nothing in --out-dir is written.

Prints a summary table (case, generator, tip x, tip y, tip angle, time). After a
full run (no --only, no --check) it also runs validation/agreement.py, which writes
validation/AGREEMENT.md, and validation/plot_references.py (validation/figures/).
"""

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
VENV = os.path.join(HERE, ".venv")
REQUIREMENTS = os.path.join(HERE, "requirements.txt")
DEFAULT_OUT = os.path.join(ROOT, "reference")
RTOL = 1e-9
ATOL = 1e-15  # numbers below this magnitude are round-off zeros (e.g. constrained base coordinates)
IGNORED_KEYS = {"versions", "timing_s"}
# Solver diagnostics: round-off-level residuals and iteration counts. They reproduce
# bit-for-bit on one machine but need not on another CPU, so by default only their
# presence and structure are compared (--strict compares them like everything else).
DIAGNOSTIC_KEYS = {"residual", "shooting_residual_nm", "final_residual_max_abs_n", "newton_iterations",
                   "load_steps", "step_halvings"}
# Differences of two solutions (mesh to mesh, rod to elastica, distance to a bound): their
# round-off is absolute, that of the solutions they subtract (about 1e-12 m on the 0.24 m
# rod; scikit-fem's sparse solve differs at that level from one CPU to another), so a
# relative test on a 1e-9 m difference fails for no reason. Compared to DIFFERENCE_ATOL.
DIFFERENCE_KEYS = {"mesh_change_last_refinement_m", "pass_bound", "rod_elastica_equivalent"}
DIFFERENCE_ATOL = 1e-11  # m or rad: 40x the round-off seen, 1e3x below any difference kept

# one thread for BLAS: reproducible sums, and no oversubscription on 2 cores
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")


def in_venv():
    return os.path.realpath(sys.prefix) == os.path.realpath(VENV)


def venv_python():
    return os.path.join(VENV, "bin", "python")


def ensure_venv():
    """Create/refresh validation/.venv and re-exec this script inside it."""
    if in_venv():
        return
    if not os.path.exists(venv_python()):
        print(f"creating {VENV}", flush=True)
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    with open(REQUIREMENTS, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    stamp = os.path.join(VENV, ".requirements.sha256")
    if not os.path.exists(stamp) or open(stamp).read().strip() != digest:
        print(f"installing {REQUIREMENTS} into {VENV}", flush=True)
        subprocess.check_call([venv_python(), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                               "-r", REQUIREMENTS])
        with open(stamp, "w") as f:
            f.write(digest + "\n")
    args = [a for a in sys.argv[1:] if a != "--venv"]
    sys.stdout.flush()
    os.execv(venv_python(), [venv_python(), os.path.abspath(__file__), *args])


def generate(only, out_dir):
    """Run the generators; return the summary rows."""
    sys.path.insert(0, HERE)
    import common as C

    rows = []
    if only in (None, "elastica"):
        import elastica_follower

        for name in elastica_follower.CASES:
            rows += elastica_follower.run_case(name, out_dir)
        import elastica_heavy_column

        rows += elastica_heavy_column.run_case(out_dir)
        import elastica

        for name in C.CASES:
            rows += elastica.run_case(name, out_dir)
    if only in (None, "exudyn", "cheap"):
        import exudyn_cantilever

        names = C.CHEAP["exudyn"] if only == "cheap" else list(C.CASES)
        for name in names:
            rows += exudyn_cantilever.run_case(name, out_dir)
    if only in (None, "exudyn", "family"):
        import exudyn_load_family

        rows += exudyn_load_family.run_all(out_dir)
    if only in (None, "exudyn"):
        import exudyn_rest_curvature

        for name in exudyn_rest_curvature.CASES:
            rows += exudyn_rest_curvature.run_case(name, out_dir)
    if only in (None, "exudyn", "spatial", "cheap"):
        import exudyn_spatial_cable

        names = exudyn_spatial_cable.CHEAP if only == "cheap" else list(exudyn_spatial_cable.CASES)
        for name in names:
            rows += exudyn_spatial_cable.run_case(name, out_dir)
    if only in (None, "exudyn", "beam3d", "cheap"):
        import exudyn_beam3d

        names = exudyn_beam3d.CHEAP if only == "cheap" else list(exudyn_beam3d.CASES)
        for name in names:
            rows += exudyn_beam3d.run_case(name, out_dir)
    if only in (None, "exudyn", "parallel", "cheap"):
        import exudyn_parallel

        for name in exudyn_parallel.CHEAP if only == "cheap" else list(exudyn_parallel.CASES):
            rows += exudyn_parallel.run_case(name, out_dir)
    if only in (None, "skfem", "cheap"):
        import skfem_strip

        if only == "cheap":
            jobs = [("slender", n) for n in C.CHEAP["skfem"]]
        else:
            jobs = [(s, n) for s in skfem_strip.STRIPS for n in skfem_strip.SKFEM_CASES]
        for strip, name in jobs:
            rows += skfem_strip.run_case(name, out_dir, strip)
    if only in (None, "contact"):
        import contact_elastica_obstacle
        import contact_exudyn_penalty
        import contact_propped_cantilever

        rows += contact_propped_cantilever.run_all(out_dir)
        rows += contact_elastica_obstacle.run_all(out_dir)
        rows += contact_exudyn_penalty.run_all(out_dir)
    return rows


def print_summary(rows):
    head = f"{'case':26s} {'generator':22s} {'tip x [m]':>16s} {'tip y [m]':>16s} {'tip angle [rad]':>16s} {'time [s]':>9s}"
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r['case']:26s} {r['generator']:22s} {r['tip'][0]:16.10f} {r['tip'][1]:16.10f} {r['angle']:16.10f} {r['time']:9.2f}")
    print(f"{len(rows)} files, {sum(r['time'] for r in rows):.1f} s")


# ---------------------------------------------------------------------------
# --check
# ---------------------------------------------------------------------------

def compare(new, old, path="", out=None, strict=False, loose=False, atol=ATOL):
    """Recursive comparison; append human-readable mismatches to `out`.

    Numbers: |new - old| <= RTOL max(|new|, |old|) + atol (ATOL, or DIFFERENCE_ATOL under a
    DIFFERENCE_KEYS key). Inside a diagnostic key
    (unless strict) numbers need only be numbers on both sides.
    """
    if out is None:
        out = []
    if isinstance(new, dict) and isinstance(old, dict):
        for k in sorted(set(new) | set(old)):
            if k in IGNORED_KEYS:
                continue
            if k not in new:
                out.append(f"{path}/{k}: missing in the regenerated file")
            elif k not in old:
                out.append(f"{path}/{k}: missing in the committed file")
            else:
                compare(new[k], old[k], f"{path}/{k}", out, strict, loose or (k in DIAGNOSTIC_KEYS and not strict),
                        DIFFERENCE_ATOL if k in DIFFERENCE_KEYS else atol)
    elif isinstance(new, list) and isinstance(old, list):
        if len(new) != len(old):
            out.append(f"{path}: length {len(new)} (regenerated) != {len(old)} (committed)")
        else:
            for i, (a, b) in enumerate(zip(new, old)):
                compare(a, b, f"{path}[{i}]", out, strict, loose, atol)
    elif _is_number(new) and _is_number(old):
        if loose:
            return out
        if not (abs(new - old) <= RTOL * max(abs(new), abs(old)) + atol):
            rel = abs(new - old) / max(abs(new), abs(old))
            out.append(f"{path}: {new!r} (regenerated) vs {old!r} (committed), relative difference {rel:.3e}")
    elif new != old:
        out.append(f"{path}: {new!r} (regenerated) != {old!r} (committed)")
    return out


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check(rows, tmp_dir, ref_dir, full, strict=False):
    bad = 0
    generated = {os.path.basename(r["path"]) for r in rows}
    for fname in sorted(generated):
        committed = os.path.join(ref_dir, fname)
        if not os.path.exists(committed):
            print(f"MISMATCH {fname}: no committed file {committed}")
            bad += 1
            continue
        with open(os.path.join(tmp_dir, fname)) as f:
            new = json.load(f)
        with open(committed) as f:
            old = json.load(f)
        diffs = compare(new, old, strict=strict)
        if diffs:
            bad += 1
            print(f"MISMATCH {fname}: {len(diffs)} difference(s)")
            for d in diffs[:15]:
                print(f"    {d}")
            if len(diffs) > 15:
                print(f"    ... {len(diffs) - 15} more")
        else:
            print(f"ok       {fname}")
    if full:
        stale = sorted(f for f in os.listdir(ref_dir) if f.endswith(".json") and f not in generated)
        stale = [f for f in stale if f.split("_")[0] in ("exudyn", "elastica", "skfem", "contact")]
        for f in stale:
            print(f"MISMATCH {f}: committed but no generator writes it any more")
            bad += 1
    return bad


def main():
    ap = argparse.ArgumentParser(description="Regenerate or check the reference/*.json files.")
    ap.add_argument("--venv", action="store_true", help="run inside validation/.venv (created/updated as needed)")
    ap.add_argument(
        "--only", choices=["cheap", "exudyn", "family", "spatial", "beam3d", "parallel", "elastica", "skfem", "contact"], default=None
    )
    ap.add_argument("--out-dir", default=DEFAULT_OUT)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--strict", action="store_true", help="with --check: compare solver diagnostics too")
    a = ap.parse_args()
    if a.venv:
        ensure_venv()
    out_dir = os.path.abspath(a.out_dir)
    if a.check:
        with tempfile.TemporaryDirectory(prefix="softrod-ref-") as tmp:
            rows = generate(a.only, tmp)
            print_summary(rows)
            print()
            bad = check(rows, tmp, out_dir, full=a.only is None, strict=a.strict)
        if bad:
            print(f"\nCHECK FAILED: {bad} of the reference files differ from a fresh regeneration "
                  f"(relative tolerance {RTOL:g}). Regenerate with `python validation/make_references.py --venv` "
                  f"if the change is intended, and review the diff.")
            sys.exit(1)
        print(f"\ncheck passed: {len(rows)} files agree with {out_dir} (relative tolerance {RTOL:g})")
        return
    os.makedirs(out_dir, exist_ok=True)
    rows = generate(a.only, out_dir)
    print_summary(rows)
    if a.only is None:
        sys.path.insert(0, HERE)
        import agreement
        import plot_references

        agreement.main(["--ref-dir", out_dir])
        plot_references.main(["--ref-dir", out_dir])


if __name__ == "__main__":
    main()
