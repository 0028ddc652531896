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


#: Instruction sets that change speeds (and 8-bit results: onnxruntime without VNNI saturates).
SIMD_FLAGS = ("avx2", "avx512f", "avx512_vnni", "avx_vnni", "asimddp")


def cpu_model() -> tuple[str, list[str]]:
    """The processor's name and which of SIMD_FLAGS it has, from /proc/cpuinfo (Linux; elsewhere
    platform.processor() and no flags). The sessions' machines differ by 2x in speed."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or "unknown", []
    fields = dict(
        (k.strip(), v.strip())
        for k, _, v in (line.partition(":") for line in text.splitlines()[:64])
        if v
    )
    flags = set(fields.get("flags", fields.get("Features", "")).split())
    name = fields.get("model name") or platform.processor() or "unknown"
    return name, [f for f in SIMD_FLAGS if f in flags]


def machine() -> dict[str, object]:
    """What the numbers were measured on."""
    name, flags = cpu_model()
    return {
        "platform": platform.platform(),
        "processor": name,
        "simd": flags,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }


def speed_reference_ms(image: np.ndarray, repeats: int = 30) -> float:
    """Median time [ms] of OpenCV's ORB (the core's ``extract_orb`` with adaptive detection off)
    on ``image`` (8-bit gray): one fixed piece of work, to put runs of different machines side
    by side (the sessions' machines differ by about 2x)."""
    from slslam import _core  # (imported here: the helpers above need no build)

    options = _core.OrbOptions()
    options.adaptive = False
    image = np.ascontiguousarray(image)
    return time_calls(lambda: _core.extract_orb(image, options), repeats)["median_ms"]


def machine_line() -> str:
    """One line for a results table: processor, its SIMD flags, cores."""
    m = machine()
    simd = ", ".join(m["simd"]) or "none of " + " / ".join(SIMD_FLAGS)
    return f"Machine: {m['processor']} ({simd}), {m['cpu_count']} cores"


def write_results(name: str, results: dict, out: Path | None = None) -> Path:
    path = out or RESULTS_DIR / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"benchmark": name, "machine": machine(), **results}, indent=2))
    return path


def load_published_sources(path: Path, check_values: Callable[[str, object], None]) -> dict:
    """The ``sources`` of a published-numbers file (published_ate.yaml, published_kitti.yaml):
    ``{source: {label, citation, note?, values, ...}}``, each with a ``label`` and a non-empty
    ``citation``; ``check_values(where, values)`` raises InputError for a source's bad
    ``values`` (``where``: ``sources.<name>.values``). A bad file raises InputError naming the
    file and the key."""
    import yaml  # (imported here: the helpers above need neither)

    from slslam.errors import InputError

    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise InputError(path, f"cannot read published numbers ({exc})") from None
    sources = data.get("sources") if isinstance(data, dict) else None
    if not isinstance(sources, dict) or not sources:
        raise InputError(path, "expected a 'sources' mapping")
    for source, entry in sources.items():
        where = f"sources.{source}"
        if not isinstance(entry, dict) or not isinstance(entry.get("label"), str):
            raise InputError(path, f"{where}: needs a 'label' string")
        if not isinstance(entry.get("citation"), str) or not entry["citation"].strip():
            raise InputError(path, f"{where}: needs a 'citation' naming where the numbers are from")
        try:
            check_values(f"{where}.values", entry.get("values"))
        except InputError as exc:
            raise InputError(path, exc.problem) from None
    return sources


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


def sim_cam_b_from_cam_a(sim, a: int, b: int) -> np.ndarray:
    """T_b_a (4 x 4): the rectified left camera of simulated frame a seen from frame b's."""
    T_w_a, T_w_b = (
        sim.trajectory.pose(np.array([f / sim.options.rate_hz]))[0] @ sim.camera.T_body_cam0
        for f in (a, b)
    )
    return np.linalg.inv(T_w_b) @ T_w_a


def segment_match_correct(a_in_b: np.ndarray, b: np.ndarray, eps_px: float) -> bool:
    """A line match is right when segment a, moved into B (u0 v0 u1 v1), lies within eps_px of
    b's line on average over its endpoints and overlaps b along it."""
    if not np.all(np.isfinite(a_in_b)):
        return False
    p0, p1 = b[:2], b[2:]
    d = (p1 - p0) / max(np.linalg.norm(p1 - p0), 1e-9)
    n = np.array([-d[1], d[0]])
    a0, a1 = a_in_b[:2], a_in_b[2:]
    distance = 0.5 * (abs(n @ (a0 - p0)) + abs(n @ (a1 - p0)))
    t = sorted([(a0 - p0) @ d, (a1 - p0) @ d])
    overlap = min(t[1], np.linalg.norm(p1 - p0)) - max(t[0], 0.0)
    return distance < eps_px and overlap > 0


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
