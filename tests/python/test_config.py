import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from slslam import _core
from slslam.config import (
    Config,
    ConfigError,
    config_from_dict,
    default_config,
    dump_config,
    load_config,
    make_point_frontend,
)
from slslam.features.orb import Orb
from slslam.features.superpoint import ENV_MODEL, SuperPoint
from slslam.features.xfeat import XFeatOptions

DEFAULT_YAML = Path(__file__).resolve().parents[2] / "configs" / "default.yaml"


def test_documented_defaults_equal_the_code_defaults():
    """configs/default.yaml holds the base defaults (Config()): it sets every key, so no preset
    key is left to fill. No file at all gives the default front end's preset (default_config)."""
    assert load_config(DEFAULT_YAML) == load_config(DEFAULT_YAML, preset=False) == Config()
    assert load_config(None, preset=False) == Config()
    assert load_config(None) == default_config() != Config()  # XFeat's preset changes something


def test_python_and_cpp_defaults_agree():
    features = Config().features
    grid, dynamic, orb = _core.GridLimitOptions(), _core.DynamicCellOptions(), _core.OrbOptions()
    assert (features.grid.cell_size_px, features.grid.max_per_cell) == (
        grid.cell_size_px,
        grid.max_per_cell,
    )
    d = features.dynamic_cells
    assert (d.cell_size_px, d.sigma_px, d.alpha, d.threshold) == (
        dynamic.cell_size_px,
        dynamic.sigma_px,
        dynamic.alpha,
        dynamic.threshold,
    )
    assert features.orb.fast_threshold == orb.fast_threshold
    assert features.orb.num_levels == orb.num_levels
    assert features.orb.scale_factor == pytest.approx(orb.scale_factor)


def test_loop_closing_defaults_agree_with_cpp():
    loop, core = Config().tracking.loop_closing, _core.LoopClosingOptions()
    for name in (
        "enabled",
        "merge_maps",
        "global_ba",
        "yaw_and_position_with_gravity",
        "consistency",
        "max_correction_ratio",
        "max_correction_floor_m",
        "welding_keyframes",
    ):
        assert getattr(loop, name) == pytest.approx(getattr(core, name)), name
    assert loop.min_inliers == pytest.approx(core.min_inliers)


def test_partial_file_and_round_trip(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("features:\n  point_frontend: orb\n  orb:\n    max_keypoints: 500\n")
    config = load_config(path)
    assert config.features.point_frontend == "orb"
    assert config.features.orb.max_keypoints == 500
    assert config.features.grid.max_per_cell == 8
    assert load_config(dump_config(config, tmp_path / "out.yaml")) == config


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("features:\n  orbb: {}\n", "unknown key 'config.features.orbb'"),
        ("features:\n  point_frontend: sift\n", "must be one of"),
        ("features:\n  grid:\n    max_per_cell: many\n", "must be an integer"),
        ("features:\n  superpoint:\n    detection_threshold: 2.0\n", "detection_threshold"),
        ("features: [1, 2]\n", "must be a mapping"),
        ("features: {grid: [}\n", "not valid YAML"),
    ],
)
def test_malformed_configs_name_file_and_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as info:
        load_config(path)
    assert str(path) in str(info.value)


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="config file not found"):
        load_config(tmp_path / "none.yaml")


def test_frontend_choice_and_model_path_precedence(tmp_path, monkeypatch, caplog):
    from test_superpoint import tiny_model

    from slslam.features.xfeat import XFeat

    monkeypatch.delenv(ENV_MODEL, raising=False)
    # the default: ORB; XFeat's weights ship with slslam (no SuperPoint weights needed)
    assert isinstance(make_point_frontend(Config().features), Orb)
    assert isinstance(make_point_frontend(default_config("xfeat").features), XFeat)
    assert "using the ORB front end" not in caplog.text
    superpoint = default_config("superpoint").features
    assert isinstance(make_point_frontend(superpoint), Orb)
    assert "using the ORB front end" in caplog.text
    env_model = tiny_model(tmp_path / "env.onnx")
    config_model = tiny_model(tmp_path / "config.onnx")
    monkeypatch.setenv(ENV_MODEL, str(env_model))
    assert make_point_frontend(superpoint).model_path == env_model
    config = config_from_dict(
        {
            "features": {
                "point_frontend": "superpoint",
                "superpoint": {"model_path": str(config_model)},
            }
        }
    )
    frontend = make_point_frontend(config.features)
    assert isinstance(frontend, SuperPoint) and frontend.model_path == config_model
    orb = config_from_dict({"features": {"point_frontend": "orb"}})
    assert isinstance(make_point_frontend(orb.features), Orb)


def test_dynamic_cell_settings_reach_the_tracker():
    """features.dynamic_cells is read by tracking (it was documented but read by nothing)."""
    from slslam.datasets.euroc import RectifiedStereoCamera
    from slslam.tracking.tracker import _core_options

    camera = RectifiedStereoCamera(458.0, 458.0, 376.0, 240.0, 752, 480, 0.11, np.eye(4))
    defaults = _core_options(camera, Config())
    assert defaults.dynamic_cells == _core.TrackerOptions().dynamic_cells == True  # noqa: E712
    assert defaults.dynamic.sigma_px == _core.DynamicCellOptions().sigma_px
    config = config_from_dict(
        {"features": {"dynamic_cells": {"enabled": False, "sigma_px": 5.0, "threshold": 0.3}}}
    )
    options = _core_options(camera, config)
    assert options.dynamic_cells is False
    assert (options.dynamic.sigma_px, options.dynamic.threshold) == (5.0, 0.3)


def test_orb_is_the_default_front_end_with_its_preset():
    """ORB is the default point front end (benchmarks/kitti.py: XFeat loses the scale on real
    KITTI), with its preset (presets/orb.yaml) under the config's keys: ORB on the left image
    only with the row search on the right; every other key at its default."""
    from slslam.datasets.euroc import RectifiedStereoCamera
    from slslam.tracking.tracker import _core_options

    config = default_config()
    assert config.features.point_frontend == "orb" == Config().features.point_frontend
    camera = RectifiedStereoCamera(458.0, 458.0, 376.0, 240.0, 752, 480, 0.11, np.eye(4))
    assert config.tracking.stereo_row_search and not Config().tracking.stereo_row_search
    assert _core_options(camera, config).stereo.row_search
    # and dark frames through the gamma curve (features.low_light; none by default)
    assert config.features.low_light.mode == "gamma" and Config().features.low_light.mode == "none"
    assert default_config("xfeat").features.low_light.mode == "none"
    tracking = dataclasses.replace(config.tracking, stereo_row_search=False)
    features = dataclasses.replace(config.features, low_light=Config().features.low_light)
    assert dataclasses.replace(config, tracking=tracking, features=features) == Config()


def test_xfeat_preset():
    """XFeat with its preset (presets/xfeat.yaml) under the config's keys: the filter's width
    following the frame's residuals, the 8-bit network on the left image with the row search,
    keyframes at most every 6 frames (5 in noisy frames), every frame's lines, projected frames,
    triangulated points with patches; every other key at its default."""
    from slslam.datasets.euroc import RectifiedStereoCamera
    from slslam.tracking.tracker import _core_options

    config = default_config("xfeat")
    assert config.features.point_frontend == "xfeat"
    base = dataclasses.replace(
        Config(), features=dataclasses.replace(Config().features, point_frontend="xfeat")
    )
    assert config.features.dynamic_cells.sigma_median_ratio == 2.0
    assert config.features.xfeat.precision == "int8"
    assert config.features.xfeat.intra_op_threads == 2
    assert not config.features.xfeat.intra_op_spinning and XFeatOptions().intra_op_spinning
    assert _core.DynamicCellOptions().sigma_median_ratio == 0.0  # the paper's fixed width
    camera = RectifiedStereoCamera(458.0, 458.0, 376.0, 240.0, 752, 480, 0.11, np.eye(4))
    assert _core_options(camera, config).dynamic.sigma_median_ratio == 2.0
    # the network on the left image only, the row search on the right
    assert config.tracking.stereo_row_search and not Config().tracking.stereo_row_search
    assert _core_options(camera, config).stereo.row_search
    rest = dataclasses.replace(
        config.features,
        dynamic_cells=Config().features.dynamic_cells,
        xfeat=Config().features.xfeat,
    )
    # and keyframes at most every 6 frames while tracking is strong, every frame's lines
    assert config.tracking.keyframe_min_frames == 6
    assert config.tracking.keyframe_min_frames_noisy == 5
    assert Config().tracking.keyframe_min_frames_noisy == -1  # (off: keyframe_min_frames)
    assert not config.tracking.lines_on_demand and Config().tracking.lines_on_demand
    # and frames between detections tracked on projected keypoints (off by default)
    assert config.tracking.projected_max_frames == 2 and Config().tracking.projected_max_frames == 0
    assert config.tracking.projection_cell_px == 16
    # and triangulated points with patches of their keyframe's image (off by default)
    assert config.tracking.triangulated_point_patches
    assert not Config().tracking.triangulated_point_patches
    assert _core_options(camera, config).triangulated_point_patches
    tracking = dataclasses.replace(
        config.tracking,
        stereo_row_search=False,
        keyframe_min_frames=Config().tracking.keyframe_min_frames,
        keyframe_min_frames_noisy=Config().tracking.keyframe_min_frames_noisy,
        lines_on_demand=Config().tracking.lines_on_demand,
        projected_max_frames=Config().tracking.projected_max_frames,
        projection_cell_px=Config().tracking.projection_cell_px,
        triangulated_point_patches=False,
    )
    assert dataclasses.replace(config, features=rest, tracking=tracking) == base


def test_front_end_presets_sit_under_the_configs_own_keys(tmp_path):
    """A key the config sets wins over the preset; naming XFeat changes nothing; ORB's preset
    (the row search) applies also when ORB is chosen by --orb's point_frontend over a file that
    names XFeat, without XFeat's; SuperPoint (no preset) runs with the base defaults; every
    preset key changes its default."""
    from slslam.config import frontend_preset

    path = tmp_path / "c.yaml"
    path.write_text("tracking:\n  keyframe_min_frames: 3\n  use_lines: false\n")
    config = load_config(path)
    assert config.tracking.keyframe_min_frames == 3 and not config.tracking.use_lines
    assert config.tracking.stereo_row_search  # the rest of the preset still applies
    assert load_config(path, preset=False).tracking.keyframe_min_frames == 3
    assert not load_config(path, preset=False).tracking.stereo_row_search
    assert config_from_dict({"features": {"point_frontend": "orb"}}) == default_config()
    assert config_from_dict({"features": {"point_frontend": "xfeat"}}) == default_config("xfeat")
    assert frontend_preset("superpoint") == {}
    superpoint = config_from_dict({"features": {"point_frontend": "superpoint"}})
    assert superpoint == dataclasses.replace(
        Config(), features=dataclasses.replace(Config().features, point_frontend="superpoint")
    )
    assert default_config("superpoint") == superpoint
    orb = config_from_dict({"features": {"point_frontend": "orb"}})
    assert orb == default_config("orb")
    assert orb.tracking == dataclasses.replace(Config().tracking, stereo_row_search=True)
    assert orb.features == dataclasses.replace(
        Config().features,
        point_frontend="orb",
        low_light=dataclasses.replace(Config().features.low_light, mode="gamma"),
    )
    path.write_text("features:\n  point_frontend: xfeat\n")
    assert load_config(path, point_frontend="orb") == orb
    path.write_text("features:\n  point_frontend: orb\ntracking:\n  stereo_row_search: false\n")
    assert not load_config(path).tracking.stereo_row_search  # the file's key wins

    def leaves(tree: dict, prefix: str = ""):
        for key, value in tree.items():
            if isinstance(value, dict):
                yield from leaves(value, f"{prefix}{key}.")
            else:
                yield f"{prefix}{key}", value

    def lookup(config: Config, dotted: str):
        value = config
        for part in dotted.split("."):
            value = getattr(value, part)
        return value

    for name, least in (("xfeat", 10), ("orb", 1)):
        preset = dict(leaves(frontend_preset(name)))
        assert len(preset) >= least
        for key, value in preset.items():
            assert lookup(default_config(name), key) == value, key
            assert lookup(Config(), key) != value, f"{key}: the preset repeats the default"
    with pytest.raises(ValueError, match="point_frontend"):
        frontend_preset("../default")


def test_every_mirrored_default_equals_the_cpp_default():
    """One source of defaults: each config key that goes to the C++ tracker options
    (``TRACKING_TO_CORE`` and its siblings, the table ``_core_options`` applies) has the C++
    default, field by field; every tracker-section key is either mirrored or read in Python."""
    from slslam._cpp_defaults import core_attribute
    from slslam.config import (
        DYNAMIC_CELLS_TO_CORE,
        IMU_TO_CORE,
        LINES_TO_CORE,
        LOOP_CLOSING_TO_CORE,
        TRACKING_TO_CORE,
    )

    core = _core.TrackerOptions()
    config = Config()
    checked = 0
    for section, table in (
        (config.tracking, TRACKING_TO_CORE),
        (config.tracking.loop_closing, LOOP_CLOSING_TO_CORE),
        (config.tracking.imu, IMU_TO_CORE),
        (config.features.dynamic_cells, DYNAMIC_CELLS_TO_CORE),
    ):
        for name, paths in table.items():
            for path in paths:
                expected = core_attribute(core, path)
                assert getattr(section, name) == pytest.approx(expected, rel=1e-6), (name, path)
                checked += 1
    lines = _core.LineExtractorOptions()
    for name, paths in LINES_TO_CORE.items():
        for path in paths:
            expected = core_attribute(lines, path)
            value = getattr(config.tracking, name)
            if isinstance(expected, str):
                assert value == expected, (name, path)
            else:
                assert value == pytest.approx(expected, rel=1e-6), (name, path)
            checked += 1
    assert checked >= 50
    python_only = {
        "pipeline",
        "pipeline_frames_ahead",
        "relocalisation",
        "vocabulary_path",
        "loop_closing",
        "imu",
    }
    fields = {f.name for f in dataclasses.fields(config.tracking)}
    assert fields - set(TRACKING_TO_CORE) - set(LINES_TO_CORE) == python_only


def test_mirrored_defaults_are_written_only_in_cpp():
    """Each config key that goes to the C++ options takes its default from the C++ struct: its
    dataclass field is declared with the reader (``_tracking("key", range)`` etc.), never with a
    literal, so a default changed in C++ changes the config, the YAML dump and the CLI."""
    import ast
    import inspect

    import slslam.config as cfg
    from slslam.features import orb

    readers = {
        "TrackingConfig": ({"_tracking": cfg.TRACKING_TO_CORE, "_lines": cfg.LINES_TO_CORE}),
        "LoopClosingConfig": {"_loop_closing": cfg.LOOP_CLOSING_TO_CORE},
        "DynamicCellConfig": {"_dynamic_cells": cfg.DYNAMIC_CELLS_TO_CORE},
        "GridConfig": {"_grid": cfg.GRID_TO_CORE},
    }
    tree = ast.parse(inspect.getsource(cfg))
    seen = 0
    for node in tree.body:
        if not isinstance(node, ast.ClassDef) or node.name not in readers:
            continue
        for item in node.body:
            if not isinstance(item, ast.AnnAssign):
                continue
            name = item.target.id
            table = {k: r for r, t in readers[node.name].items() for k in t}
            if name not in table:
                continue
            call = item.value
            assert isinstance(call, ast.Call) and call.func.id == table[name], (node.name, name)
            assert isinstance(call.args[0], ast.Constant) and call.args[0].value == name
            seen += 1
    mirrored = sum(len(t) for r in readers.values() for t in r.values())
    assert seen == mirrored >= 45
    # The ORB front end's options too.
    core_orb = _core.OrbOptions()
    defaults = orb.OrbOptions()
    assert (defaults.max_keypoints, defaults.num_levels, defaults.fast_threshold) == (
        core_orb.max_features,
        core_orb.num_levels,
        core_orb.fast_threshold,
    )
    assert defaults.scale_factor == 1.2  # the C++ 1.2f, as written


def test_cpp_float_defaults_read_as_written():
    from slslam._cpp_defaults import as_written

    assert as_written(float(np.float32(0.9))) == 0.9  # a C++ float field
    assert as_written(float(np.float32(0.005))) == 0.005
    assert as_written(0.1) == 0.1  # a double stays as it is
    assert as_written(1.0 / 3.0) == 1.0 / 3.0
    assert as_written(7) == 7 and as_written("lsd") == "lsd" and as_written(True) is True


def test_imu_windows_are_checked_against_each_other(tmp_path):
    """tracking.imu.min_window_s may not exceed window_s (C++ checks it too): a YAML file that
    breaks it gets one error naming the file and both keys, before anything reaches C++."""
    path = tmp_path / "imu.yaml"
    path.write_text("tracking:\n  imu:\n    window_s: 2.0\n    min_window_s: 2.5\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert "imu.yaml" in message and "min_window_s" in message and "window_s' (2.0)" in message
    path.write_text("tracking:\n  imu:\n    window_s: 2.0\n    min_window_s: 2.0\n")
    assert load_config(path).tracking.imu.min_window_s == 2.0


def test_triangulation_keys_reach_the_core():
    """tracking.triangulate_points / triangulation_min_parallax_deg: local mapping's
    TriangulationOptions (points on and 3 degrees by default, the C++ defaults)."""
    from slslam.datasets.euroc import RectifiedStereoCamera
    from slslam.tracking.tracker import _core_options

    camera = RectifiedStereoCamera(458.0, 458.0, 376.0, 240.0, 752, 480, 0.11, np.eye(4))
    default = _core_options(camera, Config()).mapping.triangulation
    assert default.points and default.min_parallax_deg == 3.0
    assert _core.TriangulationOptions().min_parallax_deg == 3.0
    tracking = dataclasses.replace(
        Config().tracking, triangulate_points=False, triangulation_min_parallax_deg=5.0
    )
    changed = _core_options(camera, dataclasses.replace(Config(), tracking=tracking))
    assert not changed.mapping.triangulation.points
    assert changed.mapping.triangulation.min_parallax_deg == 5.0


def _range_probes(rng, integer: bool) -> tuple[list, list]:
    """(values the range refuses, values it takes) at both of its ends."""
    step = 1 if integer else max(1e-6, 1e-4 * max(abs(rng.low), abs(rng.high), 1.0))
    bad = [
        rng.low if rng.low_open else rng.low - step,
        rng.high if rng.high_open else rng.high + step,
    ]
    good = [
        rng.low + step if rng.low_open else rng.low,
        rng.high - step if rng.high_open else rng.high,
    ]
    if integer:
        bad, good = [int(v) for v in bad], [int(v) for v in good]
    return bad, good


#: Ends of a Python range that the C++ check refuses only together with another key's default
#: (a relation between two keys, checked in Python too: relations_error).
_RELATED_ENDS = {
    ("imu", "window_s", "good", 0.1),  # below min_window_s' default (1.0)
    ("imu", "min_window_s", "good", 1000.0),  # above window_s' default (3.0)
}


def test_every_python_range_is_the_cpp_check():
    """One source of bounds: for every mirrored key with a range, the values just outside each
    end are refused by the C++ options' check and the ends (or just inside an open end) are
    taken, so Python refuses a YAML value exactly when C++ would."""
    from slslam.config import (
        DYNAMIC_CELLS_TO_CORE,
        IMU_TO_CORE,
        LOOP_CLOSING_TO_CORE,
        TRACKING_TO_CORE,
    )
    from slslam.tracking.tracker import _core_options, _set_core

    camera = SimpleNamespace(
        fx=458.0,
        fy=458.0,
        cx=375.5,
        cy=239.5,
        width=752,
        height=480,
        baseline_m=0.11,
        T_body_cam=np.eye(4),
    )
    config = Config()
    mismatches, probed = [], 0
    for label, section, table in (
        ("tracking", config.tracking, TRACKING_TO_CORE),
        ("loop_closing", config.tracking.loop_closing, LOOP_CLOSING_TO_CORE),
        ("imu", config.tracking.imu, IMU_TO_CORE),
        ("dynamic_cells", config.features.dynamic_cells, DYNAMIC_CELLS_TO_CORE),
    ):
        for f in dataclasses.fields(section):
            rng = f.metadata.get("range")
            if rng is None or f.name not in table:
                continue
            integer = isinstance(getattr(section, f.name), int)
            bad, good = _range_probes(rng, integer)
            for kind, values in (("bad", bad), ("good", good)):
                for value in values:
                    if (label, f.name, kind, value) in _RELATED_ENDS:
                        continue
                    options = _core_options(camera, config)
                    for path in table[f.name]:
                        _set_core(options, path, value)
                    try:
                        options.check()
                        taken = True
                    except ValueError:
                        taken = False
                    probed += 1
                    if taken != (kind == "good"):
                        mismatches.append(f"{label}.{f.name} = {value} ({kind} in Python {rng})")
    assert probed >= 100
    assert not mismatches, "\n".join(mismatches)
