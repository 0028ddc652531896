"""docs/configuration.md is generated from the options (scripts/make_config_docs.py): it must
match what the generator makes of the current code, and cover every key with its meaning."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _generator():
    spec = importlib.util.spec_from_file_location(
        "make_config_docs", ROOT / "scripts" / "make_config_docs.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["make_config_docs"] = module
    spec.loader.exec_module(module)
    return module


def _leaf_keys(obj, prefix: str) -> list[str]:
    keys = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if dataclasses.is_dataclass(value):
            keys += _leaf_keys(value, f"{prefix}.{f.name}")
        else:
            keys.append(f"{prefix}.{f.name}")
    return keys


def test_the_configuration_page_is_generated_from_the_current_options():
    page = (ROOT / "docs" / "configuration.md").read_text(encoding="utf-8")
    assert page == _generator().render(), (
        "docs/configuration.md is stale: run python scripts/make_config_docs.py"
    )


def test_every_key_has_a_row_with_its_meaning():
    from slslam.config import Config

    generator = _generator()
    comments = generator.yaml_comments(generator.YAML)
    config = Config()
    keys = [
        k for f in dataclasses.fields(config) for k in _leaf_keys(getattr(config, f.name), f.name)
    ]
    assert len(keys) > 100
    undocumented = [k for k in keys if not comments.get(k)]
    assert not undocumented, f"keys without a comment in configs/default.yaml: {undocumented}"
    page = generator.render()
    for key in keys:
        section, _, name = key.rpartition(".")
        assert f"## `{section}`" in page and f"| `{name}` |" in page, key
    # a mirrored key names its C++ option, with the C++ default and range
    assert "| `min_inliers` |" in page and "`TrackerOptions.min_inliers`" in page
    assert "`TrackerOptions.imu.window_s`" in page
