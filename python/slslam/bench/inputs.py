"""Simulated inputs of a sweep, generated once per (simulator options, seed) and kept.

Each sequence lives in ``<data_dir>/<name>-seed<k>-<hash>`` (hash: of the complete SimOptions),
written under a ``.partial`` name and renamed when the simulator reports it complete, so a folder
under the final name is always whole. Cells that need the same input at the same time (Ray
workers) wait on a lock file instead of simulating it twice.
"""

from __future__ import annotations

import fcntl
import json
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from slslam.bench.keys import digest


def sim_options(sim: dict[str, Any], seed: int) -> dict[str, Any]:
    """The complete simulator options of a simulated sequence at ``seed`` (defaults filled in):
    what the input's identity is hashed from."""
    from slslam.sim import SimOptions

    return SimOptions(**sim, seed=seed).to_dict()


def input_dir(data_dir: Path, name: str, sim: dict[str, Any], seed: int) -> Path:
    return Path(data_dir) / f"{name}-seed{seed}-{digest(sim_options(sim, seed))[:12]}"


def is_complete(folder: Path) -> bool:
    manifest = folder / "manifest.json"
    try:
        return json.loads(manifest.read_text()).get("status") == "complete"
    except (OSError, ValueError):
        return False


@contextmanager
def _locked(path: Path) -> Iterator[None]:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)  # blocks while another process simulates it
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def ensure_simulated(data_dir: Path, name: str, sim: dict[str, Any], seed: int) -> Path:
    """The simulated sequence's folder, simulating it first when it is missing or incomplete."""
    from slslam.sim import SimOptions, Simulator

    out = input_dir(data_dir, name, sim, seed)
    if is_complete(out):
        return out
    with _locked(out.with_name(out.name + ".lock")):
        if is_complete(out):  # another worker finished it while this one waited
            return out
        partial = out.with_name(out.name + ".partial")
        shutil.rmtree(partial, ignore_errors=True)
        Simulator(SimOptions(**sim, seed=seed)).write(partial, progress=False)
        if not is_complete(partial):
            raise RuntimeError(f"{partial}: the simulator did not complete the sequence")
        shutil.rmtree(out, ignore_errors=True)
        partial.rename(out)
    return out
