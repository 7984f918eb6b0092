"""Fig. 4 of the paper: estimation error against the number of position-only
feature points, both backends.

Reads validation/figures/fig4_feature_points.json (written by
`SOFTROD_WRITE_FIGURES=1 cargo test --release --test estimate_figures`) and writes
validation/figures/fig4_feature_points.{png,svg}.

Run: validation/.venv/bin/python validation/plot_fig4.py
"""
import json
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
DATA = HERE / "figures" / "fig4_feature_points.json"


def main():
    d = json.loads(DATA.read_text())
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for backend, style in (("newton", dict(marker="o", ls="-")), ("sqp", dict(marker="x", ls="--"))):
        rows = sorted((v for v in d["values"] if v["backend"] == backend), key=lambda v: v["points"])
        pts = [v["points"] for v in rows]
        axes[0].plot(pts, [1e3 * v["backbone_rms_m"] for v in rows], label=backend, **style)
        axes[1].plot(pts, [v["resultant_error_n"] for v in rows], label=backend, **style)
    axes[0].set_ylabel("backbone RMS error [mm]")
    axes[1].set_ylabel("resultant force error [N]")
    for ax in axes:
        ax.set_xlabel("feature points (positions only)")
        ax.grid(True, alpha=0.4)
        ax.legend()
    p = d["params"]
    fig.suptitle(f"Fig. 4: {p['robot']}; load {p['load']}; noise {1e3 * p['noise_m']:.2f} mm", fontsize=9)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(HERE / "figures" / f"fig4_feature_points.{ext}", dpi=120)
    print("wrote", HERE / "figures" / "fig4_feature_points.{png,svg}")


if __name__ == "__main__":
    main()
