"""Type stubs: python/slslam/_core.pyi matches the compiled module (regenerate with
scripts/make_stubs.py after changing a binding), and the installed package is typed (py.typed)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from conftest import REPO


def test_core_stubs_match_the_compiled_module():
    pytest.importorskip("pybind11_stubgen")
    spec = importlib.util.spec_from_file_location("make_stubs", REPO / "scripts" / "make_stubs.py")
    make_stubs = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_stubs)
    assert make_stubs.STUB.read_text(encoding="utf-8") == make_stubs.generate(), (
        "python/slslam/_core.pyi is stale: reinstall, then run python scripts/make_stubs.py"
    )


def test_installed_package_is_typed():
    import slslam

    package = Path(slslam.__file__).parent
    assert (package / "py.typed").is_file()
    assert (package / "_core.pyi").is_file()
