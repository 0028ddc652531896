"""The threads of ``slslam.Tracker``'s frame pipeline, apart from what they run.

- :class:`FrontEndThreads`: one frame's helper threads, the right image (smoothing, and the point
  front end unless ``tracking.stereo_row_search``) and the left image's lines, beside the
  tracker's own thread doing the left image.
- :func:`run_ahead`: ``Tracker.track_stream``'s worker, which reads and prepares the next frames
  while the caller (the C++ core) takes the ones before, at most ``ahead`` prepared and not yet
  taken; items come out in input order, and an error comes out in its place after the items
  before it.

Nothing here knows frames or the core: the tracker hands in what to run.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Generator, Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Generic, TypeVar

T = TypeVar("T")
P = TypeVar("P")

__all__ = ["FrontEndThreads", "run_ahead"]


class FrontEndThreads:
    """The front end's helper threads for one frame at a time: ``right`` (``slslam-right``) and,
    with ``lines``, ``lines`` (``slslam-lines``; None otherwise: the core extracts the lines
    itself). One worker each, so work given to one runs in the order given."""

    def __init__(self, lines: bool) -> None:
        self.right = ThreadPoolExecutor(max_workers=1, thread_name_prefix="slslam-right")
        self.lines: ThreadPoolExecutor | None = (
            ThreadPoolExecutor(max_workers=1, thread_name_prefix="slslam-lines") if lines else None
        )

    def submit_right(self, fn: Callable[..., Any], *args: Any) -> Future:
        """``fn(*args)`` on the right image's thread."""
        return self.right.submit(fn, *args)

    def submit_lines(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Future | None:
        """``fn(*args, **kwargs)`` on the lines thread; None (nothing run) without one."""
        return None if self.lines is None else self.lines.submit(fn, *args, **kwargs)

    def shutdown(self) -> None:
        """Waits for the work given and stops the threads."""
        self.right.shutdown()
        if self.lines is not None:
            self.lines.shutdown()


class _End:
    """The worker has read every item."""


_END = _End()


class _Worker(Generic[T, P]):
    """run_ahead's thread: reads and prepares items one at a time while fewer than the slot's
    count wait for the consumer; ends with _END or the exception that stopped it."""

    def __init__(
        self,
        items: Iterable[T],
        prepare: Callable[[int, T], P],
        ahead: int,
        name: str,
    ) -> None:
        self.handoff: queue.Queue[P | _End | BaseException] = queue.Queue()
        self.slot = threading.Semaphore(ahead)  # items prepared and not yet taken
        self.stop = threading.Event()
        self._items, self._prepare = items, prepare
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        position = 0
        try:
            iterator = iter(self._items)
            while True:
                self.slot.acquire()
                if self.stop.is_set():
                    return
                try:
                    item = next(iterator)
                except StopIteration:
                    self.handoff.put(_END)
                    return
                self.handoff.put(self._prepare(position, item))
                position += 1
        except BaseException as exc:  # handed to the consumer, raised there in item order
            self.handoff.put(exc)


def run_ahead(
    items: Iterable[T],
    prepare: Callable[[int, T], P],
    ahead: int,
    name: str = "slslam-frontend",
) -> Generator[P, None, None]:
    """``prepare(position, item)`` for each of ``items`` in order (position from 0), on a worker
    thread (``name``, a daemon) that reads and prepares an item only while fewer than ``ahead``
    prepared ones wait to be taken. Yields them in order; an exception from ``items`` or
    ``prepare`` is raised in the place of its item, after the items before it. The worker may
    start on the next item as soon as one is taken, before the caller's work on it. Closing the
    iterator (``contextlib.closing``; break, an exception) stops the worker after the item it is
    preparing (waited for up to 60 s); items prepared and not yet taken are dropped."""
    worker: _Worker[T, P] = _Worker(items, prepare, ahead, name)
    worker.thread.start()
    try:
        while True:
            item = worker.handoff.get()
            worker.slot.release()  # the worker may start the next item now
            if isinstance(item, _End):
                return
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:
        worker.stop.set()
        worker.slot.release()  # a worker waiting for the slot sees the stop
        worker.thread.join(timeout=60.0)
