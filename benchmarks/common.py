"""Helpers shared by the benchmark scripts: timing statistics and result files."""

from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

RESULTS_DIR = Path(__file__).resolve().parent / "results"
SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def time_calls(fn: Callable[[], object], repeats: int, warmup: int = 2) -> dict[str, float]:
    """Median, mean and min wall time of ``fn`` in milliseconds."""
    for _ in range(warmup):
        fn()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - start) * 1e3)
    values = np.asarray(samples)
    return {
        "median_ms": float(np.median(values)),
        "mean_ms": float(values.mean()),
        "min_ms": float(values.min()),
        "repeats": repeats,
    }


def machine() -> dict[str, object]:
    """What the numbers were measured on."""
    return {
        "platform": platform.platform(),
        "processor": platform.processor(),
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }


def write_results(name: str, results: dict, out: Path | None = None) -> Path:
    path = out or RESULTS_DIR / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"benchmark": name, "machine": machine(), **results}, indent=2))
    return path


def transfer_pixels(
    uv: np.ndarray, depth_a: np.ndarray, T_b_a: np.ndarray, cam
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels of rectified camera A moved into camera B through A's depth map (ground truth
    correspondences of the simulator): (uv in B (N, 2), depth in A (N,), depth in B (N,))."""
    u = np.clip(np.round(uv[:, 0]).astype(int), 0, cam.width - 1)
    v = np.clip(np.round(uv[:, 1]).astype(int), 0, cam.height - 1)
    z = depth_a[v, u]
    p = np.column_stack([(uv[:, 0] - cam.cx) / cam.fx * z, (uv[:, 1] - cam.cy) / cam.fx * z, z])
    q = p @ T_b_a[:3, :3].T + T_b_a[:3, 3]
    uv_b = np.column_stack(
        [cam.fx * q[:, 0] / q[:, 2] + cam.cx, cam.fx * q[:, 1] / q[:, 2] + cam.cy]
    )
    return uv_b, z, q[:, 2]


def parse_overrides(items: list[str]) -> dict:
    """``a.b.c=value`` pairs as a nested dict (values parsed as YAML scalars)."""
    import yaml

    tree: dict = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"--set {item!r}: expected KEY=VALUE, e.g. tracking.use_lines=false")
        node = tree
        *parents, leaf = key.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = yaml.safe_load(value)
    return tree
