"""Running a spec's cells: cached ones skipped, the rest inline or as Ray tasks.

Backends:
    inline   ``workers=1``: one cell after the other in this process (debugging; no Ray needed)
    Ray      otherwise: each cell one task with its CPU / GPU request; ``address`` joins a
             running cluster (``ray start --head`` ...), without it Ray starts locally on
             ``workers`` cores (default: all)

Each finished cell's record is written at once (``cells/<sequence>/<configuration>/seed<k>.json``,
atomically), so an interrupt (Ctrl-C, SIGTERM) loses only the cells in progress. A cell whose
record holds the same key and status ok is not run again; failed cells are. Cells marked
``exclusive`` run after the others, one at a time with nothing else running.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import signal
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from slslam.bench.cells import Cell, execute_cell, plan_cells
from slslam.bench.spec import Spec
from slslam.errors import InputError

log = logging.getLogger(__name__)

#: Seconds past a cell's timeout before the driver kills its Ray task (the cell's own alarm
#: stops it between frames first; this catches a cell stuck inside one long C++ call).
KILL_GRACE_S = 60.0


class BenchInterrupted(KeyboardInterrupt):
    """The sweep was stopped by SIGINT / SIGTERM; finished cells are saved."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(f"interrupted by {signal.Signals(signum).name}")


#: The signal _sigterm_as_interrupt's handler last received. A library the interrupt passes
#: through (Ray's get / wait) may replace the handler's exception by a plain KeyboardInterrupt,
#: which would otherwise read as SIGINT.
_received: list[int] = []


def _signum_of(exc: KeyboardInterrupt) -> int:
    """The signal behind an interrupt: its own, else the last one received, else SIGINT."""
    signum = getattr(exc, "signum", None)
    if isinstance(signum, int):
        return signum
    return _received[-1] if _received else int(signal.SIGINT)


@dataclass
class BenchRun:
    """What one invocation did."""

    cells: list[Cell]
    records: dict[str, dict[str, Any]]  # cell id -> record (cached and new)
    ran: list[str] = field(default_factory=list)  # ids run by this invocation
    cached: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)
    wall_s: float = 0.0
    backend: str = "inline"


def write_json_atomic(path: Path, data: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    try:
        tmp.write_text(json.dumps(data, indent=2, default=str) + "\n", encoding="utf-8")
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


def read_record(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def cached_record(cell: Cell, out: Path) -> dict[str, Any] | None:
    """The cell's saved record when it is complete and has the cell's key."""
    record = read_record(cell.record_path(out))
    if record and record.get("key") == cell.key and record.get("status") == "ok":
        return record
    return None


class _Progress:
    """A bar of cells done, with running / failed / cached counts."""

    def __init__(self, total: int, cached: int, enabled: bool) -> None:
        from slslam.progress import progress_bar

        self.bar = progress_bar(None, desc="cells", unit="cell", enabled=enabled, total=total)
        self.bar.update(cached)
        self.cached, self.running, self.failed = cached, 0, 0
        self.show()

    def show(self) -> None:
        self.bar.set_postfix(
            running=self.running, failed=self.failed, cached=self.cached, refresh=True
        )

    def done(self, record: dict[str, Any]) -> None:
        if record.get("status") != "ok":
            self.failed += 1
        self.bar.update(1)
        self.show()

    def set_running(self, n: int) -> None:
        if n != self.running:
            self.running = n
            self.show()

    def close(self) -> None:
        self.bar.close()


@contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM stops the sweep as Ctrl-C does (main thread only)."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        _received.append(signum)
        raise BenchInterrupted(signum)

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def _signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM ignored for the duration (main thread only): clean-up that must end."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _failure(cell: Cell, status: str, error: str) -> dict[str, Any]:
    """The record of a cell whose task did not return one (a crashed or killed worker)."""
    return {
        "key": cell.key,
        "cell": {
            "sequence": cell.sequence,
            "configuration": cell.configuration,
            "seed": cell.seed,
            "label": cell.label,
            "kind": cell.kind,
        },
        "status": status,
        "error": error,
        "result": {},
        "metrics": None,
        "measurements": {},
        "material": cell.material,
    }


def _run_inline(
    todo: list[Cell], out: Path, data_dir: Path, save: Callable[[Cell, dict], None], bar: _Progress
) -> None:
    for cell in todo:
        bar.set_running(1)
        try:
            record = execute_cell(cell, out, data_dir)
        except KeyboardInterrupt as exc:
            raise BenchInterrupted(_signum_of(exc)) from None
        bar.set_running(0)
        save(cell, record)
        bar.done(record)


def _started_at(cell: Cell, out: Path) -> float | None:
    """When the cell's task began (its run folder's marker), None while it waits in the queue."""
    try:
        return (cell.run_dir(out) / ".started").stat().st_mtime
    except OSError:
        return None


def _ray_init(
    address: str | None, workers: int | None, temp_dir: str | None
) -> tuple[bool, str | None]:
    """Starts or joins Ray unless this process already did: (whether this call started it, and
    so shuts it down; the session folder it made, removed afterwards)."""
    try:
        import ray
    except ImportError:
        raise InputError(
            "--workers",
            "Ray is not installed: pip install 'slslam[cluster]' (or ray), or run the cells "
            "inline with --workers 1",
        ) from None
    if ray.is_initialized():
        return False, None
    kwargs: dict[str, Any] = {
        "include_dashboard": False,
        "log_to_driver": False,
        "configure_logging": True,
        "logging_level": logging.WARNING,
    }
    # The workers import slslam from where this process does (a source tree on PYTHONPATH too).
    env = {k: os.environ[k] for k in ("PYTHONPATH",) if k in os.environ}
    if address:
        kwargs["address"] = address
        if env:
            kwargs["runtime_env"] = {"env_vars": env}
    made = None
    if not address:
        kwargs["num_cpus"] = workers or os.cpu_count() or 1
        made = None if temp_dir else tempfile.mkdtemp(prefix="slslam-ray-")
        kwargs["_temp_dir"] = temp_dir or made
    ray.init(**kwargs)
    return True, made


def _run_ray(
    todo: list[Cell],
    out: Path,
    data_dir: Path,
    save: Callable[[Cell, dict], None],
    bar: _Progress,
    address: str | None,
    workers: int | None,
    ray_temp_dir: str | None,
) -> None:
    import ray

    started_here, session_dir = _ray_init(address, workers, ray_temp_dir)
    remote = ray.remote(max_retries=0)(execute_cell)
    shared = [c for c in todo if not c.exclusive]  # submitted together: Ray queues them
    alone = [c for c in todo if c.exclusive]
    pending: dict[Any, Cell] = {}
    killed: set[Any] = set()  # tasks the driver cancelled past their deadline

    def submit(cell: Cell) -> None:
        ref = remote.options(
            num_cpus=cell.resources.cpus, num_gpus=cell.resources.gpus, name=cell.id
        ).remote(cell, str(out), str(data_dir))
        pending[ref] = cell

    def drain() -> None:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
            for ref in ready:
                cell = pending.pop(ref)
                try:
                    record = ray.get(ref)
                except Exception as exc:  # the worker died (a crash in the core) or was killed
                    if ref in killed:
                        status = "timeout"
                        message = (
                            f"killed {KILL_GRACE_S:g} s past its timeout of {cell.timeout_s:g} s"
                        )
                    else:
                        status = "failed"
                        message = " ".join(str(exc).split())[:500] or type(exc).__name__
                    record = _failure(cell, status, message)
                save(cell, record)
                bar.done(record)
            now = time.time()
            running = 0
            for ref, cell in pending.items():
                began = _started_at(cell, out)
                if began is None:
                    continue
                running += 1
                if now - began > cell.timeout_s + KILL_GRACE_S and ref not in killed:
                    ray.cancel(ref, force=True)
                    killed.add(ref)
            bar.set_running(running)

    try:
        with _sigterm_as_interrupt():  # over the handler ray.init installs in the driver
            for cell in shared:
                submit(cell)
            drain()
            for cell in alone:
                submit(cell)
                drain()
    except KeyboardInterrupt as exc:
        with _signals_held():  # a second Ctrl-C does not cut the clean-up short
            for ref in pending:
                try:
                    ray.cancel(ref, force=False)  # KeyboardInterrupt in the task: it stops
                except Exception as cancel_error:  # a task that finished meanwhile
                    log.debug("cancel: %s", cancel_error)
        raise BenchInterrupted(_signum_of(exc)) from None
    finally:
        if started_here:
            with _signals_held():
                ray.shutdown()
                if session_dir is not None:  # Ray's logs and sockets of this sweep
                    shutil.rmtree(session_dir, ignore_errors=True)


def run_bench(
    spec: Spec,
    out: str | Path,
    *,
    workers: int | None = None,
    address: str | None = None,
    data_dir: str | Path | None = None,
    progress: bool = True,
    ray_temp_dir: str | None = None,
    on_done: Callable[[BenchRun], object] | None = None,
) -> BenchRun:
    """Runs the spec's missing or changed cells and returns every cell's record. ``on_done`` is
    called with what is finished, also when the sweep is interrupted (then BenchInterrupted is
    raised after it)."""
    _received.clear()
    start = time.perf_counter()
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(out, "--out names an existing file; give a folder")
    data_dir = Path(data_dir) if data_dir is not None else out / "inputs"
    if workers is not None and workers < 1:
        raise InputError("--workers", f"must be >= 1, got {workers}")
    cells = plan_cells(spec)
    ids = [c.id for c in cells]
    if len(set(ids)) != len(ids):
        raise InputError(spec.path, "two cells share a sequence, configuration and seed")
    run = BenchRun(cells=cells, records={})
    todo: list[Cell] = []
    for cell in cells:
        record = cached_record(cell, out)
        if record is not None:
            run.records[cell.id] = record
            run.cached.append(cell.id)
        else:
            todo.append(cell)
    run.backend = "inline" if workers == 1 else ("ray " + (address or "local"))
    out.mkdir(parents=True, exist_ok=True)

    def save(cell: Cell, record: dict[str, Any]) -> None:
        record.setdefault("measurements", {})["backend"] = run.backend
        write_json_atomic(cell.record_path(out), record)
        run.records[cell.id] = record
        run.ran.append(cell.id)
        if record.get("status") != "ok":
            run.failed.append(cell.id)
            log.warning("cell %s %s: %s", cell.id, record.get("status"), record.get("error"))

    bar = _Progress(len(cells), len(run.cached), progress)
    try:
        with _sigterm_as_interrupt():
            if todo and workers == 1:
                _run_inline(todo, out, data_dir, save, bar)
            elif todo:
                _run_ray(todo, out, data_dir, save, bar, address, workers, ray_temp_dir)
    except KeyboardInterrupt as exc:  # Ctrl-C (or SIGTERM) anywhere in the sweep
        stop = exc if isinstance(exc, BenchInterrupted) else BenchInterrupted(_signum_of(exc))
        run.wall_s = time.perf_counter() - start
        if on_done is not None:
            with _signals_held():  # the pages of the finished cells are written whole
                on_done(run)
        raise stop from None
    finally:
        bar.close()
    run.wall_s = time.perf_counter() - start
    if on_done is not None:
        on_done(run)
    return run
