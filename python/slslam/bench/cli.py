"""``slslam bench``: sweep a spec's sequences x configurations x seeds, write the results pages.

    slslam bench SPEC.yaml [--out DIR] [--address ADDR] [--workers N]
    slslam bench report SPEC.yaml [--out DIR] [--update FILE ...]

``slslam bench SPEC`` is ``slslam bench run SPEC``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from typer.core import TyperGroup

from slslam.terminal import stderr_console, stdout_console


class _RunByDefault(TyperGroup):
    """``slslam bench SPEC ...`` runs the spec: anything but a subcommand name goes to ``run``."""

    def parse_args(self, ctx, args):  # type: ignore[no-untyped-def]
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = ["run", *args]
        return super().parse_args(ctx, args)


bench_app = typer.Typer(
    cls=_RunByDefault,
    help="Batch evaluation: sweep a spec's sequences x configurations x seeds (on Ray, or inline "
    "with --workers 1) and write per-cell JSON, summary tables and plots. "
    "`slslam bench SPEC` runs it; `slslam bench report SPEC --update FILE` rewrites a marked "
    "block from the results.",
    no_args_is_help=True,
)

SpecArg = Annotated[
    Path, typer.Argument(help="Benchmark spec (YAML; see benchmarks/specs/ and slslam.bench.spec).")
]
OutOption = Annotated[
    Path | None,
    typer.Option(
        "--out",
        help="Results folder (default: benchmarks/results/<spec name> for a spec in "
        "benchmarks/specs/, else bench_results/<spec name>).",
    ),
]


def default_out(spec_path: Path, name: str) -> Path:
    spec_path = spec_path.resolve()
    if spec_path.parent.name == "specs" and spec_path.parent.parent.name == "benchmarks":
        return spec_path.parent.parent / "results" / name
    return Path("bench_results") / name


@bench_app.command("run")
def bench_run_command(
    spec: SpecArg,
    out: OutOption = None,
    address: Annotated[
        str | None,
        typer.Option(
            help="Join a running Ray cluster (`ray start --head` prints it; 'auto' finds a local "
            "one). Without it Ray starts on this machine's cores. On several machines --out must "
            "be on storage they share."
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(
            min=1,
            help="Local Ray: CPU cores to use (default: all). 1: run the cells inline, one after "
            "the other, without Ray.",
        ),
    ] = None,
    data_dir: Annotated[
        Path | None,
        typer.Option(help="Where simulated inputs are kept (default: <out>/inputs)."),
    ] = None,
    update: Annotated[
        list[Path] | None,
        typer.Option(help="Afterwards rewrite the spec's marked block in this Markdown file."),
    ] = None,
    plots: Annotated[bool, typer.Option(help="Write ate.png and the trajectory plots.")] = True,
    progress: Annotated[bool, typer.Option(help="Show the progress bar.")] = True,
) -> None:
    """Run the spec's missing or changed cells (finished ones are cached by content key) and
    write cells/, summary.md, summary.csv, cells.csv, plots and bench.json into --out."""
    from slslam.bench import load_spec, run_bench
    from slslam.bench.results import write_results
    from slslam.bench.runner import BenchInterrupted

    parsed = load_spec(spec)
    out = out if out is not None else default_out(spec, parsed.name)
    console = stderr_console()
    try:
        run = run_bench(
            parsed,
            out,
            workers=workers,
            address=address,
            data_dir=data_dir,
            progress=progress,
            on_done=lambda r: write_results(parsed, out, r, plots=plots),
        )
    except BenchInterrupted as stop:
        console.print(
            f"[bold red]stopped:[/] {stop}; finished cells are saved in {escape(str(out))} "
            "(run the spec again to complete it)",
            highlight=False,
            soft_wrap=True,
        )
        raise typer.Exit(128 + stop.signum) from None
    say = stdout_console()
    say.print(
        f"{len(run.cells)} cells: {len(run.ran)} run ({run.backend}), {len(run.cached)} cached, "
        f"{len(run.failed)} failed; {run.wall_s:.1f} s"
    )
    for cell_id in run.failed:
        record = run.records[cell_id]
        say.print(
            f"  {cell_id}: {record.get('status')}: {escape(str(record.get('error')))}",
            highlight=False,
            soft_wrap=True,
        )
    for path in update or ():
        _update(parsed, out, spec, path)
    say.print(f"results in {out}/summary.md")
    if run.failed:
        raise typer.Exit(1)


def _update(parsed, out: Path, spec_arg: Path, path: Path) -> None:
    from slslam.bench.blocks import update_file
    from slslam.bench.results import block_text, load_finished

    text = block_text(parsed, load_finished(parsed, out), str(spec_arg))
    changed = update_file(path, parsed.name, text)
    stdout_console().print(
        f"{'updated' if changed else 'unchanged'}: block {parsed.name} in {path}"
    )


@bench_app.command("report")
def bench_report_command(
    spec: SpecArg,
    out: OutOption = None,
    update: Annotated[
        list[Path] | None,
        typer.Option(
            help="Rewrite the spec's marked block (<!-- slslam-bench:NAME begin/end -->)."
        ),
    ] = None,
) -> None:
    """Print (or write into marked blocks) the summary of the spec's finished cells; runs
    nothing."""
    from slslam.bench import load_spec
    from slslam.bench.results import block_text, load_finished

    parsed = load_spec(spec)
    out = out if out is not None else default_out(spec, parsed.name)
    if not update:
        print(block_text(parsed, load_finished(parsed, out), str(spec)))
        return
    for path in update:
        _update(parsed, out, spec, path)


@bench_app.command("compare")
def bench_compare_command(
    a: Annotated[Path, typer.Argument(help="A results folder (--out of a sweep).")],
    b: Annotated[Path, typer.Argument(help="Another results folder.")],
) -> None:
    """Check two sweeps' cells for equal results: same key, status, scores and trajectory bytes
    (times and memory are left out). Exit code 1 when any shared cell differs."""
    from slslam.bench.results import compare_results
    from slslam.errors import InputError

    for folder in (a, b):
        if not (folder / "cells").is_dir():
            raise InputError(folder, "not a results folder (no cells/ in it)")
    found = compare_results(a, b)
    say = stdout_console()
    say.print(
        f"{len(found['same'])} cells identical, {len(found['different'])} different, "
        f"{len(found['other_key'])} with another key, {len(found['only_a'])} only in {a}, "
        f"{len(found['only_b'])} only in {b}",
        soft_wrap=True,
    )
    for cell_id in found["different"]:
        say.print(f"  different: {cell_id}")
    if found["different"]:
        raise typer.Exit(1)
