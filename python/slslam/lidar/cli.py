"""``slslam lidar``: LiDAR(-inertial) SLAM on a sequence folder."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

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
    from slslam.lidar.datasets import open_lidar_sequence
    from slslam.lidar.measure import measure_roadway
    from slslam.lidar.output import write_outputs
    from slslam.lidar.slam import LidarSlam, LidarSlamOptions

    sequence = open_lidar_sequence(dataset, lidar_topic, imu_topic)
    if max_sweeps is not None and max_sweeps < len(sequence):
        sequence.truncate(max_sweeps)
    options = LidarSlamOptions(loop_closure=not no_loops, map_voxel_m=map_voxel)
    if no_imu:
        sequence.imu = None
    if no_deskew:
        options.odometry.deskew = False
    result = LidarSlam(options).run(sequence, progress=progress)
    extra = {}
    manifest = dataset / "manifest.json"
    if manifest.is_file():
        preset = json.loads(manifest.read_text()).get("preset", "")
        extra["map_measurement"] = measure_roadway(
            result.map_points, result.T_world_body[:, :3, 3], preset
        )
    metrics = write_outputs(out, sequence, result, extra)
    console = Console()
    line = f"{metrics['sweeps']} sweeps, {metrics['sweeps_per_second']:.1f} sweeps/s, "
    line += f"{metrics['loops']['accepted']} loops"
    if "slam" in metrics:
        line += (
            f", ATE RMSE {metrics['slam']['ape_m']['rmse']:.3f} m "
            f"(odometry {metrics['odometry']['ape_m']['rmse']:.3f} m)"
        )
    console.print(line)
    console.print(f"results in {out}")
