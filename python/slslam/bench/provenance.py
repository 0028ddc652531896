"""Where and from what a sweep ran: the machine and the commit (stamped on results pages)."""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path
from typing import Any


def _git(path: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(path), *args], capture_output=True, text=True, timeout=10, check=True
    ).stdout.strip()


def git_commit(path: Path) -> str:
    """The commit of the slslam checkout holding ``path`` (with -dirty), or the core's build
    commit when ``path`` is not in one (an installed package, which may sit inside another
    repository, such as a Python installation kept in git)."""
    try:
        top = Path(_git(path, "rev-parse", "--show-toplevel"))
        if (top / "python" / "slslam").is_dir() and (top / "cpp" / "slslam").is_dir():
            commit = _git(path, "describe", "--always", "--dirty", "--abbrev=12")
            if commit:
                return commit
    except (OSError, subprocess.SubprocessError):
        pass
    from slslam.bench.keys import core_build

    return core_build()["commit"]


def machine() -> dict[str, Any]:
    """What the sweep ran on: processor, cores, platform, Python."""
    name = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "processor": name,
        "cpu_count": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
    }
