"""slslam's YAML configuration: typed sections with documented defaults.

A config file holds only the keys it changes; everything else keeps the default below (and in
``configs/default.yaml``, which lists every key with its meaning). Unknown keys and wrong types are
errors that name the file and the key, so a typo never passes silently.

    features:
      point_frontend: superpoint      # superpoint | orb
      superpoint:
        model_path: /models/superpoint_v1.onnx   # overrides $SLSLAM_SUPERPOINT_MODEL
"""

from __future__ import annotations

import dataclasses
import logging
import os
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import yaml

from slslam.errors import InputError
from slslam.features.orb import OrbOptions
from slslam.features.superpoint import ENV_MODEL, SuperPointOptions

log = logging.getLogger(__name__)


class ConfigError(InputError):
    """A configuration file or value is malformed."""


@dataclass(frozen=True)
class GridConfig:
    """Per-cell keypoint limit (SPEC A2); mirrors C++ ``GridLimitOptions``."""

    cell_size_px: int = 32  # P: cell side [px]
    max_per_cell: int = 8  # keypoints kept per cell


@dataclass(frozen=True)
class DynamicCellConfig:
    """Invalid-cell filter (SPEC A2); mirrors C++ ``DynamicCellOptions``."""

    enabled: bool = True
    cell_size_px: int = 32  # cell side [px]
    sigma_px: float = 3.0  # Gaussian width of G(d) [px]
    alpha: float = 0.7  # weight of the current frame in the temporal smoothing
    threshold: float = 0.5  # l: a cell below this weight is invalid (with its 8 neighbours)


@dataclass(frozen=True)
class FeaturesConfig:
    """The point front end."""

    point_frontend: Literal["superpoint", "orb"] = "superpoint"
    superpoint: SuperPointOptions = field(default_factory=SuperPointOptions)
    orb: OrbOptions = field(default_factory=OrbOptions)
    grid: GridConfig = field(default_factory=GridConfig)
    dynamic_cells: DynamicCellConfig = field(default_factory=DynamicCellConfig)


@dataclass(frozen=True)
class TrackingConfig:
    """Tracking and local mapping (SPEC A5-A6); mirrors C++ ``TrackerOptions``."""

    use_lines: bool = True  # line features in tracking and mapping
    sequential: bool = True  # local mapping inline: exactly reproducible; false: own thread
    min_init_points: int = 50  # stereo points a frame needs to start a map
    min_inliers: int = 15  # fewer inliers after motion-only BA: the frame is LOST
    search_radius_px: float = 15.0  # guided matching window [px] (doubled on a retry)
    max_distance_binary: float = 50.0  # guided matching bound for ORB [Hamming bits]
    max_distance_float: float = 0.8  # guided matching bound for SuperPoint [L2]
    keyframe_max_frames: int = 20  # a keyframe at least this often [frames]
    keyframe_track_ratio: float = 0.75  # tracked / reference keyframe points below: keyframe
    keyframe_min_inliers: int = 100  # fewer tracked points: keyframe
    local_keyframes: int = 10  # covisible keyframes in the local map and local BA
    line_weight: float = 1.0  # weight of line terms against point terms in both BAs
    line_angle_weight: float = 10.0  # scale of the bounded angle term e3 [px]
    max_depth_baselines: float = 60.0  # stereo depths beyond this many baselines are unused
    point_sigma_px: float = 1.0  # keypoint measurement sigma [px]
    line_sigma_px: float = 3.0  # line endpoint distance sigma [px] (both endpoints share the
    # map line's error; 1.5 px over-weighted lines, see benchmarks/README.md)


@dataclass(frozen=True)
class Config:
    """Everything configurable; ``load_config`` reads it, ``dump_config`` writes it."""

    features: FeaturesConfig = field(default_factory=FeaturesConfig)
    tracking: TrackingConfig = field(default_factory=TrackingConfig)


def _build(cls: type, data: Any, where: str, source: Path | None):
    """Instantiate dataclass ``cls`` from a mapping, recursing into nested dataclasses."""
    if not isinstance(data, dict):
        raise ConfigError(source, f"'{where}' must be a mapping, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise ConfigError(source, f"unknown key '{where}.{unknown[0]}' (known: {sorted(names)})")
    values = {}
    for key, value in data.items():
        values[key] = _convert(hints[key], value, f"{where}.{key}", source)
    return cls(**values)


def _convert(hint: Any, value: Any, where: str, source: Path | None) -> Any:
    origin = typing.get_origin(hint)
    if dataclasses.is_dataclass(hint):
        return _build(hint, value, where, source)
    if origin is Literal:
        if value not in typing.get_args(hint):
            raise ConfigError(
                source, f"'{where}' must be one of {typing.get_args(hint)}, got {value!r}"
            )
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in typing.get_args(hint):
            return None
        errors = []
        for option in typing.get_args(hint):
            if option is type(None):
                continue
            try:
                return _convert(option, value, where, source)
            except ConfigError as exc:
                errors.append(exc.problem)
        raise ConfigError(source, errors[0] if errors else f"'{where}' has a wrong type")
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            raise ConfigError(source, f"'{where}' must be a list, got {value!r}")
        return tuple(value)
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(source, f"'{where}' must be true or false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, f"'{where}' must be an integer, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(source, f"'{where}' must be a number, got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(source, f"'{where}' must be a string, got {value!r}")
        return value
    return value


def config_from_dict(data: dict | None, source: Path | None = None) -> Config:
    """Build and check a :class:`Config` from a (partial) mapping."""
    config = _build(Config, data or {}, "config", source)
    try:
        config.features.superpoint.check()
    except ValueError as exc:
        raise ConfigError(source, f"features.superpoint: {exc}") from None
    return config


def load_config(path: str | Path | None) -> Config:
    """Read a YAML config (None: all defaults)."""
    if path is None:
        return Config()
    path = Path(path)
    if not path.is_file():
        raise ConfigError(path, "config file not found")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ConfigError(path, f"not valid YAML ({exc})") from None
    return config_from_dict(data, path)


def dump_config(config: Config, path: str | Path) -> Path:
    """Write the complete configuration (every key) as YAML, e.g. next to a run's results."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = dataclasses.asdict(config)
    path.write_text(yaml.safe_dump(_plain(data), sort_keys=False), encoding="utf-8")
    return path


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def make_point_frontend(config: FeaturesConfig):
    """The configured point front end. SuperPoint without weights (no model_path in the config
    and no $SLSLAM_SUPERPOINT_MODEL) falls back to ORB with one warning line."""
    from slslam.features.orb import Orb
    from slslam.features.superpoint import SuperPoint

    if config.point_frontend == "superpoint":
        if config.superpoint.model_path or os.environ.get(ENV_MODEL):
            return SuperPoint(config.superpoint)
        log.warning(
            "no SuperPoint weights (set %s or features.superpoint.model_path): "
            "using the ORB front end",
            ENV_MODEL,
        )
    return Orb(config.orb)
