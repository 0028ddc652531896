"""A benchmark spec: the YAML file ``slslam bench`` sweeps (sequences x configurations x seeds).

    name: recovery                   # optional, default: the file's stem
    description: what the sweep measures
    seeds: [0, 1, 2]                 # simulator seeds: each simulated sequence runs once per
                                     # seed; a recorded one once (seed 0) unless it lists seeds:
    timeout_s: 1800                  # per cell [s]; a cell over it is reported as failed
    resources: {cpus: 1, gpus: 0}    # Ray request of each cell (a configuration may override;
                                     # gpus: onnxruntime's CUDA provider, which the front ends'
                                     # providers: auto pick when Ray gives the task a GPU)
    report: [ate, rpe, posed_ratio, maps, fps, memory]   # columns of the summary table
    sequences:
      loop_dark:                     # a simulated sequence: SimOptions fields (slslam sim)
        sim: {preset: loop, light: 0.15, dust: true, frames: 150, lidar: false}
      euroc_v101:                    # a recorded one: EuRoC ASL folder, KITTI odometry
        path: ../../../shared/data/euroc_v101_micro   # sequence or ROS bag; relative paths
        max_frames: 100              #   start at the spec file's folder
      bag:                           # a ROS bag needs its image topics (and a calibration)
        path: run.bag
        left: /cam0/image_raw
        right: /cam1/image_raw
        calib: [kalibr.yaml]         # (LiDAR runs: lidar: and imu: topics, default: the only
    configurations:                  #  PointCloud2 / Imu topic of the bag)
      orb_lines:
        label: ORB + lines           # shown in the tables (default: the name)
        point_frontend: orb          # the front end, with its preset (as slslam run --orb)
        config: my_overlay.yaml      # a config file with the keys it changes ...
        overlay: {tracking: {use_lines: true}}   # ... then these keys over it ...
        set: [tracking.imu.enabled=false]        # ... then KEY=VALUE flags over both
        sequences: [loop_dark]       # optional: only these sequences
        exclusive: true              # timing cells: run after the others, one at a time
        resources: {cpus: 2}         # this configuration's Ray request
        timeout_s: 600
      lidar:
        kind: lidar                  # the LiDAR pipeline (slslam lidar run)
        lidar: {loop_closure: false, imu: true, deskew: true, map_voxel_m: 0.1}

Every problem is an error naming the spec file and the key (``sequences.loop_dark.sim.light``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from slslam.errors import InputError
from slslam.yaml_io import short_repr

#: Summary columns a spec may ask for (``report``), in their table order.
REPORT_METRICS = ("ate", "rpe", "posed_ratio", "maps", "fps", "memory")

#: LiDAR pipeline options a configuration may set (``lidar:``), with their types.
LIDAR_KEYS: dict[str, type] = {
    "loop_closure": bool,
    "imu": bool,
    "deskew": bool,
    "map_voxel_m": float,
    "keyframe_distance_m": float,
    "keyframe_angle_deg": float,
}

Kind = Literal["visual", "lidar"]


class SpecError(InputError):
    """A benchmark spec is malformed; the message names the file and the key."""


@dataclass(frozen=True)
class Resources:
    """What one cell asks Ray for: CPU cores and GPUs (onnxruntime's CUDA provider)."""

    cpus: float = 1.0
    gpus: float = 0.0


@dataclass(frozen=True)
class SequenceSpec:
    """One sequence of the sweep: simulated (``sim`` options) or recorded (``path``)."""

    name: str
    sim: dict[str, Any] | None = None  # SimOptions fields; ``seed`` comes from the cell
    path: Path | None = None  # absolute
    max_frames: int | None = None
    seeds: tuple[int, ...] | None = None  # None: the spec's seeds (simulated) or (0,) (recorded)
    bag_topics: dict[str, Any] = field(default_factory=dict)  # left, right, imu, calib
    groundtruth: Path | None = None  # absolute; a trajectory file to score against (recorded)

    @property
    def simulated(self) -> bool:
        return self.sim is not None

    def has_lidar(self) -> bool:
        """Whether the sequence offers LiDAR sweeps (a simulated one asked for them, a KITTI
        velodyne/ folder, an ASL folder with lidar0/, or a bag: checked when it is opened)."""
        if self.sim is not None:
            return bool(self.sim.get("lidar", True))
        assert self.path is not None
        if self.path.is_file():  # a bag: its topics decide
            return True
        return (self.path / "velodyne").is_dir() or (self.path / "mav0" / "lidar0").is_dir()

    def has_cameras(self) -> bool:
        if self.sim is not None:
            return bool(self.sim.get("cameras", True))
        assert self.path is not None
        return not (self.path / "velodyne").is_dir()


@dataclass(frozen=True)
class ConfigSpec:
    """One configuration: a visual run's config layers or a LiDAR run's options."""

    name: str
    label: str
    kind: Kind = "visual"
    point_frontend: str | None = None
    config_file: Path | None = None
    overlay: dict[str, Any] = field(default_factory=dict)
    set: tuple[str, ...] = ()
    lidar: dict[str, Any] = field(default_factory=dict)
    sequences: tuple[str, ...] | None = None
    exclusive: bool = False
    resources: Resources = Resources()
    timeout_s: float | None = None


@dataclass(frozen=True)
class Spec:
    """A parsed spec: the cells are every (sequence, configuration, seed) it names."""

    path: Path
    name: str
    description: str
    sequences: tuple[SequenceSpec, ...]
    configurations: tuple[ConfigSpec, ...]
    seeds: tuple[int, ...]
    report: tuple[str, ...]
    timeout_s: float
    resources: Resources

    def sequence(self, name: str) -> SequenceSpec:
        return next(s for s in self.sequences if s.name == name)

    def configuration(self, name: str) -> ConfigSpec:
        return next(c for c in self.configurations if c.name == name)

    def seeds_of(self, sequence: SequenceSpec) -> tuple[int, ...]:
        if sequence.seeds is not None:
            return sequence.seeds
        return self.seeds if sequence.simulated else (0,)


class _Reader:
    """Typed access to one mapping of the spec, errors naming ``file: key``."""

    def __init__(self, path: Path, data: Any, where: str) -> None:
        self.path, self.where = path, where
        if not isinstance(data, dict):
            self.fail(f"expected a mapping, got {short_repr(data)}")
        self.data: dict = data

    def fail(self, problem: str, key: str | None = None) -> None:
        where = self.where if key is None else (f"{self.where}.{key}" if self.where else key)
        raise SpecError(self.path, f"{where}: {problem}" if where else problem)

    def only(self, allowed: set[str]) -> None:
        for key in self.data:
            if key not in allowed:
                known = ", ".join(sorted(allowed))
                self.fail(f"unknown key (known: {known})", str(key))

    def get(self, key: str, kind: type | tuple[type, ...], default: Any = None) -> Any:
        if key not in self.data or self.data[key] is None:
            return default
        value = self.data[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if isinstance(value, bool) and kind in (int, float):
            self.fail(f"expected a number, got {short_repr(value)}", key)
        if not isinstance(value, kind):
            names = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
            self.fail(f"expected {names}, got {short_repr(value)}", key)
        return value

    def sub(self, key: str) -> _Reader:
        return _Reader(self.path, self.data[key], f"{self.where}.{key}" if self.where else key)


def _seeds(reader: _Reader, key: str) -> tuple[int, ...] | None:
    value = reader.data.get(key)
    if value is None:
        return None
    if isinstance(value, int) and not isinstance(value, bool):
        value = [value]
    if not isinstance(value, list) or not value:
        reader.fail("expected a non-empty list of seeds", key)
    if any(not isinstance(s, int) or isinstance(s, bool) or s < 0 for s in value):
        reader.fail("seeds must be non-negative integers", key)
    if len(set(value)) != len(value):
        reader.fail("seeds must be distinct", key)
    return tuple(value)


def _resources(reader: _Reader, key: str, default: Resources) -> Resources:
    if key not in reader.data:
        return default
    sub = reader.sub(key)
    sub.only({"cpus", "gpus"})
    cpus = sub.get("cpus", float, default.cpus)
    gpus = sub.get("gpus", float, default.gpus)
    if not 0 < cpus <= 1024:
        sub.fail(f"must be in (0, 1024], got {cpus}", "cpus")
    if not 0 <= gpus <= 64:
        sub.fail(f"must be in [0, 64], got {gpus}", "gpus")
    return Resources(cpus, gpus)


def _positive(reader: _Reader, key: str, kind: type, default: Any) -> Any:
    value = reader.get(key, kind, default)
    if value is not None and not value > 0:
        reader.fail(f"must be > 0, got {value}", key)
    return value


def _sim_options(reader: _Reader) -> dict[str, Any]:
    """The ``sim`` mapping, checked against SimOptions (fields, types, SimOptions.check)."""
    from slslam.sim import SimOptions

    defaults = SimOptions()
    nested = ("section", "camera", "seed")  # the geometry stays default; the seed is the cell's
    allowed = sorted(f.name for f in dataclasses.fields(SimOptions) if f.name not in nested)
    options: dict[str, Any] = {}
    for key, value in reader.data.items():
        if key == "seed":
            reader.fail("the seed comes from the spec's seeds (or the sequence's seeds:)", key)
        if key not in allowed:
            reader.fail(f"unknown simulator option (known: {', '.join(allowed)})", str(key))
        default = getattr(defaults, key)
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if isinstance(default, bool):
            ok = isinstance(value, bool)
        elif isinstance(default, int):
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif isinstance(default, float) or default is None:  # None: an optional time [s]
            ok = number
            value = float(value) if number else value
        else:
            ok = isinstance(value, type(default))
        if not ok:
            expected = "a number" if default is None else type(default).__name__
            reader.fail(f"expected {expected}, got {short_repr(value)}", str(key))
        options[key] = value
    try:
        SimOptions(**options).check()
    except (TypeError, ValueError) as exc:
        reader.fail(str(exc))
    return options


def _sequence(reader: _Reader, name: str, base: Path) -> SequenceSpec:
    reader.only(
        {
            "sim",
            "path",
            "max_frames",
            "seeds",
            "left",
            "right",
            "imu",
            "lidar",
            "calib",
            "groundtruth",
        }
    )
    max_frames = reader.get("max_frames", int)
    if max_frames is not None and max_frames < 2:
        reader.fail(f"must be >= 2, got {max_frames}", "max_frames")
    seeds = _seeds(reader, "seeds")
    has_sim, has_path = "sim" in reader.data, "path" in reader.data
    if has_sim == has_path:
        reader.fail("give exactly one of sim: (simulator options) and path: (a recorded sequence)")
    topics: dict[str, Any] = {}
    if has_sim:
        for key in ("left", "right", "imu", "lidar", "calib", "groundtruth"):
            if key in reader.data:
                reader.fail("only for a recorded sequence (path:)", key)
        sim = _sim_options(reader.sub("sim"))
        return SequenceSpec(name, sim=sim, max_frames=max_frames, seeds=seeds)
    raw = reader.get("path", str)
    path = Path(raw).expanduser()
    path = (path if path.is_absolute() else base / path).resolve()
    for key in ("left", "right", "imu", "lidar"):
        if key in reader.data:
            topics[key] = reader.get(key, str)
    if ("left" in topics) != ("right" in topics):
        reader.fail("a ROS bag's visual runs need both left: and right: image topics")
    if "calib" in reader.data:
        calib = reader.data["calib"]
        calib = [calib] if isinstance(calib, str) else calib
        if not isinstance(calib, list) or not all(isinstance(c, str) for c in calib):
            reader.fail("expected a file or a list of files", "calib")
        topics["calib"] = [str((base / c).resolve()) for c in calib]
    groundtruth = None
    if "groundtruth" in reader.data:
        gt = Path(reader.get("groundtruth", str)).expanduser()
        groundtruth = (gt if gt.is_absolute() else base / gt).resolve()
    return SequenceSpec(
        name,
        path=path,
        max_frames=max_frames,
        seeds=seeds,
        bag_topics=topics,
        groundtruth=groundtruth,
    )


def _configuration(reader: _Reader, name: str, base: Path, defaults: Resources) -> ConfigSpec:
    reader.only(
        {
            "label",
            "kind",
            "point_frontend",
            "config",
            "overlay",
            "set",
            "lidar",
            "sequences",
            "exclusive",
            "resources",
            "timeout_s",
        }
    )
    kind = reader.get("kind", str, "visual")
    if kind not in ("visual", "lidar"):
        reader.fail(f"must be visual or lidar, got {short_repr(kind)}", "kind")
    label = reader.get("label", str, name)
    frontend = reader.get("point_frontend", str)
    config_file = None
    if "config" in reader.data:
        config_file = (base / reader.get("config", str)).resolve()
        if not config_file.is_file():
            reader.fail(f"config file not found: {config_file}", "config")
    overlay = reader.get("overlay", dict, {})
    flags = reader.get("set", (list, str), [])
    flags = [flags] if isinstance(flags, str) else flags
    for i, item in enumerate(flags):
        if not isinstance(item, str) or "=" not in item:
            reader.fail(f"expected KEY=VALUE, got {short_repr(item)}", f"set[{i}]")
    lidar = reader.get("lidar", dict, {})
    if kind == "visual":
        if lidar:
            reader.fail("only for kind: lidar", "lidar")
    else:
        for key in ("point_frontend", "config", "overlay", "set"):
            if key in reader.data:
                reader.fail("only for visual configurations (kind: visual)", key)
        sub = reader.sub("lidar") if "lidar" in reader.data else None
        if sub is not None:
            sub.only(set(LIDAR_KEYS))
            for key, kind_ in LIDAR_KEYS.items():
                sub.get(key, kind_)
    sequences = reader.get("sequences", list)
    if sequences is not None and not all(isinstance(s, str) for s in sequences):
        reader.fail("expected a list of sequence names", "sequences")
    return ConfigSpec(
        name=name,
        label=label,
        kind=kind,  # type: ignore[arg-type]
        point_frontend=frontend,
        config_file=config_file,
        overlay=overlay,
        set=tuple(flags),
        lidar=lidar,
        sequences=None if sequences is None else tuple(sequences),
        exclusive=reader.get("exclusive", bool, False),
        resources=_resources(reader, "resources", defaults),
        timeout_s=_positive(reader, "timeout_s", float, None),
    )


def _named(reader: _Reader, key: str) -> list[tuple[str, _Reader]]:
    if key not in reader.data:
        reader.fail("missing (a mapping of names to definitions)", key)
    sub = reader.sub(key)
    if not sub.data:
        sub.fail("empty: name at least one")
    out = []
    for name in sub.data:
        if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
            sub.fail("names are letters, digits, '_' and '-'", str(name))
        out.append((name, sub.sub(name)))
    return out


def parse_spec(data: Any, path: Path) -> Spec:
    """A :class:`Spec` from the spec file's parsed YAML (``path`` names it in errors and
    anchors its relative paths)."""
    from slslam.config import POINT_FRONTENDS

    path = Path(path).resolve()
    root = _Reader(path, data, "")
    root.only(
        {
            "name",
            "description",
            "seeds",
            "timeout_s",
            "resources",
            "report",
            "sequences",
            "configurations",
        }
    )
    base = path.parent
    resources = _resources(root, "resources", Resources())
    sequences = [_sequence(r, n, base) for n, r in _named(root, "sequences")]
    configs = [_configuration(r, n, base, resources) for n, r in _named(root, "configurations")]
    names = {s.name for s in sequences}
    by_name = {s.name: s for s in sequences}
    for c in configs:
        where = f"configurations.{c.name}"
        if c.point_frontend is not None and c.point_frontend not in POINT_FRONTENDS:
            root.fail(f"must be one of {', '.join(POINT_FRONTENDS)}", f"{where}.point_frontend")
        for s in c.sequences or ():
            if s not in names:
                root.fail(
                    f"unknown sequence {s!r} (known: {', '.join(sorted(names))})",
                    f"{where}.sequences",
                )
        for s in c.sequences or tuple(names):
            seq = by_name[s]
            if c.kind == "lidar" and not seq.has_lidar():
                root.fail(
                    f"a LiDAR configuration on sequence {s!r}, which has no LiDAR "
                    "(sim: lidar: true, or list the sequences it runs on)",
                    where,
                )
            if c.kind == "visual" and not seq.has_cameras():
                root.fail(f"a visual configuration on sequence {s!r}, which has no cameras", where)
    report = root.get("report", list, list(REPORT_METRICS))
    for i, item in enumerate(report):
        if item not in REPORT_METRICS:
            root.fail(
                f"unknown metric {short_repr(item)} (known: {', '.join(REPORT_METRICS)})",
                f"report[{i}]",
            )
    return Spec(
        path=path,
        name=root.get("name", str, path.stem),
        description=root.get("description", str, ""),
        sequences=tuple(sequences),
        configurations=tuple(configs),
        seeds=_seeds(root, "seeds") or (0,),
        report=tuple(report),
        timeout_s=_positive(root, "timeout_s", float, 3600.0),
        resources=resources,
    )


def load_spec(path: str | Path) -> Spec:
    """Reads and checks the spec file at ``path`` (errors name the file and the key)."""
    from slslam.yaml_io import read_yaml

    path = Path(path)
    if not path.is_file():
        raise SpecError(path, "spec file not found")
    return parse_spec(read_yaml(path, SpecError), path)
