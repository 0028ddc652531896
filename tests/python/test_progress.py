"""Progress off a terminal: a line every few seconds, not one per update."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest


def test_progress_in_a_log_writes_few_lines():
    code = (
        "from slslam.progress import progress_bar\n"
        "bar = progress_bar(range(2000), desc='tracking', unit='frame')\n"
        "for i in bar:\n"
        "    bar.set_postfix(state='OK', pts=i, refresh=False)\n"
    )
    # stderr is a pipe here, as in a CI log or `slslam run ... 2> log`.
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    updates = done.stderr.replace("\r", "\n").strip().splitlines()
    assert 1 <= len(updates) <= 3, updates  # first, last and at most one in between
    assert "2000/2000" in updates[-1]


@pytest.fixture(scope="module")
def short_sequence(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "loop"
    subprocess.run(
        [sys.executable, "-m", "slslam", "sim", "--preset", "loop", "--frames", "8"]
        + ["--out", str(out), "--no-lidar"],
        check=True,
        capture_output=True,
        timeout=300,
    )
    return out


@pytest.mark.parametrize("where", ["plain", "global", "run"])
def test_quiet_leaves_warnings_and_the_summary_only(short_sequence, tmp_path, where):
    run = ["run", str(short_sequence), "--out", str(tmp_path / "out"), "--orb", "--no-lines"]
    argv = {"plain": run, "global": ["--quiet", *run], "run": [*run, "--quiet"]}[where]
    done = subprocess.run(
        [sys.executable, "-m", "slslam", *argv], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert "results in" in done.stdout  # the summary stays
    if where == "plain":  # the bar and the info lines are there to be switched off
        assert "tracking:" in done.stderr and "INFO" in done.stderr, done.stderr
    else:
        assert "tracking:" not in done.stderr and "INFO" not in done.stderr, done.stderr
