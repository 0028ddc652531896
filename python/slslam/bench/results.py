"""A sweep's results pages: summary tables (Markdown, CSV), plots and the run record.

Written into the results folder after every invocation (also an interrupted one, from the cells
finished so far):
    summary.md     per sequence and configuration: cells ok / planned, and for each metric the
                   spec reports the mean over seeds, the sample standard deviation and the range
    summary.csv    the same numbers, one row per sequence and configuration
    cells.csv      one row per cell: its key, status, scores, time and memory
    ate.png        ATE RMSE per sequence per configuration (mean, range, each seed a dot)
    trajectories_<sequence>.png   top view: ground truth and every configuration's first seed,
                   SE3-aligned to it (evo)
    bench.json     the invocation: spec, backend, wall time, cells run / cached / failed,
                   machine, commit
"""

from __future__ import annotations

import csv
import logging
import math
import statistics
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from slslam.bench.cells import Cell
from slslam.bench.provenance import git_commit, machine
from slslam.bench.runner import BenchRun, write_json_atomic
from slslam.bench.spec import Spec

log = logging.getLogger(__name__)

#: Summary metrics: (column title, where in the record, format).
METRICS: dict[str, tuple[str, tuple[str, str], str]] = {
    "ate": ("ATE RMSE [m]", ("result", "ate_rmse_m"), "{:.4f}"),
    "rpe": ("RPE RMSE [m]", ("result", "rpe_rmse_m"), "{:.4f}"),
    "posed_ratio": ("posed after init", ("result", "posed_ratio"), "{:.3f}"),
    "maps": ("maps", ("result", "maps"), "{:.2f}"),
    "fps": ("frames/s", ("measurements", "frames_per_s"), "{:.1f}"),
    "memory": ("peak memory [MiB]", ("measurements", "peak_rss_mib"), "{:.0f}"),
}


def _value(record: dict[str, Any], where: tuple[str, str]) -> float | None:
    value = (record.get(where[0]) or {}).get(where[1])
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return float(value)


def stats(values: list[float]) -> dict[str, float | int | None]:
    """Mean, sample standard deviation (None for one value), min, max and count."""
    if not values:
        return {"n": 0, "mean": None, "std": None, "min": None, "max": None}
    return {
        "n": len(values),
        "mean": statistics.fmean(values),
        "std": statistics.stdev(values) if len(values) > 1 else None,
        "min": min(values),
        "max": max(values),
    }


def summarise(spec: Spec, cells: list[Cell], records: dict[str, dict]) -> list[dict[str, Any]]:
    """One row per (sequence, configuration) in spec order: counts and each metric's stats."""
    rows: list[dict[str, Any]] = []
    groups: dict[tuple[str, str], list[Cell]] = {}
    for cell in cells:
        groups.setdefault((cell.sequence, cell.configuration), []).append(cell)
    order = {s.name: i for i, s in enumerate(spec.sequences)}
    for (seq, cfg), group in sorted(groups.items(), key=lambda kv: order[kv[0][0]]):
        done = [records[c.id] for c in group if c.id in records]
        ok = [r for r in done if r.get("status") == "ok"]
        row: dict[str, Any] = {
            "sequence": seq,
            "configuration": cfg,
            "label": group[0].label,
            "cells": len(group),
            "ok": len(ok),
            "failed": sum(r.get("status") != "ok" for r in done),
            "seeds": [c.seed for c in group],
        }
        for metric in spec.report:
            where = METRICS[metric][1]
            row[metric] = stats([v for r in ok if (v := _value(r, where)) is not None])
        rows.append(row)
    return rows


def _fmt(fmt: str, value: float | None) -> str:
    return "-" if value is None else fmt.format(value)


def _cell_text(fmt: str, s: dict[str, Any]) -> str:
    if s["n"] == 0:
        return "-"
    if s["n"] == 1:
        return _fmt(fmt, s["mean"])
    return (
        f"{_fmt(fmt, s['mean'])} ± {_fmt(fmt, s['std'])} "
        f"({_fmt(fmt, s['min'])}-{_fmt(fmt, s['max'])})"
    )


def markdown_table(spec: Spec, rows: list[dict[str, Any]]) -> str:
    """The summary as a Markdown table: mean ± standard deviation (min-max) over seeds."""
    head = ["sequence", "configuration", "seeds ok"] + [METRICS[m][0] for m in spec.report]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row["sequence"], row["label"], f"{row['ok']}/{row['cells']}"]
        cells += [_cell_text(METRICS[m][2], row[m]) for m in spec.report]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def failures_text(records: dict[str, dict]) -> str:
    failed = [(cid, r) for cid, r in sorted(records.items()) if r.get("status") != "ok"]
    if not failed:
        return ""
    lines = ["Failed cells:", ""]
    lines += [f"- `{cid}` ({r.get('status')}): {r.get('error')}" for cid, r in failed]
    return "\n".join(lines)


def _write_csv(path: Path, header: list[str], rows: list[list[Any]]) -> None:
    tmp = path.with_name(path.name + ".partial")
    with tmp.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)
    tmp.replace(path)


def write_summary_csv(path: Path, spec: Spec, rows: list[dict[str, Any]]) -> None:
    header = ["sequence", "configuration", "label", "cells", "ok", "failed"]
    for metric in spec.report:
        header += [f"{metric}_{k}" for k in ("mean", "std", "min", "max")]
    table = []
    for row in rows:
        line = [row[k] for k in ("sequence", "configuration", "label", "cells", "ok", "failed")]
        for metric in spec.report:
            line += [row[metric][k] for k in ("mean", "std", "min", "max")]
        table.append(line)
    _write_csv(path, header, table)


def write_cells_csv(path: Path, cells: list[Cell], records: dict[str, dict]) -> None:
    header = [
        "sequence",
        "configuration",
        "seed",
        "key",
        "status",
        "ate_rmse_m",
        "rpe_rmse_m",
        "posed_ratio",
        "maps",
        "frames",
        "frames_per_s",
        "peak_rss_mib",
        "wall_s",
        "trajectory_sha256",
        "error",
    ]
    table = []
    for cell in cells:
        r = records.get(cell.id)
        if r is None:
            table.append(
                [cell.sequence, cell.configuration, cell.seed, cell.key, "not run"] + [""] * 10
            )
            continue
        res, m = r.get("result") or {}, r.get("measurements") or {}
        table.append(
            [
                cell.sequence,
                cell.configuration,
                cell.seed,
                cell.key,
                r.get("status"),
                res.get("ate_rmse_m"),
                res.get("rpe_rmse_m"),
                res.get("posed_ratio"),
                res.get("maps"),
                res.get("frames"),
                m.get("frames_per_s"),
                m.get("peak_rss_mib"),
                m.get("wall_s"),
                r.get("trajectory_sha256"),
                r.get("error") or "",
            ]
        )
    _write_csv(path, header, table)


def plot_ate(
    path: Path, spec: Spec, rows: list[dict[str, Any]], cells: list[Cell], records: dict[str, dict]
) -> Path | None:
    """Grouped bars: per sequence, each configuration's mean ATE with its range, seeds as dots."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    sequences = list(dict.fromkeys(r["sequence"] for r in rows))
    configs = list(dict.fromkeys(r["configuration"] for r in rows))
    if not sequences or "ate" not in spec.report:
        return None
    width = 0.8 / max(1, len(configs))
    fig, ax = plt.subplots(figsize=(max(6, 1.6 * len(sequences) * max(1, len(configs)) / 2), 4.5))
    labels = {r["configuration"]: r["label"] for r in rows}
    for j, cfg in enumerate(configs):
        x0 = np.arange(len(sequences)) + (j - (len(configs) - 1) / 2) * width
        means, lo, hi = [], [], []
        for seq in sequences:
            row = next(
                (r for r in rows if r["sequence"] == seq and r["configuration"] == cfg), None
            )
            s = row["ate"] if row else {"n": 0}
            means.append(s["mean"] if s["n"] else np.nan)
            lo.append(s["mean"] - s["min"] if s["n"] else 0)
            hi.append(s["max"] - s["mean"] if s["n"] else 0)
        ax.bar(x0, means, width, yerr=[lo, hi], capsize=3, label=labels[cfg], alpha=0.8)
        for k, seq in enumerate(sequences):
            values = [
                _value(records[c.id], ("result", "ate_rmse_m"))
                for c in cells
                if c.sequence == seq and c.configuration == cfg and c.id in records
            ]
            ys = [y for y in values if y is not None]
            ax.plot([x0[k]] * len(ys), ys, "k.", ms=4)
    ax.set_xticks(np.arange(len(sequences)), sequences, rotation=20, ha="right")
    ax.set_ylabel("ATE RMSE [m] (SE3-aligned)")
    ax.set_title(f"{spec.name}: ATE per sequence (bars: mean over seeds, whiskers: range)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _aligned_xy(record: dict[str, Any], out: Path):
    """(ground truth xyz, SE3-aligned estimate xyz) of a finished cell, from its files."""
    from slslam.datasets.trajectory_io import read_trajectory
    from slslam.eval.metrics import compute_ape

    run_dir = out / record["run_dir"]
    estimate = read_trajectory(run_dir / "trajectory.tum", "tum")
    if record["cell"]["kind"] == "visual":
        from slslam.tracking.run import _groundtruth, open_dataset

        # (the sequence's own ground truth, or the spec's groundtruth: file; EuRoC or KITTI)
        given = (record.get("material") or {}).get("sequence", {}).get("groundtruth") or {}
        gt = _groundtruth(open_dataset(record["input"]), given.get("path"))
        if gt is None:
            raise ValueError(f"{record['input']}: no ground truth")
        ape = compute_ape(gt, estimate, align="se3")
    else:
        from slslam.lidar.datasets import open_lidar_sequence
        from slslam.lidar.output import groundtruth_trajectory

        sequence = open_lidar_sequence(record["input"])
        frame = "body" if sequence.groundtruth_frame == "body" else "sensor"
        gt = groundtruth_trajectory(sequence, frame)
        ape = compute_ape(gt, estimate, align="se3", max_diff_s=0.003)
    return ape.reference.positions_xyz, ape.estimate_aligned.positions_xyz


def plot_trajectories(out: Path, cells: list[Cell], records: dict[str, dict]) -> list[Path]:
    """Per sequence: ground truth and each configuration's first finished seed, in the plane of
    the ground truth's two widest axes (x-y for a z-up world, x-z for a camera's: KITTI, EuRoC's
    rectified left camera)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    for seq in dict.fromkeys(c.sequence for c in cells):
        fig, ax = plt.subplots(figsize=(7, 6))
        drawn_gt = False
        for cfg in dict.fromkeys(c.configuration for c in cells if c.sequence == seq):
            first = next(
                (
                    records[c.id]
                    for c in cells
                    if c.sequence == seq
                    and c.configuration == cfg
                    and c.id in records
                    and records[c.id].get("status") == "ok"
                ),
                None,
            )
            if first is None:
                continue
            try:
                ref, est = _aligned_xy(first, out)
            except Exception as exc:  # a plot never fails the sweep
                log.warning("no trajectory of %s/%s in the plot: %s", seq, cfg, exc)
                continue
            if not drawn_gt:
                spread = ref.max(axis=0) - ref.min(axis=0)
                a, b = sorted(int(i) for i in spread.argsort()[-2:])
                ax.plot(ref[:, a], ref[:, b], "k--", lw=1.0, label="ground truth")
                drawn_gt = True
            label = f"{first['cell']['label']} (seed {first['cell']['seed']})"
            ax.plot(est[:, a], est[:, b], lw=1.2, label=label)
        if not drawn_gt:
            plt.close(fig)
            continue
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{'xyz'[a]} [m]")
        ax.set_ylabel(f"{'xyz'[b]} [m]")
        ax.set_title(f"{seq}: trajectories, SE3-aligned to the ground truth")
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = out / f"trajectories_{seq}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def write_results(spec: Spec, out: Path, run: BenchRun, plots: bool = True) -> dict[str, Any]:
    """Writes every page listed in the module docstring; returns bench.json's content."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = summarise(spec, run.cells, run.records)
    table = markdown_table(spec, rows)
    failures = failures_text({c.id: run.records[c.id] for c in run.cells if c.id in run.records})
    info = {
        "spec": str(spec.path),
        "name": spec.name,
        "date_utc": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": git_commit(spec.path.parent),
        "machine": machine(),
        "backend": run.backend,
        "wall_s": run.wall_s,
        "cells": len(run.cells),
        "ran": run.ran,
        "cached": run.cached,
        "failed": run.failed,
        "not_run": [c.id for c in run.cells if c.id not in run.records],
        "summary": rows,
    }
    about = f"{spec.description.strip()}\n\n" if spec.description.strip() else ""
    text = f"# {spec.name}\n\n{about}{table}\n"
    if failures:
        text += f"\n{failures}\n"
    tmp = out / "summary.md.partial"
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(out / "summary.md")
    write_summary_csv(out / "summary.csv", spec, rows)
    write_cells_csv(out / "cells.csv", run.cells, run.records)
    if plots:
        try:
            plot_ate(out / "ate.png", spec, rows, run.cells, run.records)
            plot_trajectories(out, run.cells, run.records)
        except Exception as exc:  # the tables are written; a plot failure is one warning
            log.warning("plots: %s", exc)
    write_json_atomic(out / "bench.json", info)
    return info


def block_text(spec: Spec, run: BenchRun, spec_arg: str) -> str:
    """The Markdown a marked block shows: where the numbers come from, then the summary."""
    done = [run.records[c.id] for c in run.cells if c.id in run.records]
    finished = [
        r["measurements"]["finished_unix"]
        for r in done
        if (r.get("measurements") or {}).get("finished_unix")
    ]
    date = (
        datetime.fromtimestamp(max(finished), timezone.utc).strftime("%Y-%m-%d")
        if finished
        else "never"
    )
    machines = sorted(
        {
            f"{m['machine']['processor']}, {m['machine']['cpu_count']} cores"
            for r in done
            if (m := r.get("measurements") or {}).get("machine")
        }
    )
    builds = sorted(
        {r["material"]["software"]["core"]["commit"] for r in done if r.get("material")}
    )
    versions = sorted({r["material"]["software"]["slslam"] for r in done if r.get("material")})
    checkouts = sorted(
        {
            m["slslam_checkout"]
            for r in done
            if (m := r.get("measurements") or {}).get("slslam_checkout")
        }
    )
    loads = [
        m["load_1min"]
        for r in done
        if (m := r.get("measurements") or {}).get("load_1min") is not None
    ]
    load = (
        f"; 1-minute load average {min(loads):.1f}-{max(loads):.1f} as cells ended" if loads else ""
    )
    rows = summarise(spec, run.cells, run.records)
    lines = [
        f"Generated by `slslam bench report {spec_arg}` from the cells of `slslam bench "
        f"{spec_arg}` (do not edit by hand: the next report replaces this block). "
        f"Cells finished {date} (UTC) on {'; '.join(machines) or 'unknown'}; slslam "
        f"{', '.join(versions) or '?'}, C++ core built from commit "
        f"{', '.join(builds) or '?'}"
        + (f", Python from {', '.join(checkouts)}" if checkouts else "")
        + f"{load}; {len(done)} of {len(run.cells)} cells.",
        "",
    ]
    if spec.description.strip():
        lines += [spec.description.strip(), ""]
    lines.append(markdown_table(spec, rows))
    failures = failures_text({c.id: run.records[c.id] for c in run.cells if c.id in run.records})
    if failures:
        lines += ["", failures]
    return "\n".join(lines)


def load_finished(spec: Spec, out: Path) -> BenchRun:
    """The spec's cells with the records saved under ``out`` that match their keys (any
    status), without running anything."""
    from slslam.bench.cells import plan_cells
    from slslam.bench.runner import read_record

    cells = plan_cells(spec)
    run = BenchRun(cells=cells, records={})
    for cell in cells:
        record = read_record(cell.record_path(out))
        if record is not None and record.get("key") == cell.key:
            run.records[cell.id] = record
            run.cached.append(cell.id)
    return run


def deterministic_view(record: dict[str, Any]) -> dict[str, Any]:
    """The part of a cell record that must not change between runs of the same cell: key,
    status, scores and the trajectory's hash (not times, memory, hosts)."""
    return {k: record.get(k) for k in ("key", "status", "result", "trajectory_sha256")}


def compare_results(a: Path, b: Path) -> dict[str, list[str]]:
    """Cells of two results folders side by side: ``same``, ``different`` (same key, other
    scores or trajectory), ``other_key`` and ``only_a`` / ``only_b`` (cell ids)."""
    from slslam.bench.runner import read_record

    def records(root: Path) -> dict[str, dict[str, Any]]:
        found = {}
        for path in sorted((Path(root) / "cells").glob("*/*/seed*.json")):
            record = read_record(path)
            if record is not None:
                found[str(path.relative_to(Path(root) / "cells").with_suffix(""))] = record
        return found

    ra, rb = records(a), records(b)
    out: dict[str, list[str]] = {
        k: [] for k in ("same", "different", "other_key", "only_a", "only_b")
    }
    for cell_id in sorted(set(ra) | set(rb)):
        if cell_id not in rb:
            out["only_a"].append(cell_id)
        elif cell_id not in ra:
            out["only_b"].append(cell_id)
        elif ra[cell_id].get("key") != rb[cell_id].get("key"):
            out["other_key"].append(cell_id)
        elif deterministic_view(ra[cell_id]) == deterministic_view(rb[cell_id]):
            out["same"].append(cell_id)
        else:
            out["different"].append(cell_id)
    return out
