"""The ``sweep`` command line: a thin layer over the Python API (``sweep.api``).

Exit status 0 on success, 2 on bad input (one line naming the field), 1 on a failure inside.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import click

from sweep import api
from sweep.errors import UserError, for_command_line

DEFAULT_EXAMPLE = "crank_rocker"
EXIT_CODES = ("Exit status: 0 success; 2 bad input (one line naming the field, before any "
              "compute, nothing written); 1 a failure inside (one line; SWEEP_DEBUG=1 shows "
              "the traceback).")
CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


def _epilog(*examples: str) -> str:
    """A command's help ending: its examples, then the exit codes. \b keeps click from
    re-wrapping the example lines."""
    return ("\b\nExamples:\n" + "\n".join(f"  {e}" for e in examples) + "\n\n" + EXIT_CODES)


@click.group(context_settings=CONTEXT, epilog=_epilog(
    "sweep run                          # the built-in default sweep",
    "sweep examples rotary_pendulum -o rp.toml && sweep run rp.toml",
    "sweep query rp.nc --where 'regime == \"period_1\"' --sort impact_speed --desc"))
@click.version_option(package_name="impact-sweep")
def cli():
    """Batch sweeps of impact mechanisms into CF-annotated netCDF design atlases.

    The same functions are a Python API: import sweep; help(sweep)."""


def _spec(spec_file: str | None):
    from sweep import spec

    if spec_file is None:
        return spec.parse(api.example_text(DEFAULT_EXAMPLE), source="default spec")
    path = Path(spec_file)
    if not path.exists() and path.suffix != ".toml" and spec_file in api.examples():
        raise UserError(f"spec: no such file: {spec_file}; it is the name of a built-in "
                        f"example: `sweep examples {spec_file} -o {spec_file}.toml` writes it, "
                        f"then `sweep run {spec_file}.toml`")
    return spec.load(spec_file)


@cli.command(short_help="Run a sweep into a design atlas (netCDF), with its chart.",
             epilog=_epilog("sweep run                       # default: crank_rocker_atlas.nc",
                            "sweep run cr.toml -o cr.nc --force",
                            "sweep run big.toml -o big.nc --resume   # after an interruption",
                            "sweep run cr.toml --scheduler tcp://10.0.0.5:8786"))
@click.argument("spec_file", required=False, metavar="[SPEC]")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="atlas file (.nc)")
@click.option("--force", is_flag=True, help="overwrite an existing atlas")
@click.option("--chunk", type=click.IntRange(1, 10**8), help="points per task")
@click.option("--workers", type=click.IntRange(1, 1024), help="threads (default: all cores)")
@click.option("-q", "--quiet", is_flag=True, help="no progress bar or summary")
@click.option("--resume", is_flag=True, help="continue an interrupted run of the same spec")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="run on a dask.distributed cluster, e.g. tcp://10.0.0.5:8786")
def run(spec_file, output, force, chunk, workers, quiet, resume, scheduler):
    """Run a sweep; with no SPEC, the built-in default (the crank-rocker design atlas).

    The atlas is written atomically; every finished block is kept beside it until then, so
    an interrupted run continues with --resume. A spec's [chart] is drawn beside the atlas
    (ATLAS.png)."""
    from sweep.metadata import file_status_counts, status_summary

    sweep_spec = _spec(spec_file)
    if not quiet:
        for note in sweep_spec.notes:
            click.echo(f"sweep: note: {note}", err=True)
    default = f"{DEFAULT_EXAMPLE}_atlas.nc" if spec_file is None else \
        Path(spec_file).with_suffix(".nc").name
    target = Path(output if output is not None else default)
    started = time.perf_counter()
    done = api.write(sweep_spec, target, force=force, resume=resume, chunk=chunk,
                     workers=workers, scheduler=scheduler, progress=not quiet)
    elapsed = time.perf_counter() - started
    if quiet:
        return
    counts, usable = file_status_counts(target)
    click.echo(f"atlas: {target.resolve()}")
    if done["boundaries"] is not None:
        click.echo(f"boundaries: {done['boundaries'].resolve()} ({done['crossings']:,} "
                   f"crossings of {sweep_spec.chart.boundaries})")
    if done["chart"] is not None:
        click.echo(f"chart: {done['chart'].resolve()}")
    if done["reused"]:
        click.echo(f"resumed: {done['reused']} of {done['blocks']} blocks were already done")
    click.echo(f"{sweep_spec.size:,} points in {elapsed:.2f} s; "
               + status_summary(counts, usable))


@cli.command(short_help="Refine a flag's boundaries (status, regime) to a tolerance.",
             epilog=_epilog("sweep boundaries cr.nc                    # status, to 1e-8",
                            "sweep boundaries rp.nc --var regime --tol 1e-10",
                            "sweep chart cr.nc --x R --y largest_link --color status "
                            "--boundaries cr.bounds.nc"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--var", default="status", show_default=True,
              help="flag variable whose boundaries are refined (status, regime, ...)")
@click.option("--tol", type=float, default=1e-8, show_default=True,
              help="each crossing to within tol max(1, |x|) in its axis's units")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="boundaries file (default: ATLAS.bounds.nc)")
@click.option("--force", is_flag=True, help="overwrite an existing boundaries file")
@click.option("--resume", is_flag=True, help="continue an interrupted run")
@click.option("--chunk", type=click.IntRange(1, 10**8), help="points per task")
@click.option("--workers", type=click.IntRange(1, 1024), help="threads (default: all cores)")
@click.option("-q", "--quiet", is_flag=True, help="no progress or summary")
def boundaries(atlas_file, var, tol, output, force, resume, chunk, workers, quiet):
    """Refine every boundary of a flag variable of an atlas (where status or regime changes
    between neighbouring grid points) to a tolerance, by bisection through the same
    kernels; write the crossings, with what explains each, to a companion netCDF."""
    import collections

    from sweep.selection import flag_names

    target = Path(output) if output is not None else api.bounds_target(Path(atlas_file))
    started = time.perf_counter()
    with api.open_atlas(atlas_file) as ds:
        result = api.boundaries(ds, var, tol, path=target, workers=workers, chunk=chunk,
                                resume=resume, force=force, progress=not quiet)
    if quiet:
        return
    meaning = flag_names(result["side_below"])
    pairs = collections.Counter(
        f"{meaning[int(a)]} | {meaning[int(b)]}" for a, b in
        zip(result["side_below"].values, result["side_above"].values))
    click.echo(f"boundaries: {target.resolve()}")
    click.echo(f"{result.sizes['crossing']:,} crossings in {time.perf_counter() - started:.2f} s "
               f"({result.attrs['kernel_evaluations']:,} kernel evaluations, "
               f"{result.attrs['rounds']} rounds, to {tol:g})")
    if not pairs:
        click.echo(f"  ({var} is the same at every two neighbouring grid points)")
    for pair, count in pairs.most_common():
        click.echo(f"  {count:6,}  {pair}")
    unfollowed = int((result["edge_crossings"].values == 1).sum())
    if unfollowed:
        click.echo(f"  {unfollowed:,} crossings lie on edges with more crossings than were "
                   "followed (see edge_crossings)")


@cli.command(short_help="List the built-in specs, or print or write one as TOML.",
             epilog=_epilog("sweep examples", "sweep examples rotary_pendulum",
                            "sweep examples six_link -o six.toml"))
@click.argument("name", required=False)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="write the TOML here")
@click.option("--force", is_flag=True, help="overwrite an existing file")
def examples(name, output, force):
    """List the built-in specs, or print (or write) one of them as TOML."""
    from sweep.store import atomic, check_target

    if name is None:
        titles = api.examples()
        width = max(map(len, titles))
        for key, title in titles.items():
            click.echo(f"{key:{width}s}  {title}")
        return
    api.example(name)  # an unknown name is refused with the list
    text = api.example_text(name)
    if output is not None:
        target = Path(output)
        check_target(target, force, suffix=".toml")
        with atomic(target) as tmp:
            tmp.write_text(text, encoding="utf-8")
        click.echo(f"wrote {output}")
    else:
        click.echo(text, nl=False)


@cli.command(short_help="A mechanism's parameters, method keys, outputs and statuses.",
             epilog=_epilog("sweep parameters", "sweep parameters rotary_pendulum"))
@click.argument("mechanism", required=False)
def parameters(mechanism):
    """List the mechanisms, or one mechanism's parameters, method keys, outputs and
    statuses with units, defaults and allowed values."""
    click.echo(api.parameters(mechanism))


@cli.command(short_help="What an atlas (or boundaries file) holds and how it was made.",
             epilog=_epilog("sweep info crank_rocker_atlas.nc", "sweep info cr.bounds.nc"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--require", "require", multiple=True, metavar="LIMIT",
              help="a requirement, e.g. 'impact_speed <= 10' or "
                   "'transmission_angle_working >= 40deg' (repeat for more): evaluated into "
                   "the requirements flag")
def info(atlas_file, require):
    """What an atlas's designs were computed with (grid, fixed parameters and method, in words
    and units), the range of every output, status counts and provenance; for a boundaries
    file, its crossings by sides with what explains them."""
    click.echo(api.info(atlas_file, list(require)))


@cli.command(short_help="Select designs from an atlas with a safe expression language.",
             epilog=_epilog(
                 "sweep query cr.nc --where 'status == \"ok\" and lambda2 <= 3' "
                 "--sort impact_speed --desc --limit 10",
                 "sweep query lf.nc --columns force_peak_D,F21_n --at crank_angle=90deg",
                 "sweep query cr.nc --format csv > designs.csv"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--where", "where", default=None, help='condition, e.g. "lambda2 <= 3"')
@click.option("--sort", default=None, help="variable to sort by (ascending; see --descending)")
@click.option("--descending", "--desc", is_flag=True,
              help="sort largest first (the best designs first, for a quantity to maximise)")
@click.option("--limit", type=click.IntRange(1, None), default=None, help="at most N rows")
@click.option("--columns", default=None,
              help="comma-separated variables to show (default: every variable with one "
                   "value per grid point)")
@click.option("--at", "at", multiple=True, metavar="AXIS=VALUE",
              help="profiles at this value of their axis (nearest), e.g. crank_angle=90")
@click.option("--degrees", is_flag=True,
              help="print angles in degrees (--where and --sort stay in the atlas's radians)")
@click.option("--require", "require", multiple=True, metavar="LIMIT",
              help="a requirement, e.g. 'impact_speed <= 10' or "
                   "'transmission_angle_working >= 40deg' (repeat for more): evaluated into "
                   "the requirements flag")
@click.option("--rank-all", is_flag=True,
              help="rank designs that fail a requirement among those that meet them")
@click.option("--format", "fmt", type=click.Choice(["table", "csv", "json"]), default="table")
def query(atlas_file, where, sort, descending, limit, columns, at, degrees, require,
          rank_all, fmt):
    """Select designs from an atlas with a safe expression language; flags print as their
    meanings, the table prints units under its header."""
    from sweep.selection import at_values, in_degrees, parse, units_of

    if where is not None:
        parse(where)  # syntax errors before the atlas is read
    at_values(list(at))
    cols = [c.strip() for c in columns.split(",") if c.strip()] if columns else None
    with api.open_atlas(atlas_file) as ds:
        frame = api.query(ds, where, sort=sort, limit=limit, columns=cols,
                          descending=descending, at=list(at), require=list(require),
                          rank_all=rank_all)
        ds = api.with_requirements(ds, list(require))
        matched = frame.attrs["matched"]
        if degrees:
            frame = in_degrees(ds, frame)
        units = units_of(ds, frame.columns, degrees)
    if fmt == "table" and not len(frame):
        click.echo("no matching points")
    else:
        click.echo(_rows_text(frame, units, fmt), nl=fmt != "csv")
    if fmt == "table" or (limit is None and len(frame) > 50):
        shown = f"{len(frame):,} of {matched:,} matching points" if len(frame) < matched else \
            f"{matched:,} matching points"
        click.echo(shown, err=fmt != "table")


def _records(frame) -> list[dict]:
    """Rows as JSON-able dicts: Python's shortest repr of each float (no digits beyond what
    the value carries), NaN as null."""
    return [{k: (None if isinstance(v, float) and v != v else
                 v.item() if hasattr(v, "item") else v) for k, v in row.items()}
            for row in frame.to_dict(orient="records")]


def _rows_text(frame, units: list[str], fmt: str) -> str:
    """A DataFrame as CSV, JSON records, or a table with units under its header."""
    import json

    if fmt == "csv":
        return frame.to_csv(index=False)
    if fmt == "json":
        return json.dumps(_records(frame))
    import pandas as pd

    header = pd.MultiIndex.from_arrays([list(frame.columns),
                                        [f"[{'-' if u == '1' else u}]" if u else ""
                                         for u in units]])
    return frame.set_axis(header, axis=1).to_string(index=False)


@cli.command(short_help="The Pareto front of an atlas's feasible designs, and one pick.",
             epilog=_epilog(
                 "sweep pareto cr.nc --max impact_speed --min envelope",
                 "sweep pareto cr.nc --max blow_rate --min envelope --require "
                 "'impact_speed <= 10' --chart front.png -o front.nc",
                 "sweep pareto m.nc --max blow_energy --min motor_power_mean --min "
                 "dynamic_force_peak_D --pick weighted --weights 1,1,2"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--max", "maximize", multiple=True, metavar="NAME",
              help="an output to maximise (repeat for more)")
@click.option("--min", "minimize", multiple=True, metavar="NAME",
              help="an output to minimise (repeat for more)")
@click.option("--where", default=None, help="only designs satisfying this condition")
@click.option("--require", "require", multiple=True, metavar="LIMIT",
              help="a requirement, e.g. 'impact_speed <= 10' (repeat for more): replaces "
                   "the atlas's own")
@click.option("--pick", type=click.Choice(["knee", "lexicographic", "weighted"]),
              default="knee", show_default=True,
              help="the rule that picks one design: nearest the ideal point (objectives "
                   "scaled over the front), objectives in the order given, or a weighted "
                   "sum of the scaled objectives")
@click.option("--weights", default=None, metavar="W1,W2,...",
              help="with --pick weighted: one weight per objective, maxima first, then "
                   "minima, each in the order given")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="write the front as netCDF (every variable and attribute kept): a "
                   "chained sweep's source")
@click.option("--chart", "chart_path", type=click.Path(dir_okay=False), default=None,
              metavar="PNG", help="draw the front over the feasible designs")
@click.option("--tie-tol", type=click.FloatRange(0.0, 1e-2, max_open=True), default=1e-9,
              show_default=True,
              help="objective values that agree to this relative tolerance are ties")
@click.option("--degrees", is_flag=True, help="print angles in degrees")
@click.option("--format", "fmt", type=click.Choice(["table", "csv", "json"]), default="table")
@click.option("--sheet", "sheet_path", type=click.Path(dir_okay=False), default=None,
              help="a design sheet of the picked design (.html, and a PDF beside it where "
                   "Chromium is installed)")
@click.option("--force", is_flag=True, help="overwrite existing output files")
def pareto(atlas_file, maximize, minimize, where, require, pick, weights, output, chart_path,
           tie_tol, degrees, fmt, sheet_path, force):
    """The non-dominated feasible designs (status ok, requirements met, --where) of any
    number of objectives, and the design a rule picks, printed with all its outputs."""
    import json

    from sweep.fronts import describe
    from sweep.selection import in_degrees, units_of

    with api.open_atlas(atlas_file) as ds:
        result = api.pareto(ds, list(maximize), list(minimize), where=where,
                            require=list(require), pick=pick,
                            weights=None if weights is None else weights.split(","),
                            path=output, chart=chart_path, degrees=True, force=force,
                            tie_tol=tie_tol, sheet=sheet_path)
    designs = result.designs
    dims = ["design"]
    columns = [c for c in designs.coords if designs[c].dims == ("design",)] + \
        [o.name for o in result.objectives if o.name not in designs.coords] + \
        [n for n in ("requirement_margin", "status") if n in designs.data_vars]
    frame = api.query(designs, columns=list(dict.fromkeys(c for c in columns
                                                          if c not in dims)))
    if degrees:
        frame = in_degrees(designs, frame)
    units = units_of(designs, frame.columns, degrees)
    picked = describe(result, degrees)
    if fmt == "json":
        click.echo(json.dumps({"objectives": [o.text for o in result.objectives],
                               "pick": pick, "candidates": result.candidates,
                               "front": _records(frame),
                               "picked": {name: value for name, value, _, _ in picked}}))
        return
    click.echo(_rows_text(frame, units, fmt), nl=fmt != "csv")
    if fmt == "csv":
        return
    click.echo(f"{len(frame):,} designs on the front of {result.candidates:,} feasible "
               f"({', '.join(o.text for o in result.objectives)})")
    click.echo(f"\npicked ({pick}): design {result.picked}")
    width = max(len(name) for name, _, _, _ in picked)
    for name, value, unit, long_name in picked:
        shown = f"{value} {unit}".strip()
        click.echo(f"  {name:<{width}}  {shown:<24} {long_name}")
    for label, target in (("front", output), ("chart", chart_path)):
        if target:
            click.echo(f"{label}: {Path(target).resolve()}")
    if result.sheet is not None:
        _said_sheet(*result.sheet)


def _said_sheet(page: Path, printed: Path | None) -> None:
    click.echo(f"sheet: {page.resolve()}")
    click.echo(f"pdf: {printed.resolve()}" if printed is not None else
               "pdf: not written: no Chromium (install Debian's chromium to print one)")


@cli.command(short_help="One page for one design: parameters, outputs, margins.",
             epilog=_epilog("sweep sheet limits.nc --design 1767 -o design.html",
                            "sweep sheet front.nc --where 'picked == \"yes\"' -o pick.html"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--design", type=int, default=None,
              help="the design's grid point (its index, as `sweep query` lists it)")
@click.option("--where", default=None, help="condition picking the design (first match)")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="the sheet (.html); a PDF is printed beside it")
@click.option("--no-pdf", is_flag=True, help="the page only")
@click.option("--force", is_flag=True, help="overwrite existing files")
def sheet(atlas_file, design, where, output, no_pdf, force):
    """A design sheet for a review or the workshop: the design's parameters and every output
    with unit and meaning, the requirement margins, its place on a front, its profiles over
    the cycle, the provenance; HTML, and PDF where the distribution's Chromium is
    installed."""
    from sweep.selection import parse
    from sweep.store import check_target

    check_target(Path(output), force, suffix=".html", inputs=[atlas_file])
    if where is not None:
        parse(where)
    with api.open_atlas(atlas_file) as ds:
        _said_sheet(*api.sheet(ds, output, design=design, where=where, pdf=not no_pdf,
                               force=force))


@cli.command(short_help="A design chart (PNG) of one output over two grid axes.",
             epilog=_epilog(
                 "sweep chart cr.nc --x R --y largest_link --color impact_speed -o v.png",
                 "sweep chart rp.nc --x k --y R --color regime --at omega1=60",
                 "sweep chart blade.nc --x tool_window --y R --color regime "
                 "--overlay stability_margin"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--x", "x", required=True, help="variable on the x axis")
@click.option("--y", "y", required=True, help="variable on the y axis")
@click.option("--color", required=True, help="variable shown in colour")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="chart.png",
              show_default=True)
@click.option("--all-status", is_flag=True,
              help="also colour points whose status has no design values")
@click.option("--at", "at", multiple=True, metavar="AXIS=VALUE",
              help="take another grid axis at its nearest value, e.g. omega1=60")
@click.option("--radians", is_flag=True, help="angles in radians (default: degrees)")
@click.option("--boundaries", "bounds_file", default=None, metavar="BOUNDS.nc",
              help="draw the refined boundaries of `sweep boundaries` as lines")
@click.option("--overlay", default=None, metavar="NAME",
              help="a numeric output drawn as labelled contour lines on top, e.g. "
                   "stability_margin over the regime")
@click.option("--require", "require", multiple=True, metavar="LIMIT",
              help="a requirement, e.g. 'impact_speed <= 10' or "
                   "'transmission_angle_working >= 40deg' (repeat for more): evaluated into "
                   "the requirements flag")
@click.option("--force", is_flag=True, help="overwrite an existing PNG")
def chart(atlas_file, x, y, color, output, all_status, at, radians, bounds_file, overlay,
          require, force):
    """Design chart (PNG) of COLOR over X and Y, with units; a flag variable (regime,
    status) is drawn as categories, cells without a value in greys named by their status."""
    from sweep.selection import at_values
    from sweep.store import check_target

    check_target(Path(output), force, suffix=".png")
    at_values(list(at))
    with api.open_atlas(atlas_file) as ds:
        bounds = api.open_boundaries(bounds_file) if bounds_file else None
        api.chart(ds, x, y, color, path=output, all_status=all_status,
                  degrees=not radians, at=list(at), boundaries=bounds, overlay=overlay,
                  force=force, require=list(require))
    click.echo(f"chart: {Path(output).resolve()}")


@cli.command(short_help="Sobol' indices of outputs to inputs, failed designs counted.",
             epilog=_epilog("sweep sensitivity study.toml -o study.nc --chart study.png",
                            "sweep sensitivity study.toml --samples 4096 --outputs blow_rate"))
@click.argument("spec_file", metavar="SPEC")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="the result (.nc)")
@click.option("--chart", "chart_path", type=click.Path(dir_okay=False), default=None,
              help="bars of the indices with their intervals (.png)")
@click.option("--samples", type=int, default=1024, show_default=True,
              help="base samples, a power of two (the kernel runs samples x (inputs + 2))")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--outputs", "names", default=None, help="outputs, comma-separated")
@click.option("--workers", type=click.IntRange(1, 1024), help="threads (default: all cores)")
@click.option("--force", is_flag=True, help="overwrite existing files")
def sensitivity(spec_file, output, chart_path, samples, seed, names, workers, force):
    """The spec's grid axes are the inputs, each uniform over its range; its fixed
    parameters, method, outputs and requirements are the study's. Prints the indices and
    the probability of each status and of meeting the requirements."""
    result = api.sensitivity(spec_file, None,
                             None if names is None else [n for n in names.split(",") if n],
                             samples=samples, seed=seed, path=output, chart=chart_path,
                             force=force, workers=workers)
    click.echo(f"{result.attrs['evaluations']:,} designs ({result.attrs['samples']:,} base "
               f"samples); {result.attrs['method']}")
    inputs = list(result.input.values)
    width = max(len(str(q)) for q in result.quantity.values)
    click.echo(f"{'':<{width}}  " + "  ".join(f"{n:>22}" for n in inputs))
    for q in result.quantity.values:
        row = result.sel(quantity=q)
        cells = [f"S1 {a:5.2f}±{b:4.2f} ST {c:5.2f}" for a, b, c in zip(
            row.first_order.values, row.first_order_conf.values, row.total.values)]
        click.echo(f"{str(q):<{width}}  " + "  ".join(f"{c:>22}" for c in cells))
    _said_study(result, output, chart_path)


def _said_study(result, output, chart_path) -> None:
    """A study's probabilities with their intervals, and where its files went."""
    for event, p, low, high in zip(result.event.values, result.probability.values,
                                   result.probability_low.values,
                                   result.probability_high.values):
        click.echo(f"P({event}) = {p:.4f} [{low:.4f}, {high:.4f}]")
    for label, target in (("result", output), ("chart", chart_path)):
        if target:
            click.echo(f"{label}: {Path(target).resolve()}")


@cli.command(short_help="One design under tolerances: its outputs' spread, its statuses.",
             epilog=_epilog("sweep tolerance front.nc --where 'picked == \"yes\"' "
                            "--tol crank_length=1e-4 --tol rocker_inertia=5% -o tol.nc",
                            "sweep tolerance design.toml --tol R=0.05:0.3 --chart tol.png"))
@click.argument("source", metavar="ATLAS|SPEC")
@click.option("--design", type=int, default=None,
              help="an atlas's design: its grid point (as `sweep query` lists it)")
@click.option("--where", default=None, help="an atlas's design: the first that matches")
@click.option("--tol", "tolerances", multiple=True, metavar="NAME=VALUE", required=True,
              help="+-VALUE in the parameter's units, N%, or LOW:HIGH (repeat for more)")
@click.option("--method", "methods", multiple=True, metavar="KEY=VALUE",
              help="a method option replacing the design's, e.g. geometry_tol=1e-3 (a "
                   "linkage that near a change point modelled as one)")
@click.option("--samples", type=int, default=4096, show_default=True,
              help="a power of two")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="the result (.nc)")
@click.option("--chart", "chart_path", type=click.Path(dir_okay=False), default=None,
              help="the spreads and the statuses' shares (.png)")
@click.option("--workers", type=click.IntRange(1, 1024), help="threads (default: all cores)")
@click.option("--force", is_flag=True, help="overwrite existing files")
def tolerance(source, design, where, tolerances, methods, samples, seed, output, chart_path,
              workers, force):
    """The design (an atlas's, by --design or --where, or a spec of one point) built to the
    tolerances: each output's quantiles where it exists and the share of each status."""
    parsed = {}
    for item in tolerances:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise UserError(f"--tol: NAME=VALUE, not {item!r}")
        if ":" in value:
            low, _, high = value.partition(":")
            try:
                parsed[name] = (float(low), float(high))
            except ValueError:
                raise UserError(f"--tol {name}: LOW:HIGH numbers, not {value!r}") from None
        elif value.endswith("%"):
            parsed[name] = value
        else:
            try:
                parsed[name] = float(value)
            except ValueError:
                raise UserError(f"--tol {name}: a number, N% or LOW:HIGH, not "
                                f"{value!r}") from None
    if source.endswith(".nc"):
        spec_of = api.design_spec(source, design=design, where=where)
    else:
        if design is not None or where is not None:
            raise UserError("--design/--where: pick a design of an atlas; a spec is one "
                            "design already")
        spec_of = source
    method = {}
    for item in methods:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise UserError(f"--method: KEY=VALUE, not {item!r}")
        try:
            method[key] = int(value) if value.lstrip("-").isdigit() else float(value)
        except ValueError:
            method[key] = value
    result = api.tolerance(spec_of, parsed, method=method, samples=samples, seed=seed,
                           path=output, chart=chart_path, force=force, workers=workers)
    click.echo(f"{result.attrs['samples']:,} samples; {result.attrs['method']}")
    levels = [0.01, 0.5, 0.99]
    click.echo(f"{'output':<32} {'design':>14} " + " ".join(f"{f'q{l:g}':>14}"
                                                              for l in levels) + "  with value")
    for name in result.output.values:
        row = result.sel(output=name)
        q = [float(row.quantiles.sel(probability_level=l)) for l in levels]
        click.echo(f"{str(name):<32} {float(row.nominal):>14.6g} "
                   + " ".join(f"{v:>14.6g}" for v in q)
                   + f"  {int(row.samples_with_value):,}")
    _said_study(result, output, chart_path)


@cli.command(short_help="An atlas reduced over a band of one axis: worst, best, spread.",
             epilog=_epilog("sweep robust machine.nc --over R=0.05:0.3 -o robust.nc",
                            "sweep pareto robust.nc --max blow_energy_min --min "
                            "motor_torque_peak_max"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--over", required=True, metavar="AXIS[=LOW:HIGH]",
              help="the band: a grid axis, its whole range or LOW:HIGH inside it")
@click.option("--refine", default=None, metavar="A,B",
              help="outputs whose extremes are refined between samples on the kernel "
                   "(default: those the requirements name; '' for none)")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="the reduced atlas (.nc)")
@click.option("--force", is_flag=True, help="overwrite an existing file")
def robust(atlas_file, over, refine, output, force):
    """Each design's least and greatest value of every output over the band, its spread,
    and whether it is usable and meets the requirements at every point of it."""
    axis, sep, band = over.partition("=")
    if sep:
        low, colon, high = band.partition(":")
        try:
            over = {axis: (float(low), float(high))}
        except ValueError:
            raise UserError(f"--over: AXIS=LOW:HIGH numbers, not {band!r}") from None
        if not colon:
            raise UserError(f"--over: AXIS=LOW:HIGH, not {band!r}")
    names = None if refine is None else [n for n in refine.split(",") if n]
    result = api.robust(atlas_file, over, refine=names, path=output, force=force)
    record = json.loads(result.attrs["robust"])
    usable = int((result["requirements"] == 0).sum()) if "requirements" in result else None
    click.echo(f"over {record['axis']} in {record['band']}: {record['samples_in_band']} "
               f"samples" + (f", ends computed {record['ends_computed']}"
                             if record["ends_computed"] else "")
               + (f", refined: {', '.join(record['refined'])}" if record["refined"] else ""))
    if usable is not None:
        click.echo(f"{usable:,} of {result['status'].size:,} designs meet the requirements "
                   "at every point of the band")
    click.echo(f"atlas: {Path(output).resolve()}")


@cli.command(short_help="An atlas as one HTML page to explore offline, in the browser.",
             epilog=_epilog("sweep explore limits.nc -o limits.html",
                            "sweep explore front.nc -o front.html --vars blow_rate,force_peak_A"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="the page (.html)")
@click.option("--vars", "names", default=None,
              help="2 to 4 numeric variables of the scatter matrix, comma-separated")
@click.option("--max-designs", type=click.IntRange(1, None), default=None,
              help="designs shown at most (beyond: every k-th in grid order, said on the "
                   "page; default 100,000)")
@click.option("--force", is_flag=True, help="overwrite an existing page")
def explore(atlas_file, output, names, max_designs, force):
    """One self-contained page (every script inlined, no network): a chart of any two
    variables coloured by any other, a scatter matrix to brush designs in, hover for a
    design's values, the selected designs as a table and CSV."""
    from sweep.store import check_target

    check_target(Path(output), force, suffix=".html", inputs=[atlas_file])
    with api.open_atlas(atlas_file) as ds:
        page = api.explore(ds, output, variables=names, max_designs=max_designs,
                           force=force)
    click.echo(f"explorer: {page.resolve()}")


@cli.command(short_help="Outputs against one grid axis, one curve per value of another.",
             epilog=_epilog("sweep lines bal.nc --x f --y moment_invariant_peak_balanced "
                            "--by r --values 0.5,1,1.5 -o fig2.png",
                            "sweep lines rp.nc --x k --y impact_speed --by R --at omega1=60"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--x", "x", required=True, help="the grid axis along the curves")
@click.option("--y", "y", required=True, help="outputs, comma-separated (a panel each)")
@click.option("--by", default=None, help="a grid axis: one curve per value")
@click.option("--values", default=None, metavar="V1,V2,...",
              help="the values of --by to draw (nearest grid values)")
@click.option("--at", "at", multiple=True, metavar="AXIS=VALUE",
              help="hold another grid axis at its nearest value (repeat for more)")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="lines.png",
              show_default=True)
@click.option("--radians", is_flag=True, help="angles in radians (default: degrees)")
@click.option("--force", is_flag=True, help="overwrite an existing PNG")
def lines(atlas_file, x, y, by, values, at, output, radians, force):
    """A family of curves, as the papers draw them: gaps where a design has no value."""
    from sweep.selection import at_values
    from sweep.store import check_target

    check_target(Path(output), force, suffix=".png", inputs=[atlas_file])
    at_values(list(at))
    picks = None
    if values is not None:
        picks = []
        for v in values.split(","):
            try:
                picks.append(float(v))
            except ValueError:
                picks.append(v.strip())
    with api.open_atlas(atlas_file) as ds:
        api.lines(ds, x, y, by=by, values=picks, at=list(at), path=output,
                  degrees=not radians, force=force)
    click.echo(f"chart: {Path(output).resolve()}")


@cli.command(short_help="A chart of profiles (over the crank angle) at one grid point.",
             epilog=_epilog("sweep profile lf.nc --vars F21_n,F34_n,balancing_moment "
                            "--where 'omega1 == 30'",
                            "sweep profile six.nc --vars rocker_angle --radians",
                            "sweep profile six.nc --vars rocker_angle,transfer_stage2 "
                            "--against link3_angle",
                            "sweep profile cr.nc --vars transfer_ratio --each type"))
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--vars", "names", required=True, help="comma-separated profile variables")
@click.option("--where", default=None, help="condition picking the grid point (first match)")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="profile.png",
              show_default=True)
@click.option("--radians", is_flag=True, help="angles in radians, ticks at multiples of pi/2")
@click.option("--against", default=None,
              help="a profile for the x axis instead of the crank angle")
@click.option("--each", default=None,
              help="a grid axis: one curve per value of it, the others held at --where")
@click.option("--all", "every", is_flag=True,
              help="one curve per grid point matching --where (at most 12)")
@click.option("--force", is_flag=True, help="overwrite an existing PNG")
def profile(atlas_file, names, where, output, radians, against, each, every, force):
    """Chart of profiles (e.g. joint reactions over crank_angle) at one grid point: one
    panel per unit."""
    from sweep.selection import parse
    from sweep.store import check_target

    check_target(Path(output), force, suffix=".png")
    if where is not None:
        parse(where)
    with api.open_atlas(atlas_file) as ds:
        fig = api.profile(ds, names, where, path=output, degrees=not radians, force=force,
                          against=against, each=each, every=every)
    click.echo(f"profile at {fig.grid_point}: {Path(output).resolve()}")


@cli.command(short_help="Compile the kernels ahead, once per installation.",
             epilog=_epilog("sweep warmup                     # every mechanism",
                            "sweep warmup rotary_pendulum impact_machine"))
@click.argument("mechanisms", nargs=-1, metavar="[MECHANISM ...]")
@click.option("--workers", type=click.IntRange(1, 1024),
              help="processes compiling at once (default: all cores)")
@click.option("-q", "--quiet", is_flag=True, help="no progress bar or summary")
def warmup(mechanisms, workers, quiet):
    """Compile what the first sweeps of these mechanisms need (default: all): each
    built-in example and each pendulum system under the default method, in parallel
    processes, into the compile cache every later run loads. A first run then starts in
    seconds instead of compiling for up to a minute."""
    from kernels.cache import cache_dir

    started = time.perf_counter()
    times = api.warmup(list(mechanisms) or None, workers=workers, progress=not quiet)
    if not quiet:
        click.echo(f"{len(times)} compile jobs in {time.perf_counter() - started:.0f} s "
                   f"({sum(times.values()):.0f} CPU s); cache: {cache_dir()}")


def debugging() -> bool:
    """SWEEP_DEBUG=1 (or true, yes, on) shows a failure's traceback; 0 or empty does not."""
    return os.environ.get("SWEEP_DEBUG", "").strip().lower() in ("1", "true", "yes", "on")


def main(argv: list[str] | None = None) -> None:
    from sweep.resources import RunFailed, RunInterrupted

    args = sys.argv[1:] if argv is None else list(argv)
    if not args:  # `sweep` alone: its usage and commands, as --help prints them
        with click.Context(cli, info_name="sweep", **cli.context_settings) as ctx:
            click.echo(cli.get_help(ctx))
        sys.exit(0)
    try:
        cli.main(args=argv, prog_name="sweep", standalone_mode=False)
    except UserError as err:
        click.echo(f"sweep: error: {for_command_line(str(err))}", err=True)
        sys.exit(2)
    except click.exceptions.Exit as err:
        sys.exit(err.exit_code)
    except click.ClickException as err:
        msg = str(UserError(err.format_message()))  # one line, long words shortened
        click.echo(f"sweep: error: {msg}", err=True)
        sys.exit(2)
    except (KeyboardInterrupt, click.exceptions.Abort) as err:
        # click turns a KeyboardInterrupt into Abort (from it): what the run kept, if any
        cause = err if isinstance(err, RunInterrupted) else err.__cause__
        if isinstance(cause, RunInterrupted):
            click.echo(f"sweep: {cause.message}", err=True)
        else:
            click.echo("sweep: interrupted before the run started; nothing was written",
                       err=True)
        sys.exit(130)
    except RunFailed as err:
        click.echo(f"sweep: error: {for_command_line(str(err))}", err=True)
        sys.exit(1)
    except Exception as err:  # a failure inside: one line, the traceback on request
        if debugging():
            raise
        click.echo(f"sweep: internal error: {type(err).__name__}: {UserError(str(err))} "
                   "(set SWEEP_DEBUG=1 for the traceback)", err=True)
        sys.exit(1)
    sys.exit(0)
