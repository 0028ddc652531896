"""Trajectory files: TUM, KITTI and EuRoC/ASL csv, read and written through evo.

Formats
    ``tum``    ``timestamp tx ty tz qx qy qz qw`` per line, seconds, whitespace separated.
    ``kitti``  12 numbers per line (row-major 3x4 ``T_world_cam``), no timestamps; a separate
               times file (one timestamp per line, seconds) may give them.
    ``euroc``  csv ``timestamp_ns, px, py, pz, qw, qx, qy, qz[, ...]`` (ASL ground truth layout).

Every reader checks what evo does not: the file exists and is not empty, every pose is finite with
a non-zero quaternion, and timestamps increase strictly. Problems raise
:class:`~slslam.errors.TrajectoryFileError` naming the file and the first offending row.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from evo.core.trajectory import PosePath3D, PoseTrajectory3D
from evo.tools import file_interface

from slslam.errors import TrajectoryFileError

TrajectoryFormat = Literal["auto", "tum", "kitti", "euroc"]
FORMATS = ("tum", "kitti", "euroc")


def _first_data_line(path: Path) -> str:
    with path.open(encoding="utf-8", errors="replace") as handle:
        for line in handle:
            stripped = line.strip()
            if stripped and not stripped.startswith("#"):
                return stripped
    raise TrajectoryFileError(path, "the trajectory file is empty (no pose rows)")


def detect_format(path: str | Path) -> Literal["tum", "kitti", "euroc"]:
    """Guess the format from the first data row: commas -> euroc, 8 columns -> tum, 12 -> kitti."""
    path = Path(path)
    if not path.is_file():
        raise TrajectoryFileError(path, "trajectory file not found")
    line = _first_data_line(path)
    if "," in line:
        return "euroc"
    columns = len(line.split())
    if columns == 8:
        return "tum"
    if columns == 12:
        return "kitti"
    raise TrajectoryFileError(
        path,
        f"cannot tell the format: first row has {columns} columns "
        "(TUM has 8, KITTI 12, EuRoC csv uses commas)",
    )


def _line_of_row(path: Path, row: int) -> int:
    """The 1-based line number of data row ``row`` (0-based; comments and blanks skipped)."""
    seen = -1
    with path.open(encoding="utf-8", errors="replace") as handle:
        for number, line in enumerate(handle, start=1):
            stripped = line.strip()
            if stripped and not stripped.startswith("#"):
                seen += 1
                if seen == row:
                    return number
    return 0


def _validate(path: Path, traj: PosePath3D) -> None:
    if traj.num_poses == 0:
        raise TrajectoryFileError(path, "the trajectory file is empty (no pose rows)")
    bad = ~np.all(np.isfinite(traj.positions_xyz), axis=1)
    bad |= ~np.all(np.isfinite(traj.orientations_quat_wxyz), axis=1)
    if isinstance(traj, PoseTrajectory3D):
        bad |= ~np.isfinite(traj.timestamps)
    if np.any(bad):
        row = int(np.argmax(bad))
        raise TrajectoryFileError(
            path, f"line {_line_of_row(path, row)}: pose {row} contains NaN or Inf"
        )
    norms = np.linalg.norm(traj.orientations_quat_wxyz, axis=1)
    if np.any(norms < 1e-9):
        raise TrajectoryFileError(
            path, f"pose {int(np.argmax(norms < 1e-9))} has a zero quaternion"
        )
    if isinstance(traj, PoseTrajectory3D):
        steps = np.diff(traj.timestamps)
        if np.any(steps <= 0):
            i = int(np.argmax(steps <= 0)) + 1
            raise TrajectoryFileError(
                path,
                f"timestamps are not strictly increasing at pose {i} "
                f"({traj.timestamps[i - 1]:.9f} -> {traj.timestamps[i]:.9f})",
            )


def read_trajectory(
    path: str | Path,
    fmt: TrajectoryFormat = "auto",
    kitti_times: str | Path | None = None,
) -> PosePath3D:
    """Read a trajectory file.

    Args:
        path: the file.
        fmt: ``auto`` (detect), ``tum``, ``kitti`` or ``euroc``.
        kitti_times: for KITTI files, an optional times file that turns the path into a
            timestamped :class:`PoseTrajectory3D`.

    Returns:
        a :class:`PoseTrajectory3D` (TUM, EuRoC, KITTI with times) or :class:`PosePath3D` (KITTI).
    """
    path = Path(path)
    if not path.is_file():
        raise TrajectoryFileError(path, "trajectory file not found")
    fmt = detect_format(path) if fmt == "auto" else fmt
    if fmt not in FORMATS:
        raise TrajectoryFileError(path, f"unknown trajectory format '{fmt}' (use {FORMATS})")
    _first_data_line(path)  # empty files get our message rather than evo's
    try:
        if fmt == "tum":
            traj: PosePath3D = file_interface.read_tum_trajectory_file(path)
        elif fmt == "euroc":
            traj = file_interface.read_euroc_csv_trajectory(path)
        else:
            traj = file_interface.read_kitti_poses_file(path)
    except (file_interface.FileInterfaceException, ValueError, IndexError) as exc:
        raise TrajectoryFileError(path, f"not a valid {fmt.upper()} trajectory ({exc})") from None
    if fmt == "kitti" and kitti_times is not None:
        try:
            times = np.loadtxt(kitti_times, ndmin=1, dtype=float)
        except (OSError, ValueError) as exc:
            raise TrajectoryFileError(kitti_times, f"not a times file ({exc})") from None
        if times.shape[0] != traj.num_poses:
            raise TrajectoryFileError(
                kitti_times, f"has {times.shape[0]} timestamps for {traj.num_poses} poses"
            )
        traj = PoseTrajectory3D(poses_se3=traj.poses_se3, timestamps=times)
    _validate(path, traj)
    return traj


def write_trajectory(path: str | Path, traj: PosePath3D, fmt: str = "tum") -> Path:
    """Write ``traj`` as ``tum`` (needs timestamps) or ``kitti``; returns the path written.

    The file is written to a temporary name and renamed, so an interrupted write never leaves a
    half-written trajectory where a complete one was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    if fmt == "tum":
        if not isinstance(traj, PoseTrajectory3D):
            raise TrajectoryFileError(path, "TUM output needs timestamps (a PoseTrajectory3D)")
        file_interface.write_tum_trajectory_file(tmp, traj)
    elif fmt == "kitti":
        file_interface.write_kitti_poses_file(tmp, traj)
    else:
        raise TrajectoryFileError(path, f"cannot write format '{fmt}' (use tum or kitti)")
    tmp.replace(path)
    return path


def tum_time(t_ns: int) -> str:
    """Nanoseconds as exact fixed-point seconds (``1317042145.967790592``), as TUM files hold
    them; a float's ``%.9f`` of a Unix time is off by up to a few hundred ns."""
    sign, t_ns = ("-", -t_ns) if t_ns < 0 else ("", t_ns)
    return f"{sign}{t_ns // 1_000_000_000}.{t_ns % 1_000_000_000:09d}"


def tum_lines(times: list[str], T_world_frame: np.ndarray) -> list[str]:
    """TUM lines ``time x y z qx qy qz qw`` (newline-terminated; positions and quaternions to
    1e-9) of poses ``T_world_frame`` (N, 4, 4) at the given time texts (:func:`tum_time`)."""
    from scipy.spatial.transform import Rotation

    T = np.asarray(T_world_frame, dtype=np.float64).reshape(-1, 4, 4)
    if len(times) != len(T):
        raise ValueError(f"{len(times)} timestamps for {len(T)} poses")
    if not len(T):
        return []
    quats = Rotation.from_matrix(T[:, :3, :3]).as_quat()  # x y z w
    rows = np.column_stack([T[:, :3, 3], quats])
    return [
        t + " " + " ".join(f"{v:.9f}" for v in row) + "\n"
        for t, row in zip(times, rows, strict=True)
    ]


def write_tum_ns(path: str | Path, t_ns: np.ndarray, T_world_frame: np.ndarray) -> Path:
    """A TUM file of poses ``T_world_frame`` (N, 4, 4) at integer times ``t_ns`` (N,), the times
    written exactly (:func:`tum_time`); written to a temporary name and renamed."""
    path = Path(path)
    t_ns = np.asarray(t_ns, dtype=np.int64).reshape(-1)
    try:
        lines = tum_lines([tum_time(t) for t in t_ns.tolist()], T_world_frame)
    except ValueError as exc:
        raise TrajectoryFileError(path, str(exc)) from None
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    try:
        with tmp.open("w", encoding="ascii") as f:
            f.writelines(lines)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
