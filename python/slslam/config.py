"""slslam's YAML configuration: typed sections with documented defaults.

A config file holds only the keys it changes; everything else keeps the default below (and in
``configs/default.yaml``, which lists every key with its meaning). Unknown keys and wrong types are
errors that name the file and the key, so a typo never passes silently.

    features:
      point_frontend: superpoint      # orb (the default) | xfeat | superpoint
      superpoint:
        model_path: /models/superpoint_v1.onnx   # overrides $SLSLAM_SUPERPOINT_MODEL

Front-end presets: a point front end may come with the settings it tracks best with
(``python/slslam/presets/<front end>.yaml``: ORB, the default, and XFeat have one).
``config_from_dict``, ``load_config`` and ``default_config`` apply the preset of the config's
front end under the config's own keys, so a key the config sets wins. ``Config()`` itself holds
the base defaults without any preset (the values ``configs/default.yaml`` documents).
"""

from __future__ import annotations

import dataclasses
import difflib
import logging
import math
import os
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import yaml

from slslam import _core
from slslam._cpp_defaults import as_written, core_attribute
from slslam.errors import InputError
from slslam.features.low_light import LowLightOptions
from slslam.features.orb import OrbOptions
from slslam.features.superpoint import ENV_MODEL, SuperPointOptions
from slslam.features.xfeat import XFeatOptions
from slslam.yaml_io import MAX_YAML_BYTES, read_yaml, short_repr

if TYPE_CHECKING:
    from slslam.features.orb import Orb
    from slslam.features.superpoint import SuperPoint
    from slslam.features.xfeat import XFeat

log = logging.getLogger(__name__)


class ConfigError(InputError):
    """A configuration file or value is malformed."""


@dataclass(frozen=True)
class Range:
    """The values a numeric option may take: a finite interval, each end closed or open.

    Written in interval notation, ``Range.parse("(0, 1]")``; the bound of an integer option also
    keeps it inside C++ ``int``, so no value reaches the core that it cannot hold. A mirrored
    option's range is the one its C++ ``Check()`` enforces (tests/python/test_config.py probes
    both ends of each); a positive value the core stores as ``float`` and that underflows to 0
    there (below 1e-38) is still refused, by the core's check.
    """

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    @classmethod
    def parse(cls, text: str) -> Range:
        low, high = (float(part) for part in text.strip()[1:-1].split(","))
        return cls(low, high, text.strip()[0] == "(", text.strip()[-1] == ")")

    def __contains__(self, value: float) -> bool:
        if not math.isfinite(value):
            return False
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def __str__(self) -> str:
        def show(x: float) -> str:
            return str(int(x)) if x == int(x) and abs(x) < 1e6 else f"{x:g}"

        left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
        return f"{left}{show(self.low)}, {show(self.high)}{right}"


def _option(default: float, interval: str) -> Any:
    """A dataclass field with its default and its allowed range (interval notation)."""
    return field(default=default, metadata={"range": Range.parse(interval)})


def _tracking(name: str, interval: str = "") -> Any:
    return _mirrored(_TRACKER, TRACKING_TO_CORE, name, interval)


def _loop_closing(name: str, interval: str = "") -> Any:
    return _mirrored(_TRACKER, LOOP_CLOSING_TO_CORE, name, interval)


def _dynamic_cells(name: str, interval: str = "") -> Any:
    return _mirrored(_TRACKER, DYNAMIC_CELLS_TO_CORE, name, interval)


def _imu(name: str, interval: str = "") -> Any:
    return _mirrored(_TRACKER, IMU_TO_CORE, name, interval)


def _lines(name: str, interval: str = "") -> Any:
    return _mirrored(_LINES, LINES_TO_CORE, name, interval)


def _grid(name: str, interval: str = "") -> Any:
    return _mirrored(_GRID, GRID_TO_CORE, name, interval)


# -- defaults: written once, in the C++ option structs -------------------------------------------
#: Where each config key goes in the C++ options (``_core.TrackerOptions``): the config section's
#: field -> attribute paths (one key may set several). The Python defaults of these keys are read
#: from the C++ defaults (the first path), so a default is written in one place; the tracker
#: applies the table (``slslam.tracking.tracker._core_options``) and tests/python/test_config.py
#: checks every path. The line front end's keys go to ``_core.LineExtractorOptions``
#: (LINES_TO_CORE); keys absent from all tables (point_frontend, pipeline, relocalisation,
#: vocabulary_path, the network front ends' options) are read in Python and have their defaults
#: here.
TRACKING_TO_CORE: dict[str, tuple[str, ...]] = {
    name: (name,)
    for name in (
        "use_lines",
        "sequential",
        "mapping_brake",
        "mapping_overlap",
        "min_init_points",
        "min_inliers",
        "search_radius_px",
        "match_ratio",
        "max_distance_binary",
        "max_distance_float",
        "line_search_px",
        "line_max_angle_rad",
        "line_max_lbd",
        "keyframe_max_frames",
        "keyframe_min_frames",
        "keyframe_min_frames_noisy",
        "keyframe_min_interval_s",
        "keyframe_track_ratio",
        "keyframe_min_inliers",
        "close_depth_baselines",
        "point_sigma_px",
        "track_refine_window_px",
        "triangulated_point_patches",
        "track_refine_max_px",
        "unaligned_sigma_factor",
        "unaligned_min_aligned",
        "unaligned_max_turn_deg_per_frame",
        "projected_max_frames",
        "projection_min_inliers",
        "projection_search_px",
        "projection_cell_px",
        "line_sigma_px",
        "line_inlier_weight",
        "recently_lost_frames",
        "lost_velocity_decay",
        "lost_search_scale",
        "lost_motion_frames",
        "lost_reentry_min_point_ratio",
        "lost_reentry_confirm_m",
        "new_map_after_lost_frames",
        "weak_keyframe_inliers",
        "weak_keyframe_frames",
        "frame_rate_hz",
        "reference_rate_hz",
        "reference_focal_px",
    )
} | {
    "max_depth_baselines": ("stereo.max_depth_baselines",),
    "stereo_row_search": ("stereo.row_search",),
    "row_search_window_px": ("stereo.row_search_window",),
    "subpixel_window_px": ("stereo.subpixel_window",),
    "right_lines_on_keyframes": ("right_lines_on_keyframes",),
    "lines_on_demand": ("lines_on_demand",),
    "lines_on_demand_inliers": ("lines_on_demand_inliers",),
    "denoise_above_noise": ("denoise_above_noise",),
    "local_keyframes": ("mapping.local_keyframes",),
    "triangulate_points": ("mapping.triangulation.points",),
    "triangulation_min_parallax_deg": ("mapping.triangulation.min_parallax_deg",),
    "line_weight": ("pose.line_weight", "mapping.ba.line_weight"),
    "line_angle_weight": ("pose.line_angle_weight", "mapping.ba.line_angle_weight"),
    "local_ba_line_prior_weight": ("mapping.ba.line_prior_weight",),
    "local_ba_dogleg": ("mapping.ba.dogleg_with_lines",),
    "own_pose_solver": ("pose.own_solver",),
    "own_local_ba_solver": ("mapping.ba.own_solver",),
    "local_ba_line_min_information_per_rad2": ("mapping.ba.line_min_information_per_rad2",),
}
LOOP_CLOSING_TO_CORE: dict[str, tuple[str, ...]] = {
    name: (f"loop_closing.{name}",)
    for name in (
        "enabled",
        "merge_maps",
        "global_ba",
        "yaw_and_position_with_gravity",
        "min_inliers",
        "consistency",
        "max_correction_ratio",
        "max_correction_floor_m",
        "welding_keyframes",
    )
}
IMU_TO_CORE: dict[str, tuple[str, ...]] = {
    "enabled": ("use_imu",),
    **{
        name: (f"imu.{name}",)
        for name in (
            "time_offset_s",
            "gyro_noise_density",
            "acc_noise_density",
            "gyro_random_walk",
            "acc_random_walk",
            "gravity_mps2",
            "gravity_tolerance_mps2",
            "acc_bias_prior_mps2",
            "gyro_bias_sigma_radps",
            "window_s",
            "min_window_s",
            "refine_after_s",
            "refine_min_path_m",
            "max_sample_gap_s",
            "lost_sigma_fraction",
            "lost_sigma_min_m",
            "max_gap_s",
            "resume_map_after_lost",
            "nonholonomic_max_side_ratio",
            "nonholonomic_sigma_mps",
            "zero_velocity_max_statistic",
            "zero_velocity_sigma_mps",
            "flow_min_inliers",
            "flow_sigma_mps",
            "weak_update_min_inliers",
            "weak_update_min_lines",
            "keyframe_min_stereo_lines",
            "keyframe_interval_s",
            "visual_information_scale",
            "local_ba_keyframes",
        )
    },
}
LINES_TO_CORE: dict[str, tuple[str, ...]] = {
    "line_detection_scale": ("detection_scale",),
    "line_detector": ("detector",),
    "line_descriptor": ("descriptor",),
    "max_lines": ("max_lines",),
}
DYNAMIC_CELLS_TO_CORE: dict[str, tuple[str, ...]] = {
    "enabled": ("dynamic_cells",),
    **{
        name: (f"dynamic.{name}",)
        for name in (
            "cell_size_px",
            "sigma_px",
            "alpha",
            "threshold",
            "min_matches",
            "sigma_median_ratio",
        )
    },
}
GRID_TO_CORE: dict[str, tuple[str, ...]] = {
    "cell_size_px": ("cell_size_px",),
    "max_per_cell": ("max_per_cell",),
}


_TRACKER = _core.TrackerOptions()
_LINES = _core.LineExtractorOptions()
_GRID = _core.GridLimitOptions()


def _mirrored(
    options: Any, table: dict[str, tuple[str, ...]], name: str, interval: str = ""
) -> Any:
    """A dataclass field whose default is the C++ default (``table[name]`` of ``options``) and
    whose allowed range is ``interval`` (none: any value of the type)."""
    default = as_written(core_attribute(options, table[name][0]))
    return _option(default, interval) if interval else field(default=default)


#: Ranges of the options whose dataclasses live with their front end (slslam.features).
FOREIGN_RANGES: dict[type, dict[str, Range]] = {
    OrbOptions: {
        "max_keypoints": Range.parse("[1, 100000]"),
        "scale_factor": Range.parse("[1.01, 4]"),
        "num_levels": Range.parse("[1, 32]"),
        # not below the core's fallback threshold for weak cells (OrbOptions.min_fast_threshold, 7)
        "fast_threshold": Range.parse("[7, 255]"),
    },
    SuperPointOptions: {
        "detection_threshold": Range.parse("(0, 1)"),
        "nms_radius": Range.parse("[0, 100]"),
        "border_px": Range.parse("[0, 1000]"),
        "max_keypoints": Range.parse("[1, 100000]"),
        "intra_op_threads": Range.parse("[0, 1024]"),
    },
    XFeatOptions: {
        "detection_threshold": Range.parse("(0, 1)"),
        "nms_radius": Range.parse("[0, 100]"),
        "border_px": Range.parse("[0, 1000]"),
        "max_keypoints": Range.parse("[1, 100000]"),
        "intra_op_threads": Range.parse("[0, 1024]"),
        "denoise_above_noise": Range.parse("[0, 255]"),
    },
    # the bounds LowLightOptions.check states
    LowLightOptions: {
        "below_mean_gray": Range.parse("[0, 255]"),
        "target_mean_gray": Range.parse("[1, 254]"),
        "min_gamma": Range.parse("[0.05, 1]"),
        "clahe_clip_limit": Range.parse("[0.1, 100]"),
        "clahe_tile_px": Range.parse("[8, 4096]"),
    },
}
#: Where an option declares no range: finite, and an integer must fit a C++ int.
INT_FALLBACK = Range(-(2**31), 2**31 - 1)
FLOAT_FALLBACK = Range(-math.inf, math.inf, True, True)


@dataclass(frozen=True)
class GridConfig:
    """Per-cell keypoint limit (the SL-SLAM paper's grid limitation); mirrors C++
    ``GridLimitOptions``."""

    cell_size_px: int = _grid("cell_size_px", "[4, 4096]")  # P: cell side [px]
    max_per_cell: int = _grid("max_per_cell", "[1, 10000]")  # keypoints kept per cell


@dataclass(frozen=True)
class DynamicCellConfig:
    """Invalid-cell filter for moving objects (SL-SLAM paper), applied in tracking; mirrors C++
    ``DynamicCellOptions`` (``TrackerOptions.dynamic``; ``enabled`` is ``dynamic_cells``)."""

    enabled: bool = _dynamic_cells("enabled")
    cell_size_px: int = _dynamic_cells("cell_size_px", "[4, 65536]")  # cell side [px]
    sigma_px: float = _dynamic_cells("sigma_px", "(0, 1000000]")  # Gaussian width of G(d) [px]
    # weight of the current frame in the temporal smoothing
    alpha: float = _dynamic_cells("alpha", "(0, 1]")
    # l: a cell below this weight is invalid (with its 8 neighbours)
    threshold: float = _dynamic_cells("threshold", "[0, 1]")
    # matches a cell needs in a frame to count as evidence (fewer: the cell counts as static)
    min_matches: int = _dynamic_cells("min_matches", "[1, 1000000]")
    # G's width is at least this many times the frame's median match residual, for a front end
    # that repeats less precisely than ORB (XFeat: 2, presets/xfeat.yaml); 0: sigma_px alone
    sigma_median_ratio: float = _dynamic_cells("sigma_median_ratio", "[0, 1000]")


@dataclass(frozen=True)
class FeaturesConfig:
    """The point front end."""

    # ORB: the front end that is at least as accurate as the learned ones on every sequence
    # benchmarks/kitti.py and benchmarks/tracking_recovery.py run (real KITTI among them); its
    # preset (presets/orb.yaml) is applied by config_from_dict / load_config / default_config,
    # not by FeaturesConfig()
    point_frontend: Literal["superpoint", "xfeat", "orb"] = "orb"
    superpoint: SuperPointOptions = field(default_factory=SuperPointOptions)
    xfeat: XFeatOptions = field(default_factory=XFeatOptions)  # weights shipped (Apache-2.0)
    # dark frames enhanced before the front end (gamma curve or CLAHE; off by default)
    low_light: LowLightOptions = field(default_factory=LowLightOptions)
    orb: OrbOptions = field(default_factory=OrbOptions)
    grid: GridConfig = field(default_factory=GridConfig)
    dynamic_cells: DynamicCellConfig = field(default_factory=DynamicCellConfig)
    # cells with no keypoint at the detector's threshold keep weaker ones (ORB: FAST 20 -> 7 per
    # cell, as ORB-SLAM; learned detectors: detection_threshold * low_texture_ratio)
    low_texture_fallback: bool = True
    low_texture_ratio: float = _option(0.2, "(0, 1]")


@dataclass(frozen=True)
class LoopClosingConfig:
    """Loop closing and map merging; mirrors C++ ``LoopClosingOptions`` (needs the vocabulary)."""

    # close loops within a map (essential graph, then global BA)
    enabled: bool = _loop_closing("enabled")
    # merge a map into an older one when place recognition links them
    merge_maps: bool = _loop_closing("merge_maps")
    # global bundle adjustment over points and lines after a loop / merge
    global_ba: bool = _loop_closing("global_ba")
    # a map whose gravity the IMU gave corrects loops in yaw and position only (4 DoF)
    yaw_and_position_with_gravity: bool = _loop_closing("yaw_and_position_with_gravity")
    # weighted inliers (points + lines) of the candidate's local map a loop needs
    min_inliers: float = _loop_closing("min_inliers", "(0, 100000]")
    # consecutive keyframes whose verified loop transforms must agree
    consistency: int = _loop_closing("consistency", "[1, 100]")
    # same map: largest correction as a share of the path driven since the loop keyframe (a
    # repeated arch seen as the old one gives a confident, implausibly large jump)
    max_correction_ratio: float = _loop_closing("max_correction_ratio", "[0, 1]")
    # correction always allowed [m]
    max_correction_floor_m: float = _loop_closing("max_correction_floor_m", "[0, 1000]")
    # welding BA after a merge: the merged keyframe and the candidate, each with this many best
    # covisible keyframes, optimised before the global BA (0: none)
    welding_keyframes: int = _loop_closing("welding_keyframes", "[0, 1000]")


@dataclass(frozen=True)
class ImuConfig:
    """The IMU tightly coupled in tracking (docs/imu.md); mirrors C++ ``InertialOptions``
    (``TrackerOptions.imu``; ``enabled`` is ``use_imu``). Used when the sequence has IMU samples
    (EuRoC ``imu0/``, a bag's ``--imu`` topic) or they are given to ``Tracker.add_imu``; the
    camera's pose in the IMU frame is the calibration's ``T_body_cam``."""

    # use the IMU: initialisation from the first seconds of tracking, then its prediction and
    # prior in every frame, its propagated pose where the camera cannot track (INERTIAL)
    enabled: bool = _imu("enabled")
    time_offset_s: float = _imu("time_offset_s", "[-10, 10]")  # t_cam = t_imu + this [s]
    # IMU noise, Kalibr / EuRoC sensor.yaml units
    gyro_noise_density: float = _imu("gyro_noise_density", "[0, 1]")  # [rad/s/sqrt(Hz)]
    acc_noise_density: float = _imu("acc_noise_density", "[0, 1]")  # [m/s^2/sqrt(Hz)]
    gyro_random_walk: float = _imu("gyro_random_walk", "[0, 1]")  # [rad/s^2/sqrt(Hz)]
    acc_random_walk: float = _imu("acc_random_walk", "[0, 1]")  # [m/s^3/sqrt(Hz)]
    gravity_mps2: float = _imu("gravity_mps2", "(0, 20)")  # expected |g| [m/s^2]
    # an initialisation whose unconstrained gravity is further off is refused [m/s^2]
    gravity_tolerance_mps2: float = _imu("gravity_tolerance_mps2", "(0, 100]")
    # sigma of the accelerometer bias about zero before motion shows it: the initialisation's
    # prior, and the state's sigma after it (at most 0.1) [m/s^2]
    acc_bias_prior_mps2: float = _imu("acc_bias_prior_mps2", "(0, 100]")
    # sigma of the gyroscope bias in the state after an initialisation, or the fit's own if
    # larger (looser: the frames turn it with a map that turns slowly through weak texture) [rad/s]
    gyro_bias_sigma_radps: float = _imu("gyro_bias_sigma_radps", "(0, 1]")
    window_s: float = _imu("window_s", "[0.1, 1000]")  # tracked poses the initialisation uses [s]
    # the initialisation needs tracked poses spanning at least this [s] (at most window_s)
    min_window_s: float = _imu("min_window_s", "[0.05, 1000]")
    # the initialisation runs again this long after the first [s] ...
    refine_after_s: float = _imu("refine_after_s", "[0, 1000000]")
    # ... over a window in which the body moved at least this far [m]
    refine_min_path_m: float = _imu("refine_min_path_m", "[0, 1000000]")
    # IMU samples further apart than this: no propagation across the hole [s]
    max_sample_gap_s: float = _imu("max_sample_gap_s", "(0, 10]")
    # lost when the position sigma passes this fraction of the distance driven since the last
    # frame the camera tracked ...
    lost_sigma_fraction: float = _imu("lost_sigma_fraction", "[0, 10]")
    lost_sigma_min_m: float = _imu("lost_sigma_min_m", "[0, 1000000]")  # ... or this floor [m]
    max_gap_s: float = _imu("max_gap_s", "[0, 1000000]")  # and after this long without vision [s]
    # past the lost bound the IMU dead-reckons on (until max_gap_s) and the first frame that could
    # start a map resumes the one it left, a keyframe at the IMU's pose, unless the state's speed
    # ran away (false: a new map)
    resume_map_after_lost: bool = _imu("resume_map_after_lost")
    # a frame without vision holds the body's velocity to the axis of travel when, over 2 s of
    # tracked driving, the velocity across it was at most this fraction of the speed (RMS): a
    # ground vehicle's non-holonomic constraint (0: never) [-]
    nonholonomic_max_side_ratio: float = _imu("nonholonomic_max_side_ratio", "[0, 1]")
    # ... within this sigma, or the RMS side speed measured while tracked when larger [m/s]
    nonholonomic_sigma_mps: float = _imu("nonholonomic_sigma_mps", "(0, 100]")
    # a frame without vision whose last 0.5 s of IMU samples show the body at rest (the SHOE
    # statistic, about 1 at rest, at most this) is held at zero velocity, unless the state
    # disagrees beyond 99.9 % (0: never) [-]
    zero_velocity_max_statistic: float = _imu("zero_velocity_max_statistic", "[0, 1000000]")
    # ... within this sigma [m/s]
    zero_velocity_sigma_mps: float = _imu("zero_velocity_sigma_mps", "(0, 100]")
    # a frame the camera does not track takes the body's velocity from optical flow (corners
    # tracked from the frame before, PnP on their stereo depths) with this many inliers, unless
    # the state disagrees beyond 99.9 % (0: never) [-]
    flow_min_inliers: int = _imu("flow_min_inliers", "[0, 100000]")
    # ... within at least this sigma per axis [m/s]
    flow_sigma_mps: float = _imu("flow_sigma_mps", "(0, 100]")
    # a frame not tracked (fewer than min_inliers) still corrects the state with this many
    # inliers (0: never)
    weak_update_min_inliers: int = _imu("weak_update_min_inliers", "[0, 100000]")
    # ... and with this many line inliers (0: never): a lining's wall-floor edges, where the
    # points are noise
    weak_update_min_lines: int = _imu("weak_update_min_lines", "[0, 100000]")
    # an INERTIAL frame with too few stereo points becomes such a keyframe with this many stereo
    # lines (0: points only)
    keyframe_min_stereo_lines: int = _imu("keyframe_min_stereo_lines", "[0, 100000]")
    # an INERTIAL frame with stereo points for a map becomes a keyframe at the IMU's pose when the
    # last keyframe is this old: the map goes on where it did not reach (0: never) [s]
    keyframe_interval_s: float = _imu("keyframe_interval_s", "[0, 1000000]")
    # the pose optimiser's information is scaled by this before it corrects the state
    visual_information_scale: float = _imu("visual_information_scale", "[1e-06, 1000000]")
    # local BA also estimates the velocity and IMU biases of the last this many keyframes of the
    # IMU chain, with the preintegrated IMU between consecutive ones (0: a visual local BA)
    local_ba_keyframes: int = _imu("local_ba_keyframes", "[0, 1000]")

    def relations_error(self, where: str) -> str | None:
        """The C++ check between two keys (InertialOptions::Check), as a message naming
        both, or None."""
        if self.min_window_s > self.window_s:
            return (
                f"'{where}.min_window_s' ({self.min_window_s}) must not exceed "
                f"'{where}.window_s' ({self.window_s})"
            )
        return None


@dataclass(frozen=True)
class TrackingConfig:
    """Tracking and local mapping (SL-SLAM paper, ORB-SLAM3); mirrors C++ ``TrackerOptions``."""

    use_lines: bool = _tracking("use_lines")  # line features in tracking and mapping
    # local mapping inline: exactly reproducible; false: own thread
    sequential: bool = _tracking("sequential")
    # threaded mode only: ORB-SLAM3's brake on keyframes while local mapping is busy (more
    # frames/s, worse ATE on the hard dark sequences: off)
    mapping_brake: bool = _tracking("mapping_brake")
    # sequential mode only: each keyframe's local BA solves on its own thread while tracking goes
    # on, applied when the next keyframe comes (still exactly reproducible, unless the settled
    # map is asked for mid-run: flush, save_map, final_trajectory and map() apply it early)
    mapping_overlap: bool = _tracking("mapping_overlap")
    # point front end of frame k+1 on a worker thread while the core tracks frame k (same poses)
    pipeline: bool = True
    # frames the pipeline's worker may have prepared and the core not yet taken: more lets the
    # front end run on through a keyframe's local mapping (more frames/s offline at 3 than at 1,
    # benchmarks/log/realtime.md; a live camera's frames are taken as they come either way)
    pipeline_frames_ahead: int = _option(3, "[1, 64]")
    # stereo points a frame needs to start a map
    min_init_points: int = _tracking("min_init_points", "[3, 1000000]")
    # fewer inliers after motion-only BA: the frame is LOST
    min_inliers: int = _tracking("min_inliers", "[3, 1000000]")
    # guided matching window [px] (doubled on a retry)
    search_radius_px: float = _tracking("search_radius_px", "(0, 100000]")
    # best / second best inside the guided-matching window
    match_ratio: float = _tracking("match_ratio", "(0, 1]")
    # guided matching bound for ORB [Hamming bits]
    max_distance_binary: float = _tracking("max_distance_binary", "(0, 256]")
    # guided matching bound for SuperPoint [L2] (unit descriptors: at most 2)
    max_distance_float: float = _tracking("max_distance_float", "(0, 1000000]")
    # map line to frame segment: midpoint distance to the predicted line [px], angle [rad], LBD
    # distance [bits]
    line_search_px: float = _tracking("line_search_px", "(0, 100000]")
    line_max_angle_rad: float = _tracking("line_max_angle_rad", "(0, 3.14159265]")
    line_max_lbd: float = _tracking("line_max_lbd", "(0, 256]")
    # a keyframe at least this often [frames]
    keyframe_max_frames: int = _tracking("keyframe_max_frames", "[1, 1000000000]")
    # no keyframe sooner than this after the last while tracking is strong [frames]
    keyframe_min_frames: int = _tracking("keyframe_min_frames", "[0, 1000000000]")
    # ... in a noisy (dark, smoothed) frame instead [frames] (-1: keyframe_min_frames)
    keyframe_min_frames_noisy: int = _tracking("keyframe_min_frames_noisy", "[-1, 1000000000]")
    # ... nor sooner than this [s] (a gap in time, the same at any camera rate; 0: none)
    keyframe_min_interval_s: float = _tracking("keyframe_min_interval_s", "[0, 1000000]")
    # tracked / reference keyframe points below: keyframe
    keyframe_track_ratio: float = _tracking("keyframe_track_ratio", "(0, 1]")
    # fewer tracked points: keyframe
    keyframe_min_inliers: int = _tracking("keyframe_min_inliers", "[0, 1000000000]")
    # "close" stereo points for the rule above: depth below this many baselines
    close_depth_baselines: float = _tracking("close_depth_baselines", "(0, 1000000]")
    # covisible keyframes in the local map and local BA
    local_keyframes: int = _tracking("local_keyframes", "[1, 10000]")
    # local mapping also makes points from pairs of keyframes, out of the keypoints stereo left
    # without a match (flat, ambiguous along the row, far), from their detected positions; false:
    # points from stereo only (at 1 degree, without them XFeat + lines drifted less on the dark
    # 600-frame sequences but more on the short dark loops, benchmarks/log/realtime.md)
    triangulate_points: bool = _tracking("triangulate_points")
    # ... and only where the two rays meet at this angle at least [deg]
    triangulation_min_parallax_deg: float = _tracking("triangulation_min_parallax_deg", "[0, 180]")
    # weight of line terms against point terms in both BAs
    line_weight: float = _tracking("line_weight", "[0, 1000000]")
    # scale of the bounded angle term e3 [px] (0: endpoint distances only)
    line_angle_weight: float = _tracking("line_angle_weight", "[0, 1000000]")
    # local BA: each line's pull towards its value at the start of each pass [1/rad] (0: none);
    # with local_ba_dogleg a local BA with lines takes less time, but the drift moved both ways
    # over three seeds (benchmarks/log/realtime.md), so off
    local_ba_line_prior_weight: float = _tracking("local_ba_line_prior_weight", "[0, 1000000]")
    # local BA with lines: Powell's dogleg instead of Levenberg-Marquardt (a rejected step costs
    # no linear solve); needs local_ba_line_prior_weight > 0
    local_ba_dogleg: bool = _tracking("local_ba_dogleg")
    # motion-only BA by slslam's own 6-parameter Levenberg-Marquardt instead of a Ceres problem
    # per outlier round (the same costs and trust-region rules, faster: no problem to build);
    # false: a Ceres problem per round (benchmarks/log/realtime.md)
    own_pose_solver: bool = _tracking("own_pose_solver")
    # local BA by slslam's own Levenberg-Marquardt with the points and lines eliminated (the same
    # costs, trust-region rules and steps, a dense reduced system over the window's free
    # keyframes; faster) instead of Ceres' sparse Schur solver (benchmarks/log/realtime.md);
    # false: Ceres
    own_local_ba_solver: bool = _tracking("own_local_ba_solver")
    # local BA: each line moves only in the directions of its tangent whose information (its
    # observations' J^T J eigenvalues, in sigmas) reaches this, held in the others [1/rad^2]
    # (0: free in all four; 1: less drift in the dark with the IMU over five simulator seeds,
    # but camera-only recovery after a blackout came out worse, so off; benchmarks/log/realtime.md)
    local_ba_line_min_information_per_rad2: float = _tracking(
        "local_ba_line_min_information_per_rad2", "[0, 1e12]"
    )
    # stereo depths beyond this many baselines are unused
    max_depth_baselines: float = _tracking("max_depth_baselines", "(0, 1000000]")
    # stereo points without right-image keypoints: the point front end runs on the left image
    # only and each keypoint's patch is searched along its row of the right image (half the
    # network's work for a learned front end); false: keypoints on both images, matched by
    # descriptor along the row band
    stereo_row_search: bool = _tracking("stereo_row_search")
    # half size of the row search's patch [px]
    row_search_window_px: int = _tracking("row_search_window_px", "[1, 50]")
    # half size of the patch that refines stereo disparities to subpixel precision [px]; 0: off
    subpixel_window_px: int = _tracking("subpixel_window_px", "[0, 100]")
    # line segments of the right image only for frames that become keyframes or start a map, the
    # only ones whose stereo lines are used (tracking matches the left image's lines to the map);
    # false: both images every frame
    right_lines_on_keyframes: bool = _tracking("right_lines_on_keyframes")
    # the left image's lines only for the frames that use them: a frame after one tracked with
    # fewer than lines_on_demand_inliers point inliers, a frame its points alone do not track,
    # a keyframe (its lines matched from the pose its points gave), a new map and every frame
    # while lost; the frames between keyframes of a well-textured stretch skip line detection
    # and LBD. Applies with right_lines_on_keyframes; false: every frame's lines
    lines_on_demand: bool = _tracking("lines_on_demand")
    # point inliers below which the next frame is tracked with its lines (lines_on_demand) [-]
    lines_on_demand_inliers: int = _tracking("lines_on_demand_inliers", "[0, 1000000000]")
    # images noisier than this (Immerkaer's estimate, gray levels) reach line detection, line
    # descriptors and stereo matching Gaussian-smoothed, sigma = noise / 7 px, as ORB's detection
    # image (0: never)
    denoise_above_noise: float = _tracking("denoise_above_noise", "[0, 255]")
    # keypoint measurement sigma [px]
    point_sigma_px: float = _tracking("point_sigma_px", "(0, 10000]")
    # half size of the patch each map point keeps from the keyframe that made it: later matches
    # are aligned to it (scaled by the point's change of depth) instead of taking the detected
    # keypoint position as it is [px]; 0: off
    track_refine_window_px: int = _tracking("track_refine_window_px", "[0, 50]")
    # points triangulated by local mapping keep such a patch too, of the new keyframe's left
    # image (false: only the points made from stereo in the tracker's keyframes have one)
    triangulated_point_patches: bool = _tracking("triangulated_point_patches")
    # an alignment that moves the keypoint further than this is not taken [px]
    track_refine_max_px: float = _tracking("track_refine_max_px", "(0, 100000]")
    # in a frame smoothed as noisy with at least unaligned_min_aligned matches aligned to their
    # map points' patches, the matches that could not be aligned enter the motion-only BA with
    # their sigma times this (detected keypoints follow a small image motion only in part; see
    # benchmarks/log/realtime.md) [-]; 1: all alike
    unaligned_sigma_factor: float = _tracking("unaligned_sigma_factor", "[1, 1000]")
    # aligned matches a noisy frame needs for unaligned_sigma_factor to apply [-]
    unaligned_min_aligned: int = _tracking("unaligned_min_aligned", "[0, 1000000000]")
    # ... and while the camera turned by at most this between the last two frames (a turn on the
    # spot weighs all matches alike) [deg per frame]
    unaligned_max_turn_deg_per_frame: float = _tracking(
        "unaligned_max_turn_deg_per_frame", "[0, 180]"
    )
    # frames tracked on projected keypoints, at most this many in a row: while tracking is strong
    # the local map's points are projected with the predicted pose and aligned to their patches
    # (semi-direct, as SVO between keyframes), and the point front end runs only on the frames
    # the tracker hands back (keyframes, weak tracking, after this many) [frames]; 0: every
    # frame's keypoints are detected
    projected_max_frames: int = _tracking("projected_max_frames", "[0, 1000000000]")
    # point inliers the frame before must have held, and a projected frame must hold, else it
    # is tracked on detected keypoints [-]
    projection_min_inliers: int = _tracking("projection_min_inliers", "[0, 1000000000]")
    # search radius of the shift common to all projected points (the prediction's rotation
    # error) [px]
    projection_search_px: int = _tracking("projection_search_px", "[0, 64]")
    # at most one projected point per square cell of this size [px]
    projection_cell_px: int = _tracking("projection_cell_px", "[1, 1000]")
    # line endpoint distance sigma [px] (both endpoints share the map line's error; 1.5 px
    # over-weighted lines, see benchmarks/log/tracking_ablation.md)
    line_sigma_px: float = _tracking("line_sigma_px", "(0, 10000]")
    # LSD runs on the image scaled by this (segments mapped back; OpenCV's LBD at full
    # resolution, ours on the scaled image)
    line_detection_scale: float = _lines("line_detection_scale", "[0.1, 1]")
    # segment detector: lsd (the paper's, ours), lsd_opencv (OpenCV's LSD) or fld (OpenCV's
    # FastLineDetector)
    line_detector: Literal["lsd", "lsd_opencv", "fld"] = _lines("line_detector")
    # segment descriptor: opencv_lbd (OpenCV's BinaryDescriptor's bytes, computed here) or lbd
    # (ours, from the LBD paper, cheaper on the half-size image but less accurate tracking, see
    # benchmarks/log/realtime.md); a saved map keeps the kind it was made with
    line_descriptor: Literal["opencv_lbd", "lbd"] = _lines("line_descriptor")
    # keep at most this many segments per image after preprocessing, the longest (0: all)
    max_lines: int = _lines("max_lines", "[0, 100000]")
    # a line inlier counts as this many point inliers when deciding LOST, keyframes and a new map
    # (0: points only)
    line_inlier_weight: float = _tracking("line_inlier_weight", "[0, 1000000]")
    # frames of RECENTLY_LOST (wider window, decaying velocity, relocalisation into the active
    # map) before LOST, where the pose is frozen [frames]
    recently_lost_frames: int = _tracking("recently_lost_frames", "[0, 1000000000]")
    # per-frame factor on the predicted motion while recently lost
    lost_velocity_decay: float = _tracking("lost_velocity_decay", "[0, 1]")
    # guided-matching window factor while recently lost
    lost_search_scale: float = _tracking("lost_search_scale", "[1, 1000]")
    # lost: the motion before the loss, along which the local map is tried, is the mean per-frame
    # motion over this many frames (1: the last frame's; one frame's jitter extrapolated over a
    # blackout re-entered a repeated roadway off the truth; benchmarks/log/realtime.md)
    lost_motion_frames: int = _tracking("lost_motion_frames", "[1, 1000]")
    # lost: a re-entry along the motion before the loss needs this share of its point matches
    # as inliers (lines do not count: a wrong pose gathers line inliers along the lines)
    lost_reentry_min_point_ratio: float = _tracking("lost_reentry_min_point_ratio", "[0, 1]")
    # lost: a re-entry short of twice min_inliers is taken (with min_inliers) where the previous
    # frame's attempt, moved one step along the loss motion, lies within this distance (and 5
    # degrees) of it; 0: off [m]
    lost_reentry_confirm_m: float = _tracking("lost_reentry_confirm_m", "[0, 100]")
    # lost: frames that could start a map which must fail to come back into the old maps before
    # a new map starts (black frames do not count) [frames]
    new_map_after_lost_frames: int = _tracking("new_map_after_lost_frames", "[0, 1000000000]")
    # weighted inliers below this: a keyframe every weak_keyframe_frames (thin tracking)
    weak_keyframe_inliers: int = _tracking("weak_keyframe_inliers", "[0, 1000000000]")
    weak_keyframe_frames: int = _tracking("weak_keyframe_frames", "[1, 1000000000]")  # [frames]
    # the camera's frame rate [Hz]; 0: the sequence's (EuRoC sensor.yaml or timestamps, KITTI
    # times.txt, a bag's stamps, the simulator's), or unknown (Python API without it)
    frame_rate_hz: float = _tracking("frame_rate_hz", "[0, 100000]")
    # the rate the options counted in frames (keyframe gaps, recently_lost_frames,
    # lost_motion_frames, new_map_after_lost_frames, projected_max_frames) and per frame
    # (lost_velocity_decay, unaligned_max_turn_deg_per_frame) are given at [Hz]: at another
    # camera rate each becomes count * frame_rate_hz / reference_rate_hz (the same time); 0: the
    # counts as given at every rate
    reference_rate_hz: float = _tracking("reference_rate_hz", "[0, 100000]")
    # the focal length search_radius_px, line_search_px, projection_search_px and
    # projection_cell_px are given at [px]: scaled by the camera's fx / this (the same angle);
    # 0: as given
    reference_focal_px: float = _tracking("reference_focal_px", "[0, 10000000]")
    relocalisation: bool = True  # bag-of-words relocalisation when lost (needs a vocabulary)
    # BoW vocabulary file; null: the one shipped for ORB (learned descriptors need their own,
    # made with `slslam vocab train`)
    vocabulary_path: str | None = None
    loop_closing: LoopClosingConfig = field(default_factory=LoopClosingConfig)
    imu: ImuConfig = field(default_factory=ImuConfig)

    def relations_error(self, where: str) -> str | None:
        """Options that need another one set (the C++ solvers take them silently), as a
        message naming both, or None."""
        if self.local_ba_dogleg and self.local_ba_line_prior_weight <= 0:
            return (
                f"'{where}.local_ba_dogleg' needs '{where}.local_ba_line_prior_weight' > 0 "
                f"(got {self.local_ba_line_prior_weight}): without the pull its steps fail"
            )
        return None


@dataclass(frozen=True)
class Config:
    """Everything configurable; ``load_config`` reads it, ``dump_config`` writes it."""

    features: FeaturesConfig = field(default_factory=FeaturesConfig)
    tracking: TrackingConfig = field(default_factory=TrackingConfig)


def _build(cls: type, data: Any, where: str, source: Path | None) -> Any:
    """Instantiate dataclass ``cls`` from a mapping, recursing into nested dataclasses."""
    if not isinstance(data, dict):
        raise ConfigError(source, f"'{where}' must be a mapping, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(str(key) for key in set(data) - names)
    if unknown:
        key = short_repr(unknown[0], 40).strip("'")
        if len(names) <= 12:
            hint = "known: " + ", ".join(sorted(names))
        else:  # a long section: the likely ones, and where all of them are documented
            close = difflib.get_close_matches(str(unknown[0]), sorted(names), n=3, cutoff=0.6)
            hint = (f"did you mean {' or '.join(close)}? " if close else "") + (
                f"{len(names)} keys, documented in configs/default.yaml"
            )
        raise ConfigError(source, f"unknown key '{where}.{key}' ({hint})")
    values = {}
    for key, value in data.items():
        values[key] = _convert(hints[key], value, f"{where}.{key}", source)
    return cls(**values)


def _convert(hint: Any, value: Any, where: str, source: Path | None) -> Any:
    origin = typing.get_origin(hint)
    if dataclasses.is_dataclass(hint):
        return _build(typing.cast(type, hint), value, where, source)
    if origin is Literal:
        if value not in typing.get_args(hint):
            raise ConfigError(
                source,
                f"'{where}' must be one of {typing.get_args(hint)}, got {short_repr(value)}",
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
            raise ConfigError(source, f"'{where}' must be a list, got {short_repr(value)}")
        item = typing.get_args(hint)[0]
        return tuple(_convert(item, v, f"{where}[{i}]", source) for i, v in enumerate(value))
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(source, f"'{where}' must be true or false, got {short_repr(value)}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, f"'{where}' must be an integer, got {short_repr(value)}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(source, f"'{where}' must be a number, got {short_repr(value)}")
        try:
            return float(value)
        except OverflowError:  # an integer beyond any float: out of every range
            raise ConfigError(source, f"'{where}' is too large: {short_repr(value)}") from None
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(source, f"'{where}' must be a string, got {short_repr(value)}")
        return value
    return value


def option_range(cls: type, f: dataclasses.Field) -> Range | None:
    """The declared range of numeric option ``f`` of dataclass ``cls`` (None: none declared)."""
    return f.metadata.get("range") or FOREIGN_RANGES.get(cls, {}).get(f.name)


def _numeric_kind(hint: Any) -> type | None:
    """int or float when the option holds that number (possibly Optional), else None."""
    if hint in (int, float):
        return hint
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        kinds = [a for a in typing.get_args(hint) if a in (int, float)]
        return kinds[0] if len(kinds) == 1 else None
    return None


def check_config(config: Any, source: Path | None = None, where: str = "config") -> None:
    """Check every numeric option of ``config`` (a Config or any of its sections) against its
    range: finite, inside the interval, an integer where one is meant; and the relations between
    keys of a section that declares them (``relations_error``). Raises ConfigError naming the key.
    Also catches values set in code (``dataclasses.replace``) before they reach C++."""
    hints = typing.get_type_hints(type(config))
    for f in dataclasses.fields(config):
        value, key = getattr(config, f.name), f"{where}.{f.name}"
        if dataclasses.is_dataclass(value):
            check_config(value, source, key)
            continue
        if f.name == "providers" and isinstance(value, tuple) and not value:
            raise ConfigError(
                source, f"'{key}' is an empty list: name at least one onnxruntime provider, or auto"
            )
        kind = _numeric_kind(hints[f.name])
        if kind is None or value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(source, f"'{key}' must be a number, got {short_repr(value)}")
        if kind is int and not isinstance(value, int):
            raise ConfigError(source, f"'{key}' must be an integer, got {short_repr(value)}")
        declared = option_range(type(config), f)
        allowed = declared or (INT_FALLBACK if kind is int else FLOAT_FALLBACK)
        try:
            inside = value in allowed
        except OverflowError:  # an integer too large to compare as a float
            inside = False
        if not inside:
            raise ConfigError(
                source,
                f"'{key}' must be a finite number in {allowed}, got {short_repr(value)}"
                if kind is float
                else f"'{key}' must be an integer in {allowed}, got {short_repr(value)}",
            )
    relations = getattr(config, "relations_error", None)
    message = relations(where) if relations is not None else None
    if message:
        raise ConfigError(source, message)


#: Each point front end's preset, where it has one (a YAML file of config keys).
PRESETS_DIR = Path(__file__).resolve().parent / "presets"
POINT_FRONTENDS: tuple[str, ...] = typing.get_args(
    typing.get_type_hints(FeaturesConfig)["point_frontend"]
)


def frontend_preset(point_frontend: str) -> dict:
    """The config keys ``point_frontend`` is tuned with (``presets/<name>.yaml``; {} when it has
    no preset). A fresh dict on every call."""
    if point_frontend not in POINT_FRONTENDS:
        raise ValueError(f"point_frontend must be one of {POINT_FRONTENDS}, got {point_frontend!r}")
    path = PRESETS_DIR / f"{point_frontend}.yaml"
    if not path.is_file():
        return {}
    data = read_yaml(path, ConfigError, max_bytes=MAX_YAML_BYTES)
    return data if isinstance(data, dict) else {}


def merged(base: dict, top: dict) -> dict:
    """``base`` with ``top``'s keys over it, nested mappings merged key by key (config mappings;
    the benchmarks merge their --set overrides with it too)."""
    out = dict(base)
    for key, value in top.items():
        both = isinstance(value, dict) and isinstance(out.get(key), dict)
        out[key] = merged(out[key], value) if both else value
    return out


def _features_mapping(data: Any) -> dict | None:
    """The ``features`` mapping of a config mapping ({} when absent), None when malformed
    (``_build`` reports it, naming the key)."""
    if not isinstance(data, dict):
        return None
    features = data.get("features", {})
    return features if isinstance(features, dict) else None


def _with_preset(data: Any) -> Any:
    """``data`` (a config mapping) over the preset of the front end it names (the default
    front end when it names none). Malformed mappings go through unchanged."""
    features = _features_mapping(data)
    if features is None:
        return data
    name = features.get("point_frontend", FeaturesConfig.point_frontend)
    if not isinstance(name, str) or name not in POINT_FRONTENDS:
        return data
    return merged(frontend_preset(name), data)


def config_from_dict(
    data: dict | None,
    source: Path | None = None,
    *,
    point_frontend: str | None = None,
    preset: bool = True,
) -> Config:
    """Build and check a :class:`Config` from a (partial) mapping.

    ``point_frontend`` (when given) replaces the mapping's ``features.point_frontend``; with
    ``preset`` the chosen front end's preset (:func:`frontend_preset`) fills the keys the mapping
    does not set. ``preset=False`` keeps the base defaults for them."""
    data = {} if data is None else data
    if point_frontend is not None and _features_mapping(data) is not None:
        data = merged(data, {"features": {"point_frontend": point_frontend}})
    if preset:
        data = _with_preset(data)
    config = _build(Config, data, "config", source)
    check_config(config, source)
    try:
        config.features.superpoint.check()
    except ValueError as exc:
        raise ConfigError(source, f"features.superpoint: {exc}") from None
    try:
        config.features.xfeat.check()
    except ValueError as exc:
        raise ConfigError(source, f"features.xfeat: {exc}") from None
    try:
        config.features.low_light.check()
    except ValueError as exc:
        raise ConfigError(source, f"features.low_light: {exc}") from None
    return config


def default_config(point_frontend: str | None = None) -> Config:
    """The defaults with the front end's preset: ORB tuned as ``presets/orb.yaml`` says,
    unless ``point_frontend`` names another front end. What ``slslam run`` uses without
    ``--config``, and ``slslam.Tracker`` without a config."""
    return config_from_dict({}, point_frontend=point_frontend)


def load_config(
    path: str | Path | None, *, point_frontend: str | None = None, preset: bool = True
) -> Config:
    """Read a YAML config (None: all defaults), with its front end's preset under its keys (see
    :func:`config_from_dict`)."""
    if path is None:
        return config_from_dict({}, point_frontend=point_frontend, preset=preset)
    path = Path(path)
    if not path.is_file():
        raise ConfigError(path, "config file not found")
    # At most 1 MiB, no aliases, C loader: see slslam.yaml_io.
    data = read_yaml(path, ConfigError, max_bytes=MAX_YAML_BYTES)
    return config_from_dict(data, path, point_frontend=point_frontend, preset=preset)


def dump_config(config: Config, path: str | Path, header: str | None = None) -> Path:
    """Write the complete configuration (every key) as YAML, e.g. next to a run's results;
    ``header`` lines go first as YAML comments (the file still loads with ``load_config``)."""
    from slslam.files import write_text_atomic

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_text_atomic(path, config_to_yaml(config, header))  # never half a config


def config_to_yaml(config: Config, header: str | None = None) -> str:
    """The complete configuration as YAML text (what ``dump_config`` writes)."""
    text = yaml.safe_dump(_plain(dataclasses.asdict(config)), sort_keys=False)
    if header:
        text = "".join(f"# {line}\n" for line in header.splitlines()) + text
    return text


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def make_point_frontend(config: FeaturesConfig) -> Orb | XFeat | SuperPoint:
    """The configured point front end. SuperPoint without weights (no model_path in the config
    and no $SLSLAM_SUPERPOINT_MODEL) falls back to ORB with one warning line; XFeat's weights
    ship with slslam."""
    from slslam.features.orb import Orb
    from slslam.features.superpoint import SuperPoint
    from slslam.features.xfeat import XFeat

    if config.point_frontend == "xfeat":
        return XFeat(config.xfeat)
    if config.point_frontend == "superpoint":
        if config.superpoint.model_path or os.environ.get(ENV_MODEL):
            return SuperPoint(config.superpoint)
        log.warning(
            "no SuperPoint weights (set %s or features.superpoint.model_path): "
            "using the ORB front end",
            ENV_MODEL,
        )
    return Orb(config.orb, adaptive=config.low_texture_fallback)
