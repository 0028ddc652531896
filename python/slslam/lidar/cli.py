"""``slslam lidar``: LiDAR(-inertial) SLAM on a sequence folder."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from slslam.terminal import stderr_console, stdout_console

lidar_app = typer.Typer(
    help="LiDAR-inertial SLAM: deskew, scan-to-map odometry with IMU smoothing, Scan Context "
    "loops, keyframe pose graph, map measurement.",
    no_args_is_help=True,
)


@lidar_app.command("run")
def lidar_run_command(
    dataset: Annotated[
        Path,
        typer.Argument(
            help="Sequence folder: the simulator's ASL layout (mav0/lidar0 + imu0, from "
            "`slslam sim`), a KITTI odometry sequence (velodyne/*.bin, times.txt; LiDAR only), "
            "or a ROS bag (ROS1 .bag, ROS2 folder; sensor_msgs/PointCloud2 + Imu, no ROS "
            "needed; the LiDAR is taken to sit at the IMU)."
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            "-o",
            help="Output folder: trajectory.tum (loop-closed), trajectory_odometry.tum, map.ply "
            "(voxelised, world frame), metrics.json (evo APE/RPE when there is ground truth, "
            "loops, timing per stage, map measurement), trajectory.png.",
        ),
    ],
    no_loops: Annotated[
        bool, typer.Option("--no-loops", help="Odometry only: no Scan Context loop closure.")
    ] = False,
    no_imu: Annotated[
        bool, typer.Option("--no-imu", help="Ignore the IMU: LiDAR-only odometry.")
    ] = False,
    no_deskew: Annotated[
        bool, typer.Option("--no-deskew", help="Do not motion-compensate the sweeps.")
    ] = False,
    max_sweeps: Annotated[
        int | None, typer.Option(help="Process only the first N sweeps.", min=2)
    ] = None,
    map_voxel: Annotated[
        float, typer.Option(help="Voxel of the written map in metres.", min=0.01)
    ] = 0.1,
    progress: Annotated[bool, typer.Option(help="Show a progress bar.")] = True,
    lidar_topic: Annotated[
        str | None,
        typer.Option(help="ROS bag: the PointCloud2 topic (default: the bag's only one)."),
    ] = None,
    imu_topic: Annotated[
        str | None, typer.Option(help="ROS bag: the Imu topic (default: the bag's only one).")
    ] = None,
) -> None:
    """Run LiDAR(-inertial) SLAM on DATASET and write its results into --out.

    Sweeps are deskewed with the per-point times (point_time/<t_ns>.bin in the simulator's
    layout) and the IMU-predicted motion, registered point-to-plane against a bounded voxel
    map from the IMU prediction, and smoothed with IMU preintegration factors; keyframes get a
    Scan Context descriptor, loop candidates are verified by FPFH + SAC-IA and point-to-plane
    registration, and accepted loops correct the keyframe pose graph.
    """
    from slslam.errors import DatasetError, InputError
    from slslam.files import write_text_atomic
    from slslam.lidar.datasets import open_lidar_sequence
    from slslam.lidar.measure import measure_roadway
    from slslam.lidar.output import write_outputs
    from slslam.lidar.slam import LidarSlam, LidarSlamOptions
    from slslam.tracking.run import RunInterrupted, _Signals

    if out.exists() and not out.is_dir():
        raise InputError(out, "--out names an existing file; give a folder (it is created)")
    signals = _Signals()
    with signals.installed():  # a signal is noted and acted on between sweeps
        sequence = open_lidar_sequence(dataset, lidar_topic, imu_topic)
        if max_sweeps is not None and max_sweeps < len(sequence):
            sequence.truncate(max_sweeps)
        if len(sequence) < MIN_SWEEPS:
            raise DatasetError(
                dataset, f"{len(sequence)} sweep(s): LiDAR SLAM needs at least {MIN_SWEEPS}"
            )
        options = LidarSlamOptions(loop_closure=not no_loops, map_voxel_m=map_voxel)
        if no_imu:
            sequence.imu = None
        if no_deskew:
            options.odometry.deskew = False
        preset = _manifest_preset(dataset / "manifest.json")
        out.mkdir(parents=True, exist_ok=True)
        for stale in OUTPUTS:  # an earlier run's files never pass for this run's
            (out / stale).unlink(missing_ok=True)
        # replaced when the run ends; until then (even after SIGKILL) it says it did not complete
        write_text_atomic(
            out / "metrics.json",
            json.dumps({"sequence": str(dataset), "completed": False, "stopped_in": "lidar"})
            + "\n",
        )
        try:
            result = LidarSlam(options).run(
                sequence, progress=progress, between_sweeps=signals.raise_if_requested
            )
        except RunInterrupted as interrupted:  # before the first sweep: no result to write
            stderr_console().print(
                f"[bold red]stopped:[/] {interrupted} before the first sweep; {escape(str(out))} "
                "holds only metrics.json (completed: false)",
                highlight=False,
                soft_wrap=True,
            )
            raise typer.Exit(128 + interrupted.signum) from None
        extra = {}
        if preset is not None:
            extra["map_measurement"] = measure_roadway(
                result.map_points, result.T_world_body[:, :3, 3], preset
            )
        metrics = write_outputs(out, sequence, result, extra)  # a signal now waits for it
    console = stdout_console()
    stop = result.stopped
    if stop is None and len(signals.received) > signals._consumed:
        stop = RunInterrupted(signals.received[-1])  # came while the files were written
    if stop is not None:
        stderr_console().print(
            f"[bold red]stopped:[/] {escape(str(stop))}; the results of the first "
            f"{metrics['sweeps']} sweeps are in {escape(str(out))}",
            highlight=False,
            soft_wrap=True,
        )
        raise typer.Exit(128 + stop.signum if isinstance(stop, RunInterrupted) else 2)
    line = f"{metrics['sweeps']} sweeps, {metrics['sweeps_per_second']:.1f} sweeps/s, "
    line += f"{metrics['loops']['accepted']} loops"
    if "slam" in metrics:
        line += (
            f", ATE RMSE {metrics['slam']['ape_m']['rmse']:.3f} m "
            f"(odometry {metrics['odometry']['ape_m']['rmse']:.3f} m)"
        )
    console.print(line)
    if "evaluation_error" in metrics:
        console.print(f"no ATE: {escape(metrics['evaluation_error'])}", highlight=False)
    console.print(f"results in {out}")


#: the files a run writes into --out (metrics.json last: its ``completed`` says the run ended)
OUTPUTS = ("trajectory.tum", "trajectory_odometry.tum", "map.ply", "trajectory.png", "metrics.json")
#: fewest sweeps a run takes: the first sweep starts the map, the second is registered to it
MIN_SWEEPS = 2


def _manifest_preset(path: Path) -> str | None:
    """The simulator's roadway preset from ``manifest.json`` (None without the file); a file
    that is not a JSON object with a string ``preset`` is a DatasetError naming it."""
    from slslam.errors import DatasetError
    from slslam.files import require_regular_file, special_file_kind

    if special_file_kind(path) == "missing":
        return None
    require_regular_file(path, DatasetError, "manifest file")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, UnicodeDecodeError
        raise DatasetError(path, f"not valid JSON ({' '.join(str(exc).split())[:120]})") from None
    if not isinstance(data, dict):
        raise DatasetError(path, f"expected a JSON object, got {type(data).__name__}")
    preset = data.get("preset", "")
    if not isinstance(preset, str):
        raise DatasetError(path, "'preset' must be a string")
    return preset
