"""The commit a sweep's results name: the slslam checkout's, never another repository's."""

import subprocess
from pathlib import Path

import pytest

from slslam.bench.keys import core_build
from slslam.bench.provenance import git_commit


def _init_repo(root: Path) -> None:
    subprocess.run(["git", "init", "-q", str(root)], check=True)
    subprocess.run(
        [
            "git",
            "-C",
            str(root),
            "-c",
            "user.name=t",
            "-c",
            "user.email=t@t",
            "commit",
            "-q",
            "--allow-empty",
            "-m",
            "x",
        ],
        check=True,
    )


def test_a_package_inside_another_repository_reports_the_core_build(tmp_path: Path) -> None:
    pytest.importorskip("slslam._core")
    _init_repo(tmp_path)  # (as pyenv keeps its installation in git)
    package = tmp_path / "lib" / "site-packages" / "slslam"
    package.mkdir(parents=True)
    assert git_commit(package) == core_build()["commit"]


def test_a_slslam_checkout_reports_its_own_commit(tmp_path: Path) -> None:
    _init_repo(tmp_path)
    for sub in ("python/slslam", "cpp/slslam"):
        (tmp_path / sub).mkdir(parents=True)
    head = subprocess.run(
        ["git", "-C", str(tmp_path), "rev-parse", "--short=12", "HEAD"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert git_commit(tmp_path / "python" / "slslam").startswith(head)
