"""Progress off a terminal: a line every few seconds, not one per update."""

from __future__ import annotations

import subprocess
import sys


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
