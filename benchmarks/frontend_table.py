"""The README's "which front end to use when" table, generated from benchmark results.

    python benchmarks/frontend_table.py --kitti DIR/kitti.json --recovery DIR/tracking_recovery.json
        [--euroc DIR/euroc.json] [--update README.md]

Reads the JSON files that ``benchmarks/kitti.py`` (configurations orb_lines and xfeat_lines),
``benchmarks/tracking_recovery.py`` (configurations orb_lines and xfeat_lines, one or more seeds)
and ``benchmarks/euroc.py`` write, prints one Markdown table (per sequence: ORB + lines and XFeat
+ lines side by side, the better of the two in bold) with the date, the commit and the machine,
and with ``--update FILE`` rewrites the block between ``<!-- slslam-bench:frontends begin -->``
and ``<!-- slslam-bench:frontends end -->`` in FILE.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from datetime import datetime, timezone
from pathlib import Path

from slslam.bench.blocks import update_file

from common import machine_line

CONFIGS = ("orb_lines", "xfeat_lines")
LABELS = {"orb_lines": "ORB + lines", "xfeat_lines": "XFeat + lines"}


def _commit() -> str:
    here = Path(__file__).resolve().parent
    try:
        return subprocess.run(
            ["git", "-C", str(here), "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            check=True,
            timeout=10,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def kitti_rows(path: Path) -> list[tuple[str, dict[str, float | None], str]]:
    """(sequence, config -> ATE as % of the reference path, note) per KITTI sequence."""
    data = json.loads(path.read_text())
    rows = []
    for name, per_config in data.items():
        if not isinstance(per_config, dict) or not set(CONFIGS) <= set(per_config):
            continue
        values: dict[str, float | None] = {}
        notes = []
        for cfg in CONFIGS:
            r = per_config[cfg]
            values[cfg] = r.get("ate_percent_of_path")
            notes.append(
                f"{LABELS[cfg]} {r['posed']}/{r['frames']} posed, {r['maps']} map(s), path "
                f"{r.get('path_error_percent', float('nan')):+.1f} %"
            )
        rows.append((f"KITTI {name} (real, 10 Hz)", values, "; ".join(notes)))
    return rows


def recovery_rows(path: Path) -> list[tuple[str, dict[str, float | None], str]]:
    """(sequence, config -> mean ATE over seeds as % of the path, note) per simulated
    sequence."""
    data = json.loads(path.read_text())
    per: dict[str, dict[str, list[float]]] = {}
    for key, per_config in data["results"].items():
        sequence = key.split(" (seed")[0]
        for cfg in CONFIGS:
            r = (per_config or {}).get(cfg)
            if r and r.get("ate_percent_of_path") is not None:
                per.setdefault(sequence, {}).setdefault(cfg, []).append(r["ate_percent_of_path"])
    rows = []
    for sequence, values in per.items():
        if not set(CONFIGS) <= set(values):
            continue
        seeds = min(len(values[c]) for c in CONFIGS)
        means = {c: statistics.mean(values[c]) for c in CONFIGS}
        spread = ", ".join(
            f"{LABELS[c]} {min(values[c]):.3f}-{max(values[c]):.3f}" for c in CONFIGS
        )
        rows.append(
            (
                f"{sequence} (simulated, {data['frames']} frames)",
                means,
                f"mean of {seeds} seeds; range {spread}",
            )
        )
    return rows


def euroc_rows(path: Path) -> list[tuple[str, dict[str, float | None], str]]:
    data = json.loads(path.read_text())
    rows = []
    for row in data.get("rows", []):
        runs = row.get("runs", {})
        if not set(CONFIGS) <= set(runs):
            continue
        values = {c: runs[c].get("ate_m") for c in CONFIGS}
        rows.append((f"EuRoC {row['sequence']} (real, ATE [m])", values, "static camera"))
    return rows


def table(rows: list[tuple[str, dict[str, float | None], str]]) -> str:
    lines = [
        "| sequence | ORB + lines (the default) | XFeat + lines (`--xfeat`) | notes |",
        "|---|---|---|---|",
    ]
    for sequence, values, note in rows:
        known = {c: v for c, v in values.items() if v is not None}
        best = min(known, key=known.get) if len(known) == len(CONFIGS) else None
        cells = []
        for cfg in CONFIGS:
            v = values.get(cfg)
            text = "-" if v is None else f"{v:.3g}"
            tie = (
                len(known) == len(CONFIGS)
                and f"{known[CONFIGS[0]]:.3g}" == f"{known[CONFIGS[1]]:.3g}"
            )
            cells.append(f"**{text}**" if cfg == best and not tie else text)
        lines.append(f"| {sequence} | {cells[0]} | {cells[1]} | {note} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kitti", type=Path, required=True)
    parser.add_argument("--recovery", type=Path, action="append", default=[])
    parser.add_argument("--euroc", type=Path)
    parser.add_argument("--update", type=Path, action="append", default=[])
    args = parser.parse_args(argv)
    rows = kitti_rows(args.kitti)
    for path in args.recovery:
        rows += recovery_rows(path)
    if args.euroc is not None:
        rows += euroc_rows(args.euroc)
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    text = (
        f"Generated by `python benchmarks/frontend_table.py` on {date} (commit {_commit()}; "
        f"{machine_line()}) from the results of `benchmarks/kitti.py` and "
        "`benchmarks/tracking_recovery.py` (and `benchmarks/euroc.py`), each front end with its "
        "preset (ORB's includes the low-light gamma curve). ATE RMSE (SE3 alignment) as a "
        "percentage of the path (EuRoC: in metres), lower is better, the better front end in "
        "bold; KITTI against ORB-SLAM3's stereo trajectory run beside slslam.\n\n" + table(rows)
    )
    print(text)
    for path in args.update:
        update_file(path, "frontends", text)
        print(f"updated {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
