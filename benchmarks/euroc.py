"""EuRoC stereo benchmark: slslam per configuration against the published ORB-SLAM3 / SL-SLAM ATE.

    python benchmarks/euroc.py --root DIR [--configs orb_lines,orb] [--frames N] [--out DIR]
        [--groundtruth-dir DIR] [--published FILE]
        [--orbslam3 BINARY [--orbslam3-vocabulary ORBvoc.txt] [--orbslam3-settings EuRoC.yaml]]

Finds every EuRoC ASL sequence under DIR (a folder holding ``mav0/``, up to two levels down: full
sequences MH_01_easy ... V2_03_difficult, or the excerpt ``euroc_v101_micro``), runs
``slslam.tracking.run_sequence`` once per configuration, and prints one table: sequence, frames,
the published ATE columns of ``published_ate.yaml`` (ORB-SLAM3's paper; ORB-SLAM3 and SL-SLAM as
run in the SL-SLAM paper, SPEC A7), then per configuration slslam's ATE, tracked ratio and
frames/s. Sequences the papers report but that were not found under DIR are listed too, with "-"
in the measured columns, so the published columns are always in view.

Scoring, the same code for every estimate (slslam's and ORB-SLAM3's): evo APE, translation part,
RMSE in metres, after an SE3 Umeyama alignment (rotation and translation, no scale: stereo is
metric), over the frames with an estimated pose, as the SL-SLAM paper states (EVO, APE) and as
ORB-SLAM3 evaluates stereo. Ground truth is the left camera (cam0) in the Vicon / Leica world:
``<groundtruth-dir>/<MH01|V101|...>_GT.txt`` when present (ORB-SLAM3's evaluation files, resampled
at the camera times; their quaternion columns hold the conjugate of q_world_cam, which is undone
here), else the sequence's own ``state_groundtruth_estimate0`` composed with cam0's ``T_BS``.
Tracked ratio: frames with an estimated pose / frames run. frames/s: frames / the sum of the
per-frame ``total`` times (the tracking thread; with ``tracking.sequential`` the inline local
mapping is in it).

``--orbslam3 BINARY`` runs a user's ORB-SLAM3 ``stereo_euroc`` (arguments: vocabulary, settings,
sequence folder, times file, output name) on the same sequences and frames and scores its
``f_<name>.txt`` with the code above. Writes euroc.md, euroc.json and each run's outputs
(trajectory.tum, metrics.json, ...) in ``<out>/<sequence>/<configuration>/``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from evo.core.trajectory import PoseTrajectory3D

from slslam.config import Config, default_config
from slslam.datasets import EurocSequence, is_euroc, read_trajectory
from slslam.errors import InputError
from slslam.eval.report import evaluate
from slslam.tracking import run_sequence

from common import RESULTS_DIR, SHARED_DATA, load_published_sources, write_results

HERE = Path(__file__).resolve().parent
PUBLISHED = HERE / "published_ate.yaml"
#: EuRoC's eleven sequences in the papers' order.
SEQUENCES = tuple(
    [f"MH_0{i}" for i in range(1, 6)]
    + [f"V1_0{i}" for i in range(1, 4)]
    + [f"V2_0{i}" for i in range(1, 4)]
)
CONFIGS = {  # name: (label, point front end, lines)
    "orb": ("ORB points", "orb", False),
    "orb_lines": ("ORB + lines", "orb", True),
    "sp": ("SuperPoint points", "superpoint", False),
    "sp_lines": ("SuperPoint + lines", "superpoint", True),
    "xfeat_lines": ("XFeat + lines", "xfeat", True),
}
SEQUENCE_NAME = re.compile(r"(mh|v1|v2)_?(0[1-5])", re.IGNORECASE)


# -- sequences and ground truth ---------------------------------------------------------------
def sequence_key(name: str) -> str | None:
    """``MH_01`` ... ``V2_03`` from a folder name (``MH_01_easy``, ``V101``, ``euroc_v101_micro``),
    None when the name says nothing."""
    match = SEQUENCE_NAME.search(name)
    if match is None:
        return None
    key = f"{match.group(1).upper()}_{match.group(2)}"
    return key if key in SEQUENCES else None


def find_sequences(root: Path) -> list[tuple[str, Path]]:
    """(name, folder) of every EuRoC ASL sequence at ``root`` or up to two levels below it; the
    name is the EuRoC key when the folder name gives one (``V1_01 (euroc_v101_micro)``)."""
    candidates = [root, *sorted(p for p in root.glob("*") if p.is_dir())]
    candidates += sorted(p for p in root.glob("*/*") if p.is_dir() and p.name != "mav0")
    found: list[tuple[str, Path]] = []
    for folder in candidates:
        if folder.name == "mav0" or not (folder / "mav0").is_dir() or not is_euroc(folder):
            continue
        key = sequence_key(folder.name)
        canonical = key is not None and folder.name.upper().startswith(key)
        name = key if canonical else f"{key} ({folder.name})" if key else folder.name
        found.append((name, folder))
    order = {k: i for i, k in enumerate(SEQUENCES)}
    return sorted(found, key=lambda item: (order.get(item[0][:5], 99), item[0]))


def leftcam_groundtruth(path: Path) -> PoseTrajectory3D:
    """ORB-SLAM3's ``EuRoC_left_cam/<seq>_GT.txt``: positions of cam0 in the world, quaternion
    columns holding the conjugate of q_world_cam (checked against the body ground truth composed
    with cam0's T_BS, see shared/data/euroc_groundtruth_leftcam/README.txt). Returned as
    ``T_world_cam0``."""
    traj = read_trajectory(path, "euroc")
    q_wxyz = traj.orientations_quat_wxyz * np.array([1.0, -1.0, -1.0, -1.0])
    return PoseTrajectory3D(traj.positions_xyz, q_wxyz, traj.timestamps)


def groundtruth_for(name: str, folder: Path, gt_dir: Path | None) -> PoseTrajectory3D | None:
    key = sequence_key(name)
    if gt_dir is not None and key is not None:
        path = gt_dir / f"{key.replace('_', '')}_GT.txt"
        if path.is_file():
            return leftcam_groundtruth(path)
    sequence = EurocSequence(folder)
    return sequence.groundtruth("cam0") if sequence.groundtruth_path is not None else None


def load_published(path: Path) -> dict:
    """The published columns: ``{source: {label, citation, values {seq: m}, average}}``; a bad
    file raises InputError naming the file and the key (common.load_published_sources)."""
    return load_published_sources(path, _check_ate_values)


def _check_ate_values(where: str, values) -> None:
    if not isinstance(values, dict):
        raise InputError(None, f"{where}: expected a mapping sequence -> ATE [m]")
    for seq, value in values.items():
        if seq not in SEQUENCES:
            raise InputError(None, f"{where}.{seq}: unknown sequence ({SEQUENCES})")
        if not isinstance(value, int | float) or not 0 <= value < 100:
            raise InputError(None, f"{where}.{seq}: {value!r} is not an ATE in metres")


# -- runs -------------------------------------------------------------------------------------
def make_configs(names: list[str]) -> dict[str, Config]:
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL") or str(
        SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
    )
    configs = {}
    for name in names:
        _, frontend, lines = CONFIGS[name]
        base = default_config(frontend)  # with the front end's preset (XFeat's)
        features = base.features
        if frontend == "superpoint":
            if not Path(model).is_file():
                print(f"{name} skipped: no SuperPoint weights ({model})")
                continue
            features = dataclasses.replace(
                features, superpoint=dataclasses.replace(features.superpoint, model_path=model)
            )
        configs[name] = dataclasses.replace(
            base, features=features, tracking=dataclasses.replace(base.tracking, use_lines=lines)
        )
    return configs


def ate_rmse(estimate: Path, gt: PoseTrajectory3D | None) -> float | None:
    """APE translation RMSE [m] after SE3 Umeyama alignment (None without ground truth or with
    fewer than 3 matched poses)."""
    if gt is None or not estimate.is_file() or estimate.stat().st_size == 0:
        return None
    est = read_trajectory(estimate, "tum")
    if est.num_poses < 3:
        return None
    return float(evaluate(est, gt, align="se3", rpe_delta=None, plot=False).ape.stats["rmse"])


def run_slslam(folder: Path, config: Config, out: Path, frames: int | None, gt) -> dict:
    summary = run_sequence(folder, out, config, max_frames=frames, progress=True)
    totals_s = sum(r.timings_ms.total for r in summary.results) / 1e3
    n = len(summary.results)
    return {
        "frames": n,
        "ate_m": ate_rmse(out / "trajectory.tum", gt),
        "tracked_ratio": summary.metrics["tracked_ratio"],
        "fps": n / totals_s if totals_s > 0 else None,
        "keyframes": summary.metrics.get("keyframes"),
        "maps": summary.metrics.get("maps"),
    }


def run_orbslam3(args, folder: Path, out: Path, frames: int | None, gt) -> dict:
    """A user's ORB-SLAM3 ``stereo_euroc`` on the same frames, scored like slslam."""
    sequence = EurocSequence(folder)
    stamps = sequence.timestamps_ns[: frames or None]
    out.mkdir(parents=True, exist_ok=True)
    times = out / "times.txt"
    times.write_text("".join(f"{t}\n" for t in stamps), encoding="ascii")
    command = [
        str(args.orbslam3),
        str(args.orbslam3_vocabulary),
        str(args.orbslam3_settings),
        str(sequence.root.parent),
        str(times),
        "orbslam3",
    ]
    start = time.perf_counter()
    with (out / "orbslam3.log").open("w") as log_file:
        code = subprocess.run(
            command, cwd=out, stdout=log_file, stderr=subprocess.STDOUT
        ).returncode
    wall = time.perf_counter() - start
    raw = out / "f_orbslam3.txt"
    if code != 0 or not raw.is_file():
        print(f"ORB-SLAM3 failed on {folder} (exit {code}); see {out / 'orbslam3.log'}")
        return {"frames": len(stamps), "ate_m": None, "tracked_ratio": 0.0, "fps": None}
    estimate = out / "trajectory.tum"
    to_tum(raw, estimate)
    posed = read_trajectory(estimate, "tum").num_poses if estimate.stat().st_size else 0
    return {
        "frames": len(stamps),
        "ate_m": ate_rmse(estimate, gt),
        "tracked_ratio": posed / len(stamps),
        "fps": len(stamps) / wall,  # wall time of the whole binary, start-up included
    }


def to_tum(raw: Path, out: Path) -> Path:
    """ORB-SLAM3's EuRoC-style ``f_*.txt`` (t x y z qx qy qz qw, t in ns or s) as TUM seconds."""
    rows = np.loadtxt(raw, ndmin=2)
    if rows.shape[1] != 8:
        raise InputError(raw, f"expected 8 columns (t x y z qx qy qz qw), got {rows.shape[1]}")
    if len(rows) and rows[0, 0] > 1e12:  # nanoseconds
        rows[:, 0] *= 1e-9
    np.savetxt(out, rows, fmt="%.9f")
    return out


# -- the table --------------------------------------------------------------------------------
def _fmt(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value:.{digits}f}"


def table(rows: list[dict], published: dict, runs: list[str]) -> str:
    head = ["sequence", "frames"] + [p["label"] for p in published.values()]
    for run in runs:
        label = CONFIGS[run][0] if run in CONFIGS else "ORB-SLAM3 (this machine)"
        head += [f"{label} ATE", f"{label} tracked", f"{label} frames/s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row["sequence"], str(row.get("frames") or "-")]
        key = sequence_key(row["sequence"])
        cells += [_fmt(p["values"].get(key)) for p in published.values()]
        for run in runs:
            measured = row["runs"].get(run, {})
            cells += [
                _fmt(measured.get("ate_m"), 4),
                _fmt(measured.get("tracked_ratio"), 2),
                _fmt(measured.get("fps"), 1),
            ]
        lines.append("| " + " | ".join(cells) + " |")
    averages = [_fmt(p.get("average")) for p in published.values()]
    lines.append("| average (paper) | - | " + " | ".join(averages + ["-"] * 3 * len(runs)) + " |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", type=Path, required=True, help="folder holding EuRoC sequences")
    parser.add_argument("--configs", default="orb_lines", help=f"comma list of {list(CONFIGS)}")
    parser.add_argument("--frames", type=int, default=0, help="run the first N frames (0 = all)")
    parser.add_argument("--out", type=Path, default=Path("euroc_benchmark"))
    parser.add_argument(
        "--groundtruth-dir",
        type=Path,
        default=None,
        help="left-camera ground truth <SEQ>_GT.txt files "
        "(default: ROOT/euroc_groundtruth_leftcam when present)",
    )
    parser.add_argument("--published", type=Path, default=PUBLISHED)
    parser.add_argument("--orbslam3", type=Path, help="a user's ORB-SLAM3 stereo_euroc binary")
    parser.add_argument(
        "--orbslam3-vocabulary",
        type=Path,
        help="ORBvoc.txt (default: Vocabulary/ORBvoc.txt of the binary's ORB-SLAM3 tree)",
    )
    parser.add_argument(
        "--orbslam3-settings", type=Path, help="EuRoC.yaml (default: next to the binary)"
    )
    parser.add_argument(
        "--json",
        type=Path,
        default=None,
        help="results file (default benchmarks/results/euroc.json)",
    )
    args = parser.parse_args()

    names = [c.strip() for c in args.configs.split(",") if c.strip()]
    unknown = sorted(set(names) - set(CONFIGS))
    if unknown:
        parser.error(f"unknown configurations {unknown} (choose from {', '.join(CONFIGS)})")
    if not args.root.is_dir():
        parser.error(f"--root {args.root}: folder not found")
    try:
        published = load_published(args.published)
    except InputError as exc:
        parser.error(str(exc))
    if args.orbslam3 is not None:
        tree = (
            args.orbslam3.resolve().parents[2] if len(args.orbslam3.resolve().parents) > 2 else None
        )
        args.orbslam3_vocabulary = args.orbslam3_vocabulary or (
            tree / "Vocabulary" / "ORBvoc.txt" if tree else None
        )
        args.orbslam3_settings = args.orbslam3_settings or args.orbslam3.parent / "EuRoC.yaml"
        for flag, path in (
            ("--orbslam3", args.orbslam3),
            ("--orbslam3-vocabulary", args.orbslam3_vocabulary),
            ("--orbslam3-settings", args.orbslam3_settings),
        ):
            if path is None or not Path(path).is_file():
                parser.error(f"{flag} {path}: file not found")
    gt_dir = args.groundtruth_dir or args.root / "euroc_groundtruth_leftcam"
    gt_dir = gt_dir if gt_dir.is_dir() else None
    configs = make_configs(names)
    runs = list(configs) + (["orbslam3"] if args.orbslam3 else [])
    frames = args.frames or None

    sequences = find_sequences(args.root)
    print(
        f"{len(sequences)} EuRoC sequence(s) under {args.root}: "
        + ", ".join(f"{n} ({p})" for n, p in sequences)
    )
    rows: list[dict] = []
    for name, folder in sequences:
        gt = groundtruth_for(name, folder, gt_dir)
        slug = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_")
        row: dict = {
            "sequence": name,
            "path": str(folder),
            "groundtruth": gt is not None,
            "runs": {},
        }
        for run, config in configs.items():
            print(f"{name}: slslam {CONFIGS[run][0]}")
            row["runs"][run] = run_slslam(folder, config, args.out / slug / run, frames, gt)
        if args.orbslam3:
            print(f"{name}: ORB-SLAM3 {args.orbslam3}")
            row["runs"]["orbslam3"] = run_orbslam3(
                args, folder, args.out / slug / "orbslam3", frames, gt
            )
        row["frames"] = max((r["frames"] for r in row["runs"].values()), default=None)
        rows.append(row)
    listed = {sequence_key(r["sequence"]) for r in rows}
    for key in SEQUENCES:  # the papers' sequences that were not found, for their columns
        if key not in listed and any(key in p["values"] for p in published.values()):
            rows.append({"sequence": key, "runs": {}, "frames": None})

    text = table(rows, published, runs)
    notes = [
        "ATE: evo APE translation RMSE [m], SE3 Umeyama alignment, left-camera ground truth, "
        "frames with an estimated pose. tracked: share of frames with an estimated pose. "
        "frames/s: frames / summed per-frame tracking time (ORB-SLAM3: wall time of the binary).",
        *(
            f"{p['label']}: {' '.join(p['citation'].split())}"
            + (f" {' '.join(p['note'].split())}" if p.get("note") else "")
            + ("" if p["values"] else " (no numbers yet)")
            for p in published.values()
        ),
    ]
    if args.frames:
        notes.append(f"First {args.frames} frames of each sequence only.")
    print(text)
    for note in notes:
        print(f"- {note}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "euroc.md").write_text(text + "\n\n" + "\n".join(f"- {n}" for n in notes) + "\n")
    (args.out / "euroc.json").write_text(json.dumps({"rows": rows, "notes": notes}, indent=2))
    path = write_results(
        "euroc", {"rows": rows, "notes": notes}, args.json or RESULTS_DIR / "euroc.json"
    )
    print(f"wrote {args.out / 'euroc.md'}, {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
