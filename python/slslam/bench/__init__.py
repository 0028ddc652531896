"""Batch evaluation: a spec's sequences x configurations x seeds, each cell one task (Ray, or
inline), cached by content key, summarised into tables and plots.

    from slslam.bench import load_spec, run_bench
    from slslam.bench.results import write_results

    spec = load_spec("benchmarks/specs/smoke.yaml")
    run = run_bench(spec, "results/smoke", workers=2)      # workers=1: inline, no Ray
    write_results(spec, "results/smoke", run)

Modules: spec (the YAML format), keys (content keys), inputs (simulated inputs, made once),
cells (planning and running one cell), runner (cache, Ray / inline backends, interrupts),
results (tables, plots), blocks (marked blocks in Markdown files), cli (``slslam bench``).
"""

from __future__ import annotations

from slslam.bench.runner import BenchInterrupted, BenchRun, run_bench
from slslam.bench.spec import Spec, SpecError, load_spec, parse_spec

__all__ = [
    "BenchInterrupted",
    "BenchRun",
    "Spec",
    "SpecError",
    "load_spec",
    "parse_spec",
    "run_bench",
]
