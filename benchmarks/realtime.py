"""Real time on this machine: speed and accuracy of the tracker per front end, in one run.

    python benchmarks/realtime.py [--configs orb,orb_lines,xfeat,xfeat_lines,superpoint_lines,...]
        [--lights 1.0,0.15] [--frames 300] [--data-dir /tmp/slslam_realtime] [--out DIR]
        [--set features.xfeat.detection_threshold=0.02 ...]

Sequences: the simulated shaft-bottom loop (``slslam sim --preset loop``, 752 x 480 stereo at
20 Hz, seed 0, no dust, no LiDAR) at each light level, simulated once into --data-dir and reused.
The frames are decoded into memory before timing (a camera driver hands images over in memory).

Per configuration and light level, two passes over the same frames with the same tracker
settings (local mapping inline, so both passes give the same poses; the script checks it; with
``--mapping-thread`` both map on a thread of their own, ORB-SLAM3's layout, and the sequential
latency is the tracking thread's, what ORB-SLAM3 reports as its tracking time):

* sequential (``Tracker.track`` in a loop): per-frame latency, median and 95th percentile, from
  handing the pair over to having the pose; per-stage medians (the tracker's ``timings_ms``,
  the columns of frames.csv);
* pipelined (``Tracker.track_stream``, the default of ``slslam run``): throughput (frames / wall
  time), per-frame latency from the moment the worker takes the pair to the pose, CPU use
  (process CPU time / wall time: 2.0 is both cores busy) and the per-stage medians (the stage
  columns come from this pass with --no-sequential, which skips the sequential one);
* live (``--live``): the pipeline again, the frames handed over at the camera's rate (20 Hz):
  latency from each frame's due time to its pose, median, p95 and maximum. A pipeline that
  keeps up shows its processing delay; one that does not falls behind, and its latency grows
  through the run.

A second table says where the keyframes' time goes (pipelined pass): keyframes made, local
mapping's time per keyframe, the local BA's solve within it, and the solve's trust-region steps
per keyframe with those rejected (``MapStats.local_ba_*``).

XFeat and ORB configurations start from their presets (python/slslam/presets/), with --set on
top; both run their front end on the left image only, with the row search on the right
(``tracking.stereo_row_search``). Besides the default five, ``superpoint_lines_row`` runs
SuperPoint that way, and ``*_both`` configurations run ORB or XFeat on both images (descriptor
stereo matching), for side-by-side ratios.

Accuracy: ATE RMSE of the frames with an estimated pose (evo, SE3 alignment) against the
simulator's ground truth, the tracked ratio and the keyframes. Learned configurations are
compared with SuperPoint + lines at the same light level when that ran (ATE ratio).

The machine is shared: the 1-minute load average (os.getloadavg) is recorded before and after
every pass; read speeds as ratios between configurations of one run. Machines differ too (the
sessions' by about 2x): a speed reference, OpenCV's ORB on the first left image of the first
light's loop (common.speed_reference_ms; the simulator makes the same image everywhere), is timed
before and after the runs, to put runs of different machines side by side.

SuperPoint runs when its weights are found ($SLSLAM_SUPERPOINT_MODEL or
../shared/models/superpoint_v1/superpoint_v1.onnx next to the repository), and is skipped with a
note otherwise. Writes realtime.json and realtime.md into --out (default benchmarks/results).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

from slslam.config import Config, config_from_dict, merged
from slslam.datasets import EurocSequence
from slslam.eval.report import evaluate
from slslam.features.superpoint import ENV_MODEL
from slslam.sim import SimOptions, Simulator
from slslam.tracking import Tracker
from slslam.tracking.run import tracked_trajectory

from common import (
    RESULTS_DIR,
    machine_line,
    parse_overrides,
    speed_reference_ms,
    write_results,
)

SHARED_SUPERPOINT = (
    Path(__file__).resolve().parents[1].parent
    / "shared"
    / "models"
    / "superpoint_v1"
    / "superpoint_v1.onnx"
)
ROW_SEARCH = {"tracking": {"stereo_row_search": True}}
BOTH_IMAGES = {"tracking": {"stereo_row_search": False}}
CONFIGS = {  # name: (label, point front end, lines, settings under --set)
    # ORB's preset (python/slslam/presets/orb.yaml): left image only, the row search on the right
    "orb": ("ORB points", "orb", False, {}),
    "orb_lines": ("ORB + lines", "orb", True, {}),
    # before ORB's preset: ORB on both images, descriptor stereo matching
    "orb_both": ("ORB points, both images", "orb", False, BOTH_IMAGES),
    "orb_lines_both": ("ORB + lines, both images", "orb", True, BOTH_IMAGES),
    "xfeat": ("XFeat points", "xfeat", False, {}),
    "xfeat_lines": ("XFeat + lines", "xfeat", True, {}),
    # the preset before the row search: the network on both images, descriptor stereo matching
    "xfeat_lines_both": ("XFeat + lines, network on both images", "xfeat", True, BOTH_IMAGES),
    "superpoint_lines": ("SuperPoint + lines", "superpoint", True, {}),
    "superpoint_lines_row": (
        "SuperPoint + lines, left + row search",
        "superpoint",
        True,
        ROW_SEARCH,
    ),
}
#: The configurations run unless --configs says otherwise.
DEFAULT_CONFIGS = ("orb", "orb_lines", "xfeat", "xfeat_lines", "superpoint_lines")
STAGES = (
    "inference",
    "line_extraction",
    "stereo_matching",
    "matching",
    "optimisation",
    "mapping",
    "total",
)


def superpoint_model() -> str | None:
    env = os.environ.get(ENV_MODEL)
    if env and Path(env).is_file():
        return env
    return str(SHARED_SUPERPOINT) if SHARED_SUPERPOINT.is_file() else None


def simulate(light: float, frames: int, data_dir: Path) -> Path:
    out = data_dir / f"loop_l{round(light * 100):03d}"
    if (out / "mav0").is_dir() and len(EurocSequence(out)) >= frames:
        return out
    print(f"simulating the loop at light {light} ({frames} frames) into {out}", flush=True)
    Simulator(SimOptions(preset="loop", light=light, frames=frames, lidar=False)).write(
        out, progress=False
    )
    return out


def config_for(
    name: str, overrides: dict, model: str | None, mapping_thread: bool = False
) -> Config:
    _, frontend, lines, settings = CONFIGS[name]
    # the front end's preset (XFeat's: python/slslam/presets/xfeat.yaml) under the overrides
    base = config_from_dict(merged(settings, overrides), point_frontend=frontend)
    superpoint = dataclasses.replace(base.features.superpoint, model_path=model)
    features = dataclasses.replace(base.features, superpoint=superpoint)
    tracking = dataclasses.replace(base.tracking, use_lines=lines, sequential=not mapping_thread)
    return dataclasses.replace(base, features=features, tracking=tracking)


def percentiles(values: list[float]) -> dict[str, float]:
    a = np.asarray(values)
    return {"median": float(np.median(a)), "p95": float(np.percentile(a, 95))}


def sequential_pass(sequence: EurocSequence, frames: list, config: Config) -> dict:
    load_before = os.getloadavg()[0]
    latency, stages = [], {s: [] for s in STAGES}
    with Tracker(sequence.camera, config) as tracker:
        for left, right, t in frames:
            start = time.perf_counter()
            result = tracker.track(left, right, t)
            latency.append((time.perf_counter() - start) * 1e3)
            for s in STAGES:
                stages[s].append(getattr(result.timings_ms, s))
        frontend = tracker.frontend_name
        providers = getattr(tracker.frontend, "providers", None)
    return {
        "frontend": frontend,
        "providers": providers,
        "latency_ms": percentiles(latency),
        "stage_median_ms": {s: float(np.median(v)) for s, v in stages.items()},
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
        "poses": tracker.trajectory()[1],
    }


def pipelined_pass(sequence: EurocSequence, frames: list, config: Config, gt) -> dict:
    load_before = os.getloadavg()[0]
    taken: list[float] = []

    def feed():
        for frame in frames:
            taken.append(time.perf_counter())
            yield frame

    latency = []
    with Tracker(sequence.camera, config) as tracker:
        cpu0, wall0 = time.process_time(), time.perf_counter()
        for result in tracker.track_stream(feed(), pipeline=True):
            latency.append((time.perf_counter() - taken[result.index]) * 1e3)
        # Finishes local mapping (threaded mode: the keyframes still queued) inside the timed
        # span, so a mapping backlog cannot flatter the throughput.
        tracker.close()
        wall = time.perf_counter() - wall0
        cpu = time.process_time() - cpu0
        results = tracker.results
        map_data = tracker.map()
    stages = {s: float(np.median([getattr(r.timings_ms, s) for r in results])) for s in STAGES}
    estimate = tracked_trajectory(results)
    ate = None
    if estimate is not None:
        evaluation = evaluate(estimate, gt, align="se3", rpe_delta=None, plot=False)
        ate = float(evaluation.summary()["ape"]["rmse"])
    tracked = sum(r.tracked for r in results) / len(results)
    return {
        "throughput_fps": len(frames) / wall,
        "wall_s": wall,
        "latency_ms": percentiles(latency),
        "cpu_cores": cpu / wall,
        "stage_median_ms": stages,
        "ate_rmse_m": ate,
        "tracked_ratio": tracked,
        "keyframes": map_data.keyframes,
        "local_ba_interrupted": map_data.stats.local_ba_interrupted,
        "local_mapping": {
            k: getattr(map_data.stats, k)
            for k in (
                "keyframes_processed",
                "local_mapping_ms",
                "local_ba_solve_ms",
                "local_ba_iterations",
                "local_ba_rejected_steps",
            )
        },
        "maps": map_data.maps,
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
        "poses": np.array([r.T_world_cam for r in results]),
    }


def live_pass(sequence: EurocSequence, frames: list, config: Config) -> dict:
    """The frames handed over at the camera's rate (their timestamps from the pass's start, as a
    driver delivers them), the pipeline as ``slslam run`` drives it. Latency from each frame's
    due time to its pose: a frame the pipeline could not take yet waits at the source, and that
    wait counts. A pipeline slower than the camera falls behind, and the latency grows through
    the run (its maximum is then the last frame's)."""
    load_before = os.getloadavg()[0]
    t_first = frames[0][2]
    due: list[float] = []

    def feed():
        start = time.perf_counter()
        for left, right, t in frames:
            due.append(start + (t - t_first))
            wait = due[-1] - time.perf_counter()
            if wait > 0.0:
                time.sleep(wait)
            yield left, right, t

    latency = []
    with Tracker(sequence.camera, config) as tracker:
        for result in tracker.track_stream(feed(), pipeline=True):
            latency.append((time.perf_counter() - due[result.index]) * 1e3)
    camera_hz = (len(frames) - 1) / (frames[-1][2] - t_first)
    return {
        "camera_hz": camera_hz,
        "latency_ms": {**percentiles(latency), "max": float(np.max(latency))},
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
    }


def run_one(
    name: str,
    light: float,
    data: Path,
    n: int,
    overrides: dict,
    model,
    sequential: bool,
    mapping_thread: bool = False,
    live: bool = False,
) -> dict:
    sequence = EurocSequence(data)
    frames = [(f.left, f.right, f.t_ns * 1e-9) for f in (sequence[i] for i in range(n))]
    gt = sequence.groundtruth(frame="rectified")
    # With --mapping-thread both passes map on a thread of their own (ORB-SLAM3's layout): the
    # sequential latency is then the tracking thread's, as ORB-SLAM3 reports its tracking time;
    # the poses depend on thread timing, so the two passes' poses are not compared.
    config = config_for(name, overrides, model, mapping_thread)
    seq = sequential_pass(sequence, frames, config) if sequential else None
    pipe = pipelined_pass(sequence, frames, config, gt)
    live_result = live_pass(sequence, frames, config) if live else None
    poses = pipe.pop("poses")
    same = None if seq is None or mapping_thread else bool(np.array_equal(seq.pop("poses"), poses))
    if seq is not None:
        seq.pop("poses", None)
    return {
        "label": CONFIGS[name][0],
        "light": light,
        "frames": n,
        "sequential": seq,
        "pipelined": pipe,
        "live": live_result,
        "same_poses": same,
    }


def fmt(x, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def live_cell(live: dict | None) -> str:
    if live is None:
        return " - |"
    ms = live["latency_ms"]
    return f" {ms['median']:.1f} / {ms['p95']:.1f} / {ms['max']:.1f} |"


def table(runs: list[dict]) -> str:
    head = (
        "| configuration | light | tracked | ATE [m] | vs SuperPoint + lines "
        "| latency median / p95 [ms] | pipelined [frames/s] "
        "| pipelined latency median / p95 [ms] | CPU [cores] "
        "| inference | lines | stereo | matching | optimisation | mapping | load 1 min |"
    )
    live = any(r.get("live") for r in runs)
    if live:
        head += " live latency median / p95 / max [ms] |"
    lines = [head, "|---|---:" + "|---:" * (15 if live else 14) + "|"]
    reference = {
        r["light"]: r["pipelined"]["ate_rmse_m"]
        for r in runs
        if r["label"] == CONFIGS["superpoint_lines"][0]
    }
    for r in runs:
        s, p = r["sequential"], r["pipelined"]
        if s is None:  # --no-sequential: stage times of the pipelined pass, no plain latency
            s = {
                "latency_ms": {"median": float("nan"), "p95": float("nan")},
                "stage_median_ms": p["stage_median_ms"],
                "load_before": p["load_before"],
            }
        st = s["stage_median_ms"]
        ref = reference.get(r["light"])
        ratio = p["ate_rmse_m"] / ref if ref and p["ate_rmse_m"] is not None else None
        lines.append(
            f"| {r['label']} | {r['light']} | {p['tracked_ratio']:.3f} "
            f"| {fmt(p['ate_rmse_m'], '.4f')} | {fmt(ratio, '.2f')} "
            f"| {s['latency_ms']['median']:.1f} / {s['latency_ms']['p95']:.1f} "
            f"| {p['throughput_fps']:.1f} "
            f"| {p['latency_ms']['median']:.1f} / {p['latency_ms']['p95']:.1f} "
            f"| {p['cpu_cores']:.2f} "
            + " ".join(f"| {st[k]:.1f}" for k in STAGES[:-1])
            + f" | {s['load_before']:.1f}-{p['load_after']:.1f} |"
            + (live_cell(r.get("live")) if live else "")
        )
    return "\n".join(lines)


def keyframe_table(runs: list[dict]) -> str:
    """Where the keyframes' time goes (pipelined pass): per keyframe local mapping processed, its
    time, the local BA's solve within it, and the solve's trust-region steps (5 + 10 at most)
    with those rejected (each a linear solve that bought nothing)."""
    lines = [
        "| configuration | light | keyframes / frames | local mapping [ms/keyframe] "
        "| of which the BA solve | BA steps / keyframe | of which rejected |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in runs:
        p = r["pipelined"]
        m = p["local_mapping"]
        n = max(m["keyframes_processed"], 1)
        lines.append(
            f"| {r['label']} | {r['light']} | {m['keyframes_processed']} / {r['frames']} "
            f"| {m['local_mapping_ms'] / n:.1f} | {m['local_ba_solve_ms'] / n:.1f} "
            f"| {m['local_ba_iterations'] / n:.1f} | {m['local_ba_rejected_steps'] / n:.1f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--configs",
        default=",".join(DEFAULT_CONFIGS),
        help=f"comma-separated, of: {', '.join(CONFIGS)}",
    )
    parser.add_argument("--lights", default="1.0,0.15")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--data-dir", type=Path, default=Path("/tmp/slslam_realtime"))
    parser.add_argument("--out", type=Path, default=RESULTS_DIR)
    parser.add_argument("--name", default="realtime", help="result file stem")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="config override"
    )
    parser.add_argument(
        "--no-sequential",
        action="store_true",
        help="skip the sequential pass (accuracy and throughput only, half the time)",
    )
    parser.add_argument(
        "--mapping-thread",
        action="store_true",
        help="both passes with local mapping on its own thread (tracking.sequential=false, as "
        "ORB-SLAM3 and `slslam run --realtime`) instead of inline: the sequential latency is "
        "then the tracking thread's, what ORB-SLAM3 reports as its tracking time",
    )
    parser.add_argument(
        "--live",
        action="store_true",
        help="also a live pass: the frames handed over at the camera's rate (20 Hz), latency "
        "from each frame's due time to its pose (what a robot sees; a pipeline slower than the "
        "camera falls behind and the latency grows)",
    )
    args = parser.parse_args(argv)
    configs = [c for c in args.configs.split(",") if c]
    unknown = sorted(set(configs) - set(CONFIGS))
    if unknown:
        parser.error(f"unknown configuration {unknown[0]!r} (known: {', '.join(CONFIGS)})")
    if args.frames < 10:
        parser.error("--frames must be >= 10")
    lights = [float(x) for x in args.lights.split(",") if x]
    overrides = parse_overrides(args.set)
    model = superpoint_model()
    notes = []
    for name in [c for c in configs if CONFIGS[c][1] == "superpoint"]:
        if model is None:
            configs.remove(name)
            notes.append(
                f"{CONFIGS[name][0]} skipped: no weights ({ENV_MODEL} or {SHARED_SUPERPOINT})"
            )
            print(notes[-1])
    # (the first left image of the first light's loop: the simulator makes the same bytes on
    # every machine)
    reference_image = EurocSequence(simulate(lights[0], args.frames, args.data_dir))[0].left
    reference_ms = {"before": speed_reference_ms(reference_image)}
    runs = []
    for light in lights:
        data = simulate(light, args.frames, args.data_dir)
        for name in configs:
            start = time.perf_counter()
            r = run_one(
                name,
                light,
                data,
                args.frames,
                overrides,
                model,
                not args.no_sequential,
                args.mapping_thread,
                args.live,
            )
            runs.append(r)
            p, s = r["pipelined"], r["sequential"]
            latency = "-" if s is None else f"{s['latency_ms']['median']:.1f}"
            if r["live"] is not None:
                latency += f" (live {r['live']['latency_ms']['median']:.1f})"
            print(
                f"{r['label']:20s} light {light:4.2f}: ATE {fmt(p['ate_rmse_m'], '.4f')} m, "
                f"tracked {p['tracked_ratio']:.3f}, latency {latency} ms "
                f"median, pipelined {p['throughput_fps']:.1f} frames/s, CPU {p['cpu_cores']:.2f}, "
                f"same poses {r['same_poses']} [{time.perf_counter() - start:.0f} s]",
                flush=True,
            )
    reference_ms["after"] = speed_reference_ms(reference_image)
    text = (
        machine_line()
        + "\n\nSpeed reference (OpenCV's ORB on the first left image, median of 30 calls): "
        + f"{reference_ms['before']:.2f} ms before the runs, {reference_ms['after']:.2f} ms after"
        + "\n\n"
        + table(runs)
        + "\n\n"
        + keyframe_table(runs)
    )
    if notes:
        text += "\n\n" + "\n".join(notes)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"{args.name}.md").write_text(text + "\n")
    path = write_results(
        args.name,
        {
            "frames": args.frames,
            "lights": lights,
            "overrides": overrides,
            "mapping_thread": args.mapping_thread,
            "live": args.live,
            "cpu_count": os.cpu_count(),
            "speed_reference_ms": reference_ms,
            "runs": runs,
            "notes": notes,
        },
        args.out / f"{args.name}.json",
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
