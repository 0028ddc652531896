"""PNG plots of a trajectory evaluation (matplotlib, no screen needed)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never open a window from a library
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection

from slslam.eval.metrics import ErrorResult


def plot_ape(ape: ErrorResult, path: str | Path, title: str = "") -> Path:
    """Top view (x-y) of ground truth and the aligned estimate coloured by APE, and APE over time.

    Returns the path of the PNG written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ref_xyz = ape.reference.positions_xyz
    est_xyz = ape.estimate_aligned.positions_xyz
    errors = ape.errors

    fig, (ax_top, ax_err) = plt.subplots(
        1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [1.1, 1]}
    )
    ax_top.plot(ref_xyz[:, 0], ref_xyz[:, 1], "--", color="0.45", lw=1.2, label="ground truth")
    segments = np.stack([est_xyz[:-1, :2], est_xyz[1:, :2]], axis=1)
    # an (N, 2, 2) array is a sequence of segments; matplotlib's stub takes only a Sequence
    lines = LineCollection(segments, cmap="viridis", linewidths=2.0)  # type: ignore[arg-type]
    lines.set_array(0.5 * (errors[:-1] + errors[1:]))
    ax_top.add_collection(lines)
    ax_top.autoscale()
    ax_top.set_aspect("equal", adjustable="datalim")
    ax_top.set_xlabel("x [m]")
    ax_top.set_ylabel("y [m]")
    ax_top.set_title("top view, estimate coloured by APE")
    ax_top.legend(loc="best")
    fig.colorbar(lines, ax=ax_top, label="APE [m]")

    if ape.timestamps is not None and len(ape.timestamps) == len(errors):
        x = ape.timestamps - ape.timestamps[0]
        ax_err.set_xlabel("time [s]")
    else:
        x = np.arange(len(errors))
        ax_err.set_xlabel("pose index")
    ax_err.plot(x, errors, color="tab:blue", lw=1.0, label="APE")
    ax_err.axhline(
        ape.stats["rmse"], color="tab:red", lw=1.0, label=f"RMSE {ape.stats['rmse']:.4f} m"
    )
    ax_err.axhline(
        ape.stats["median"],
        color="tab:green",
        lw=1.0,
        ls=":",
        label=f"median {ape.stats['median']:.4f} m",
    )
    ax_err.set_ylabel("APE [m]")
    ax_err.set_title(f"APE over time (alignment: {ape.options.get('align')})")
    ax_err.grid(alpha=0.3)
    ax_err.legend(loc="best")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    # A temporary name and a rename: an interrupted run never leaves a truncated ape.png.
    tmp = path.with_name(path.name + ".partial")
    try:
        fig.savefig(tmp, dpi=110, format="png")
        tmp.replace(path)
    finally:
        plt.close(fig)
        tmp.unlink(missing_ok=True)
    return path
