"""Keypoints, line segments and their matches drawn on images, written as PNG."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection


def _axes_for(images: list[np.ndarray], title: str):
    h = max(im.shape[0] for im in images)
    w = sum(im.shape[1] for im in images)
    fig = plt.figure(figsize=(w / 100, h / 100 + 0.4), dpi=100)
    ax = fig.add_axes([0, 0, 1, h / (h + 40)])
    ax.imshow(np.hstack(images), cmap="gray", vmin=0, vmax=255)
    ax.set_axis_off()
    fig.suptitle(title, fontsize=9, y=0.995)
    return fig, ax


def draw_features(
    path: str | Path,
    image: np.ndarray,
    keypoints: np.ndarray | None = None,
    segments: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """Keypoints (N, 2) as green dots and segments (M, 4: u0 v0 u1 v1) as orange lines."""
    fig, ax = _axes_for([image], title)
    if segments is not None and len(segments):
        ax.add_collection(
            LineCollection(segments.reshape(-1, 2, 2), colors="orange", linewidths=1.2)
        )
    if keypoints is not None and len(keypoints):
        ax.scatter(keypoints[:, 0], keypoints[:, 1], s=4, c="lime", linewidths=0)
    return _save(fig, path)


def draw_matches(
    path: str | Path,
    image_a: np.ndarray,
    image_b: np.ndarray,
    points_a: np.ndarray,
    points_b: np.ndarray,
    point_pairs: np.ndarray,
    segments_a: np.ndarray | None = None,
    segments_b: np.ndarray | None = None,
    line_pairs: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """Two images side by side: point matches in green, matched segments in matching colours."""
    fig, ax = _axes_for([image_a, image_b], title)
    shift = np.array([image_a.shape[1], 0.0])
    if len(point_pairs):
        a, b = points_a[point_pairs[:, 0]], points_b[point_pairs[:, 1]] + shift
        ax.add_collection(
            LineCollection(np.stack([a, b], 1), colors="lime", linewidths=0.4, alpha=0.6)
        )
    if line_pairs is not None and len(line_pairs):
        colours = plt.cm.tab20(np.arange(len(line_pairs)) % 20)
        sa = segments_a[line_pairs[:, 0]].reshape(-1, 2, 2)
        sb = segments_b[line_pairs[:, 1]].reshape(-1, 2, 2) + shift
        ax.add_collection(LineCollection(sa, colors=colours, linewidths=2))
        ax.add_collection(LineCollection(sb, colors=colours, linewidths=2))
    return _save(fig, path)


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
