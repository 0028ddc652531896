"""Tracking ablation: ORB vs SuperPoint points, with and without lines, over whole sequences.

    python benchmarks/tracking_ablation.py [--sequences euroc loop_l100 loop_l015]
        [--configs orb,sp,orb_lines,sp_lines] [--frames 400] [--data-dir DIR] [--out DIR]

Runs ``slslam.tracking.run_sequence`` per configuration, one after the other in one process: ORB
points (orb), SuperPoint points (sp), ORB + lines (orb_lines), SuperPoint + lines (sp_lines), on
the real EuRoC V1_01 excerpt (ATE against euroc_groundtruth_leftcam/V101_GT.txt) and the simulated
loop at light 1.0 (loop_l100) and 0.15 (loop_l015), seed 0, no LiDAR, written into --data-dir
once. --frames is the simulated length and the most frames tracked. Reports per run: tracked
ratio, ATE RMSE (evo, SE3), keyframes, median time per stage; per sequence, the ATE ratio of
SuperPoint + lines to ORB points. SuperPoint weights: $SLSLAM_SUPERPOINT_MODEL, else
../shared/models (skipped without). Both SuperPoint runs of a sequence share a detection cache
(keyed on the image bytes); their inference and total columns use each image's real inference.
Writes tracking_ablation.md, tracking_ablation.json and each run's outputs (trajectory.tum,
metrics.json, ...) in <out>/<sequence>/<configuration>/.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from slslam.config import Config
from slslam.features import Keypoints, ModelError, SuperPoint
from slslam.sim import SimOptions, Simulator
from slslam.tracking import RunSummary, run_sequence
from slslam.tracking.run import STAGES

from common import RESULTS_DIR, SHARED_DATA, write_results

EUROC = SHARED_DATA / "euroc_v101_micro"  # real excerpt without ground truth inside
EUROC_GT = SHARED_DATA / "euroc_groundtruth_leftcam" / "V101_GT.txt"  # left camera, 20 Hz
SIM_LIGHTS = {"loop_l100": 1.0, "loop_l015": 0.15}
SEQUENCES = ("euroc", *SIM_LIGHTS)
CONFIGS = {  # name: (label, point front end, lines)
    "orb": ("ORB points", "orb", False),
    "sp": ("SuperPoint points", "superpoint", False),
    "orb_lines": ("ORB + lines", "orb", True),
    "sp_lines": ("SuperPoint + lines", "superpoint", True),
}
CAPTION = (
    "Median per-frame time [ms] per stage; inference = SuperPoint network (real inference of "
    "both images, cache hits excluded) or ORB detection. ATE: evo, SE3 alignment, tracked frames."
)


class CachedFrontend:
    """A point front end that runs ``detector`` once per distinct image (keyed on a hash of its
    bytes) and keeps the real time of each inference. ``extra_ms`` gets, per detect call, the real
    time minus what the call took: about 0 on a miss, the saved inference on a hit."""

    def __init__(self, detector: SuperPoint) -> None:
        self.detector = detector
        self.cache: dict[bytes, tuple[Keypoints, float]] = {}
        self.extra_ms: list[float] = []

    def detect(self, image: np.ndarray) -> Keypoints:
        start = time.perf_counter()
        key = hashlib.blake2b(image.tobytes(), digest_size=16)
        key.update(repr(image.shape).encode())
        digest = key.digest()
        entry = self.cache.get(digest)
        if entry is None:
            t0 = time.perf_counter()
            keypoints = self.detector.detect(image)
            entry = self.cache[digest] = (keypoints, (time.perf_counter() - t0) * 1e3)
        self.extra_ms.append(entry[1] - (time.perf_counter() - start) * 1e3)
        return entry[0]


def stage_medians(summary: RunSummary, extra_ms: list[float] | None) -> dict:
    """Median per-frame stage times [ms]; with ``extra_ms`` (two detect calls a frame) the
    inference and total times get the real inference back."""
    medians = dict(summary.metrics["median_ms"])
    results = summary.results
    if extra_ms is None or not results or len(extra_ms) != 2 * len(results):
        return medians
    extra = np.add(extra_ms[0::2], extra_ms[1::2])
    for stage in ("inference", "total"):
        values = [getattr(r.timings_ms, stage) + e for r, e in zip(results, extra, strict=True)]
        medians[stage] = float(statistics.median(values))
    return medians


def prepare(name: str, args: argparse.Namespace) -> tuple[Path, Path | None]:
    """The dataset folder of a sequence and its separate ground-truth file (None: its own)."""
    if name == "euroc":
        return args.euroc, args.euroc_groundtruth
    folder = args.data_dir / f"{name}_f{args.frames}_s0"
    manifest = folder / "manifest.json"
    if not manifest.is_file() or json.loads(manifest.read_text()).get("status") != "complete":
        print(f"simulating {name} ({args.frames} frames) into {folder}", flush=True)
        options = SimOptions(
            preset="loop", frames=args.frames, light=SIM_LIGHTS[name], lidar=False, seed=0
        )
        Simulator(options).write(folder, progress=False)
    return folder, None


def run_one(
    seq: str,
    name: str,
    dataset: Path,
    groundtruth: Path | None,
    config: Config,
    frontend: CachedFrontend | None,
    args: argparse.Namespace,
) -> dict:
    """One tracker run; its row of the report."""
    if frontend is not None:
        frontend.extra_ms.clear()
    start = time.perf_counter()
    summary = run_sequence(
        dataset,
        args.out / seq / name,
        config,
        max_frames=args.frames,
        progress=False,
        frontend=frontend,
        groundtruth=groundtruth,
    )
    metrics = json.loads((summary.out_dir / "metrics.json").read_text())
    return {
        "sequence": seq,
        "config": name,
        "frames": metrics["frames"],
        "tracked_ratio": metrics["tracked_ratio"],
        "ate_rmse_m": metrics.get("ape", {}).get("rmse"),
        "keyframes": metrics["keyframes"],
        "median_ms": stage_medians(summary, None if frontend is None else frontend.extra_ms),
        "wall_s": round(time.perf_counter() - start, 2),
        "out_dir": str(summary.out_dir),
        "metrics": metrics,
    }


def _fmt(value: float | None, spec: str) -> str:
    return "n/a" if value is None else format(value, spec)


def table(rows: list[dict]) -> str:
    head = ["sequence", "configuration", "frames", "tracked", "ATE RMSE [m]", "keyframes"]
    lines = [
        "| " + " | ".join(head + [s.replace("_", " ") for s in STAGES]) + " |",
        "|" + "---|" * 2 + "---:|" * (len(head) - 2 + len(STAGES)),
    ]
    for r in rows:
        cells = [
            r["sequence"],
            CONFIGS[r["config"]][0],
            str(r["frames"]),
            _fmt(r["tracked_ratio"], ".3f"),
            _fmt(r["ate_rmse_m"], ".4f"),
            str(r["keyframes"]),
            *(_fmt(r["median_ms"][s], ".1f") for s in STAGES),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def comparisons(rows: list[dict]) -> list[str]:
    """Per sequence: is SuperPoint + lines not worse than ORB points only (ATE ratio)?"""
    out = []
    for seq in dict.fromkeys(r["sequence"] for r in rows):
        by = {r["config"]: r for r in rows if r["sequence"] == seq}
        sp, orb = by.get("sp_lines"), by.get("orb")
        if sp is None or orb is None:
            continue
        tracked = f"tracked {sp['tracked_ratio']:.3f} vs {orb['tracked_ratio']:.3f}"
        if sp["ate_rmse_m"] is None or not orb["ate_rmse_m"]:
            out.append(f"{seq}: SuperPoint + lines vs ORB points: no ATE to compare ({tracked})")
            continue
        ratio = sp["ate_rmse_m"] / orb["ate_rmse_m"]
        verdict = "not worse" if ratio <= 1.0 else "worse"
        out.append(
            f"{seq}: SuperPoint + lines / ORB points ATE = {sp['ate_rmse_m']:.4f} / "
            f"{orb['ate_rmse_m']:.4f} m = {ratio:.2f} ({verdict}; {tracked})"
        )
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sequences", nargs="+", choices=SEQUENCES, default=list(SEQUENCES))
    parser.add_argument("--configs", default=",".join(CONFIGS), help="comma-separated subset")
    parser.add_argument("--frames", type=int, default=400, help="simulated / most tracked frames")
    parser.add_argument("--data-dir", type=Path, default=Path("/tmp/slslam_bench_data"))
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "tracking_ablation")
    parser.add_argument("--euroc", type=Path, default=EUROC)
    parser.add_argument("--euroc-groundtruth", type=Path, default=EUROC_GT)
    args = parser.parse_args()
    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    unknown = sorted(set(configs) - set(CONFIGS))
    if unknown:
        parser.error(f"unknown configurations {unknown} (choose from {', '.join(CONFIGS)})")

    skipped: list[str] = []
    cache_source: SuperPoint | None = None
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL") or str(
        SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
    )
    base = Config()
    if any(CONFIGS[c][1] == "superpoint" for c in configs):
        options = dataclasses.replace(base.features.superpoint, model_path=model)
        try:
            cache_source = SuperPoint(options)
            base = dataclasses.replace(
                base, features=dataclasses.replace(base.features, superpoint=options)
            )
        except (ModelError, OSError) as exc:
            skipped.append(f"SuperPoint configurations skipped: no usable weights ({exc})")
            print(skipped[-1])

    rows: list[dict] = []
    sp_image_ms: dict[str, float] = {}
    for seq in args.sequences:
        if seq == "euroc" and not args.euroc.exists():
            skipped.append(f"euroc skipped: {args.euroc} not available")
            print(skipped[-1])
            continue
        dataset, groundtruth = prepare(seq, args)
        cache = CachedFrontend(cache_source) if cache_source is not None else None
        for name in configs:
            label, point_frontend, lines = CONFIGS[name]
            frontend = cache if point_frontend == "superpoint" else None
            if point_frontend == "superpoint" and cache is None:
                continue
            config = dataclasses.replace(
                base,
                features=dataclasses.replace(base.features, point_frontend=point_frontend),
                tracking=dataclasses.replace(base.tracking, use_lines=lines),
            )
            try:  # one failing run is reported; the others still run
                row = run_one(seq, name, dataset, groundtruth, config, frontend, args)
            except Exception as exc:
                skipped.append(f"{seq} {label} failed: {type(exc).__name__}: {exc}")
                print(skipped[-1], flush=True)
                continue
            rows.append(row)
            print(
                f"{seq:10s} {label:18s} tracked {row['tracked_ratio']:.3f}  ATE "
                f"{_fmt(row['ate_rmse_m'], '.4f')} m  ({row['wall_s']:.0f} s)",
                flush=True,
            )
        if cache is not None and cache.cache:
            sp_image_ms[seq] = statistics.median(ms for _, ms in cache.cache.values())

    markdown = table(rows)
    notes = comparisons(rows)
    bullets = "".join(f"- {n}\n" for n in notes + skipped)
    text = f"{CAPTION}\n\n{markdown}\n\n{bullets}"
    print("\n" + text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "tracking_ablation.md").write_text(text)
    results = {
        "frames": args.frames,
        "sequences": args.sequences,
        "configs": configs,
        "superpoint_model": model if cache_source is not None else None,
        "superpoint_inference_ms_per_image_median": sp_image_ms,
        "runs": rows,
        "comparisons": notes,
        "skipped": skipped,
        "table": markdown,
    }
    path = write_results("tracking_ablation", results, args.out / "tracking_ablation.json")
    print(f"wrote {path} and {args.out / 'tracking_ablation.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
