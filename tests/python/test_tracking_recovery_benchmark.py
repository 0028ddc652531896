"""benchmarks/tracking_recovery.py: where each seed's data goes, the seed table's means and
spreads, and the refusal of repeated seeds."""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import load_benchmark


@pytest.fixture(scope="module")
def recovery():
    yield from load_benchmark("tracking_recovery.py")


def test_seed_zero_keeps_the_old_folders(recovery):
    root = Path("/data")
    assert recovery.seed_dir(root, 0) == root
    assert recovery.seed_dir(root, 2) == root / "seed2"


def test_seed_table_gives_mean_and_spread(recovery):
    def run(ate, maps=1):
        return {"ate_rmse_m": ate, "maps": maps}

    per_seed = {
        "loop_l100": {"orb_lines": {0: run(0.01), 1: run(0.03), 2: run(0.02, maps=2)}},
        "junction_hard": {"orb_lines": {0: run(None), 1: run(0.5)}},
    }
    rows = recovery.seed_table(per_seed, [0, 1, 2]).splitlines()
    assert len(rows) == 4
    assert rows[2] == (
        "| loop_l100 | ORB + lines | 0.0100 | 0.0300 | 0.0200 | 0.0200 | 0.0100-0.0300 | 2 |"
    )
    # a run without an ATE and a seed not run count as missing, not as zero
    assert rows[3] == (
        "| junction_hard | ORB + lines | - | 0.5000 | - | 0.5000 | 0.5000-0.5000 | 1 |"
    )


def test_repeated_seeds_are_refused(recovery, capsys):
    with pytest.raises(SystemExit):
        recovery.main(["--seeds", "1", "1"])
    assert "--seeds must be distinct" in capsys.readouterr().err
