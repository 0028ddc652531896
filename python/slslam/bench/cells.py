"""One benchmark cell (sequence x configuration x seed): what it is, and running it.

:func:`plan_cells` turns a spec into cells, each with its content key (slslam.bench.keys);
:func:`execute_cell` runs one (inline or as a Ray task) and returns its record:

    key, cell            the content key and (sequence, configuration, seed, label, kind)
    status, error        ok | failed | timeout, and the error in one line
    result               the run's scores, equal whenever the cell is: ATE / RPE RMSE [m],
                         posed ratio, maps, keyframes, frames ...
    trajectory_sha256    of the run's trajectory.tum (bit-for-bit reproducibility)
    measurements         what varies between runs: wall time [s], frames/s, peak memory [MiB],
                         host, process
    metrics              the run's metrics.json
    material             what the key was hashed from

A run writes its files (trajectory.tum, metrics.json, frames.csv, map.ply, ...) into
``run_dir``; on a cluster of several machines that folder must be on storage they share.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import os
import signal
import socket
import sys
import threading
import time
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from slslam.bench.inputs import ensure_simulated, sim_options
from slslam.bench.keys import KEY_SCHEMA, digest, software, tree_fingerprint
from slslam.bench.provenance import git_commit, machine
from slslam.bench.spec import ConfigSpec, Kind, Resources, SequenceSpec, Spec, SpecError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Cell:
    """A planned cell: its names, its key and the material the worker runs it from."""

    sequence: str
    configuration: str
    seed: int
    label: str
    kind: Kind
    key: str
    material: dict[str, Any]
    exclusive: bool
    resources: Resources
    timeout_s: float
    sim: dict[str, Any] | None = None  # the spec's simulator options (None: recorded)

    @property
    def id(self) -> str:
        return f"{self.sequence}/{self.configuration}/seed{self.seed}"

    def record_path(self, out: Path) -> Path:
        return Path(out) / "cells" / self.sequence / self.configuration / f"seed{self.seed}.json"

    def run_dir(self, out: Path) -> Path:
        return Path(out) / "runs" / self.sequence / self.configuration / f"seed{self.seed}"


class CellTimeout(Exception):
    """A cell ran past its ``timeout_s``."""


def _parse_flags(flags: tuple[str, ...]) -> dict[str, Any]:
    """``a.b=value`` flags as a nested mapping (values parsed as YAML scalars)."""
    tree: dict[str, Any] = {}
    for item in flags:
        key, _, value = item.partition("=")
        node = tree
        *parents, leaf = key.strip().split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = yaml.safe_load(value)
    return tree


def visual_config(spec: Spec, config: ConfigSpec) -> dict[str, Any]:
    """The complete configuration (every key, presets applied) a visual configuration runs with:
    its config file, then ``overlay``, then ``set`` flags, over the front end's preset. The
    network front ends get ``intra_op_threads`` = the cell's CPU request when left at 0 (all
    cores), so cells sharing a machine do not each spawn a thread per core."""
    from slslam.config import ConfigError, config_from_dict, config_to_yaml, merged
    from slslam.yaml_io import MAX_YAML_BYTES, read_yaml

    where = f"configurations.{config.name}"
    data: dict[str, Any] = {}
    if config.config_file is not None:
        data = read_yaml(config.config_file, ConfigError, max_bytes=MAX_YAML_BYTES) or {}
        if not isinstance(data, dict):
            raise SpecError(spec.path, f"{where}.config: {config.config_file} is not a mapping")
    data = merged(merged(data, config.overlay), _parse_flags(config.set))
    try:
        built = config_from_dict(data, point_frontend=config.point_frontend)
    except ConfigError as exc:
        raise SpecError(spec.path, f"{where}: {exc.problem}") from None
    full = yaml.safe_load(config_to_yaml(built))
    threads = max(1, int(config.resources.cpus))
    for network in ("xfeat", "superpoint"):
        section = full["features"].get(network, {})
        if section.get("intra_op_threads") == 0:
            section["intra_op_threads"] = threads
    return full


def _struct(obj: Any) -> dict[str, Any]:
    """A core options struct's public fields as plain values (for the key)."""
    out: dict[str, Any] = {}
    for name in sorted(dir(obj)):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value):
            continue
        if hasattr(value, "tolist"):
            value = value.tolist()
        out[name] = value if isinstance(value, int | float | str | bool | list) else repr(value)
    return out


def lidar_options(config: ConfigSpec) -> dict[str, Any]:
    """The complete LiDAR options of a configuration: the bench's keys (``imu``, ``deskew``)
    and every LidarSlamOptions field, the odometry's and Scan Context's core structs included."""
    from slslam.lidar.slam import LidarSlamOptions

    opts = LidarSlamOptions()
    scalars = {
        f.name: getattr(opts, f.name)
        for f in dataclasses.fields(LidarSlamOptions)
        if f.name not in ("odometry", "scan_context")
    }
    given = dict(config.lidar)
    bench = {"imu": bool(given.pop("imu", True)), "deskew": bool(given.pop("deskew", True))}
    scalars.update(given)
    return {
        **bench,
        "slam": scalars,
        "odometry": _struct(opts.odometry),
        "scan_context": _struct(opts.scan_context),
    }


def _sequence_material(seq: SequenceSpec, seed: int) -> dict[str, Any]:
    if seq.sim is not None:
        return {"sim": sim_options(seq.sim, seed), "max_frames": seq.max_frames}
    assert seq.path is not None
    if not seq.path.exists():
        raise SpecError(seq.path, f"sequences.{seq.name}.path: not found")
    material: dict[str, Any] = {
        "recorded": tree_fingerprint(seq.path),
        "topics": seq.bag_topics,
        "max_frames": seq.max_frames,
    }
    if seq.groundtruth is not None:  # (only then: the keys of cells without one stay as they were)
        if not seq.groundtruth.is_file():
            raise SpecError(seq.groundtruth, f"sequences.{seq.name}.groundtruth: not found")
        material["groundtruth"] = tree_fingerprint(seq.groundtruth)
    return material


def plan_cells(spec: Spec) -> list[Cell]:
    """Every cell of the spec with its key, in spec order (configuration, sequence, seed)."""
    sw = software()
    cells: list[Cell] = []
    for config in spec.configurations:
        if config.kind == "visual":
            config_material: dict[str, Any] = {
                "kind": "visual",
                "config": visual_config(spec, config),
            }
            tracking = config_material["config"]["tracking"]
            if not tracking["sequential"]:
                # inline local mapping (the default) gives the same poses on every run and
                # backend; on its own thread the keyframes depend on the threads' timing
                log.warning(
                    "configuration %s: local mapping on a thread of its own "
                    "(tracking.sequential false): its cells' results can differ between runs",
                    config.name,
                )
        else:
            config_material = {"kind": "lidar", "options": lidar_options(config)}
        names = config.sequences or tuple(s.name for s in spec.sequences)
        for name in names:
            seq = spec.sequence(name)
            for seed in spec.seeds_of(seq):
                material = {
                    "schema": KEY_SCHEMA,
                    "sequence": _sequence_material(seq, seed),
                    "configuration": config_material,
                    "seed": seed,
                    "software": sw,
                }
                cells.append(
                    Cell(
                        sequence=name,
                        configuration=config.name,
                        seed=seed,
                        label=config.label,
                        kind=config.kind,
                        key=digest(material),
                        material=material,
                        exclusive=config.exclusive,
                        resources=config.resources,
                        timeout_s=config.timeout_s or spec.timeout_s,
                        sim=seq.sim,
                    )
                )
    return cells


@contextmanager
def _alarm(seconds: float) -> Iterator[None]:
    """Raises :class:`CellTimeout` in the main thread after ``seconds`` (between frames: the run
    is stopped as by a signal and keeps its files). Elsewhere than the main thread nothing is
    armed (the driver's own deadline still applies)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise CellTimeout(f"ran past its timeout of {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _reset_peak_memory() -> bool:
    """Resets the process's resident-memory high-water mark (Linux: /proc/self/clear_refs), so
    VmHWM afterwards is this cell's peak. False where that is not possible."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def _peak_memory_mib() -> float | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0  # kB -> MiB
    except OSError:
        return None
    return None


def _checkout() -> str:
    """The commit of the slslam source this process runs (a checkout's ``git describe
    --dirty``; an installed package: its core's build commit)."""
    import slslam

    return git_commit(Path(slslam.__file__).parent)


def _ray_node() -> str | None:
    """The Ray node running this cell (None inline): which machine of a cluster it was."""
    ray = sys.modules.get("ray")
    if ray is None or not ray.is_initialized():
        return None
    return ray.get_runtime_context().get_node_id()


def _one_line(exc: BaseException, limit: int = 500) -> str:
    text = " ".join(f"{type(exc).__name__}: {exc}".split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _open_visual(seq: dict[str, Any], data: Path) -> Any:
    """What run_sequence takes: the folder, or an opened ROS bag."""
    topics = seq.get("topics") or {}
    if "left" not in topics:
        return data
    from slslam.datasets.rosbag import RosbagSequence

    return RosbagSequence(
        data, topics["left"], topics["right"], topics.get("calib"), imu_topic=topics.get("imu")
    )


def _visual_result(metrics: dict[str, Any]) -> dict[str, Any]:
    ape, rpe = metrics.get("ape") or {}, metrics.get("rpe") or {}
    return {
        "completed": metrics.get("completed"),
        "frames": metrics.get("frames"),
        "ate_rmse_m": ape.get("rmse"),
        "ate_percent_of_path": metrics.get("ape_rmse_percent_of_path"),
        "rpe_rmse_m": rpe.get("rmse"),
        "posed_ratio": metrics.get("posed_ratio_after_init"),
        "tracked_ratio": metrics.get("tracked_ratio"),
        "maps": metrics.get("maps"),
        "keyframes": metrics.get("keyframes"),
        "map_points": metrics.get("map_points"),
        "map_lines": metrics.get("map_lines"),
        "relocalisations": metrics.get("relocalisations"),
        "lost_frames": metrics.get("lost_frames"),
        "loops_accepted": (metrics.get("loops") or {}).get("accepted"),
        "evaluation_error": metrics.get("evaluation_error"),
    }


def _run_visual(material: dict[str, Any], data: Path, run_dir: Path) -> dict[str, Any]:
    from slslam.config import config_from_dict
    from slslam.tracking import run_sequence

    config = config_from_dict(material["configuration"]["config"], preset=False)
    seq = material["sequence"]
    groundtruth = (seq.get("groundtruth") or {}).get("path")
    summary = run_sequence(
        _open_visual(seq, data),
        run_dir,
        config,
        max_frames=seq.get("max_frames"),
        progress=False,
        groundtruth=Path(groundtruth) if groundtruth else None,
    )
    return summary.metrics


def _run_lidar(material: dict[str, Any], data: Path, run_dir: Path) -> dict[str, Any]:
    from slslam.lidar.datasets import open_lidar_sequence
    from slslam.lidar.measure import measure_roadway
    from slslam.lidar.output import write_outputs
    from slslam.lidar.slam import LidarSlam, LidarSlamOptions

    options_material = material["configuration"]["options"]
    seq = material["sequence"]
    topics = seq.get("topics") or {}
    sequence = open_lidar_sequence(data, topics.get("lidar"), topics.get("imu"))
    if seq.get("max_frames") and seq["max_frames"] < len(sequence):
        sequence.truncate(seq["max_frames"])
    options = LidarSlamOptions(**options_material["slam"])
    if not options_material["imu"]:
        sequence.imu = None
    options.odometry.deskew = bool(options_material["deskew"])
    result = LidarSlam(options).run(sequence, progress=False)
    extra: dict[str, Any] = {"completed": True}
    if "sim" in seq:
        extra["map_measurement"] = measure_roadway(
            result.map_points, result.T_world_body[:, :3, 3], seq["sim"]["preset"]
        )
    return write_outputs(run_dir, sequence, result, extra)


def _lidar_result(metrics: dict[str, Any]) -> dict[str, Any]:
    slam, odometry = metrics.get("slam") or {}, metrics.get("odometry") or {}
    return {
        "completed": True,
        "frames": metrics.get("sweeps"),
        "ate_rmse_m": (slam.get("ape_m") or {}).get("rmse"),
        "ate_odometry_rmse_m": (odometry.get("ape_m") or {}).get("rmse"),
        "rpe_rmse_m": (slam.get("rpe_1m_m") or {}).get("rmse"),
        "posed_ratio": 1.0 if metrics.get("sweeps") else 0.0,  # every sweep gets a pose
        "maps": 1,
        "keyframes": metrics.get("keyframes"),
        "map_points": metrics.get("map_points"),
        "loops_accepted": (metrics.get("loops") or {}).get("accepted"),
    }


def execute_cell(cell: Cell, out: str | Path, data_dir: str | Path) -> dict[str, Any]:
    """Runs one cell (simulating its input first when needed) and returns its record. Errors and
    timeouts become a record with ``status`` failed / timeout; an interrupt (SIGINT, SIGTERM,
    Ray's cancel) propagates, the run's own files kept (slslam.tracking.run)."""
    out, data_dir = Path(out), Path(data_dir)
    run_dir = cell.run_dir(out)
    run_dir.mkdir(parents=True, exist_ok=True)
    (run_dir / ".started").write_text(f"{socket.gethostname()} {os.getpid()} {time.time()}\n")
    record: dict[str, Any] = {
        "schema": KEY_SCHEMA,
        "key": cell.key,
        "cell": {
            "sequence": cell.sequence,
            "configuration": cell.configuration,
            "seed": cell.seed,
            "label": cell.label,
            "kind": cell.kind,
        },
        "run_dir": os.path.relpath(run_dir, out),
    }
    measurements: dict[str, Any] = {
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "machine": machine(),
        "ray_node": _ray_node(),
    }
    start = time.perf_counter()
    per_cell_memory = _reset_peak_memory()
    try:
        with _alarm(cell.timeout_s):
            if cell.sim is not None:
                data = ensure_simulated(data_dir, cell.sequence, cell.sim, cell.seed)
            else:
                data = Path(cell.material["sequence"]["recorded"]["path"])
            record["input"] = str(data)
            measurements["input_s"] = time.perf_counter() - start
            run_start = time.perf_counter()
            if cell.kind == "visual":
                metrics = _run_visual(cell.material, data, run_dir)
                result = _visual_result(metrics)
            else:
                metrics = _run_lidar(cell.material, data, run_dir)
                result = _lidar_result(metrics)
            run_s = time.perf_counter() - run_start
        record["status"] = "ok"
        record["error"] = None
        record["result"] = result
        record["metrics"] = metrics
        measurements["run_s"] = run_s
        frames = result.get("frames") or 0
        measurements["frames_per_s"] = frames / run_s if run_s > 0 else None
        trajectory = run_dir / "trajectory.tum"
        record["trajectory_sha256"] = (
            hashlib.sha256(trajectory.read_bytes()).hexdigest() if trajectory.is_file() else None
        )
    except CellTimeout as exc:
        record.update(status="timeout", error=_one_line(exc), result={}, metrics=None)
    except Exception as exc:  # a failing cell is reported; the sweep goes on
        record.update(status="failed", error=_one_line(exc), result={}, metrics=None)
        record["traceback"] = traceback.format_exc(limit=8)[-4000:]
    measurements["wall_s"] = time.perf_counter() - start
    peak = _peak_memory_mib()
    measurements["peak_rss_mib"] = peak
    measurements["memory_scope"] = "cell" if per_cell_memory else "process"
    measurements["finished_unix"] = time.time()
    # the machine's 1-minute load average at the end: other jobs slow frames/s down
    measurements["load_1min"] = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    measurements["slslam_checkout"] = _checkout()
    record["measurements"] = measurements
    record["material"] = cell.material
    return record
