"""slslam.tracking.pipeline on its own: run_ahead keeps input order, holds at most ``ahead``
prepared items, raises an error in its item's place and stops its worker when closed;
FrontEndThreads runs work on its named threads."""

from __future__ import annotations

import threading
import time
from contextlib import closing

import pytest

from slslam.tracking.pipeline import FrontEndThreads, run_ahead


def test_items_come_out_in_order_with_at_most_ahead_prepared():
    prepared: list[int] = []
    taken: list[int] = []
    waiting: list[int] = []

    def prepare(position: int, item: str) -> tuple[int, str]:
        prepared.append(position)
        return position, item

    for position, item in run_ahead("abcdef", prepare, ahead=2):
        time.sleep(0.02)  # the worker fills the slots meanwhile
        taken.append(position)
        waiting.append(len(prepared) - len(taken))  # prepared, not yet taken
        assert item == "abcdef"[position]
    assert taken == prepared == list(range(6))
    assert max(waiting) <= 2


def test_an_error_comes_out_after_the_items_before_it():
    def items():
        yield 1
        yield 2
        raise OSError("reader failed")

    out = []
    with pytest.raises(OSError, match="reader failed"):
        for value in run_ahead(items(), lambda _, item: item * 10, ahead=3):
            out.append(value)
    assert out == [10, 20]

    def prepare(position: int, item: int) -> int:
        if position == 1:
            raise ValueError("bad frame")
        return item

    out = []
    with pytest.raises(ValueError, match="bad frame"):
        for value in run_ahead([5, 6, 7], prepare, ahead=1):
            out.append(value)
    assert out == [5]


def test_closing_stops_the_worker():
    started = threading.Event()

    def endless():
        while True:
            started.set()
            yield 0

    with closing(run_ahead(endless(), lambda _, item: item, ahead=2, name="test-ahead")) as it:
        assert next(it) == 0
        assert any(t.name == "test-ahead" for t in threading.enumerate())
    assert started.is_set()
    deadline = time.monotonic() + 5.0
    while any(t.name == "test-ahead" for t in threading.enumerate()):
        assert time.monotonic() < deadline
        time.sleep(0.01)


def test_front_end_threads_run_on_their_named_threads():
    threads = FrontEndThreads(lines=True)
    assert (
        threads.submit_right(lambda: threading.current_thread().name)
        .result()
        .startswith("slslam-right")
    )
    lines = threads.submit_lines(lambda x, y=0: (threading.current_thread().name, x + y), 1, y=2)
    assert lines is not None
    name, value = lines.result()
    assert name.startswith("slslam-lines") and value == 3
    threads.shutdown()
    no_lines = FrontEndThreads(lines=False)
    assert no_lines.lines is None and no_lines.submit_lines(print) is None
    no_lines.shutdown()
