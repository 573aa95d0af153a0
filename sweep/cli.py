"""The ``sweep`` command line (README, "The command line"): run, examples, parameters, info,
query, chart, profile, boundaries.

Exit status 0 on success, 2 on bad input (one line naming the field), 1 on a failure inside.
"""

from __future__ import annotations

import os
import sys
import time
from importlib import resources
from pathlib import Path

import click

from sweep.errors import UserError

#: the built-in specs: every TOML file of the package sweep.examples, by its stem
EXAMPLES = {entry.name[:-len(".toml")]: entry.name
            for entry in resources.files("sweep.examples").iterdir()
            if entry.name.endswith(".toml")}
DEFAULT_EXAMPLE = "crank_rocker"


def _example_text(name: str) -> str:
    return resources.files("sweep.examples").joinpath(EXAMPLES[name]).read_text("utf-8")


def _open_netcdf(path: str, what: str):
    import xarray as xr

    p = Path(path)
    if not p.is_file():
        raise UserError(f"{what}: no such file: {p}")
    try:
        return xr.open_dataset(p, engine="netcdf4")
    except Exception as err:  # netCDF4 raises OSError/RuntimeError/ValueError alike
        raise UserError(f"{what}: {p} is not a readable netCDF file "
                        f"({type(err).__name__})") from None


def _is_boundaries(ds) -> bool:
    return "grid_point" in ds and "variable" in ds.attrs


def _open_atlas(path: str):
    ds = _open_netcdf(path, "atlas")
    p = Path(path)
    if _is_boundaries(ds):
        raise UserError(f"atlas: {p} holds the boundaries of an atlas, not an atlas; "
                        "`sweep info` describes it")
    if "status" not in ds or "mechanism" not in ds.attrs:
        raise UserError(f"atlas: {p} is not an impact-sweep atlas (no status or mechanism)")
    return ds


def _open_boundaries(path: str):
    ds = _open_netcdf(path, "boundaries")
    if not _is_boundaries(ds):
        raise UserError(f"boundaries: {path} was not written by `sweep boundaries`")
    return ds


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="impact-sweep")
def cli():
    """Batch sweeps of impact mechanisms into CF-annotated netCDF design atlases."""


@cli.command()
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
    """Run a sweep; with no SPEC, the built-in default (the crank-rocker design atlas)."""
    from sweep import runner, spec, store
    from sweep.metadata import file_status_counts

    if spec_file is None:
        sweep_spec = spec.parse(_example_text(DEFAULT_EXAMPLE), source="default spec")
        target = Path(output or f"{DEFAULT_EXAMPLE}_atlas.nc")
    else:
        sweep_spec = spec.load(spec_file)
        target = Path(output or Path(spec_file).with_suffix(".nc").name)
    if target.suffix != ".nc":
        raise UserError(f"output: {target} must end in .nc")
    store.check_target(target, force or resume)
    if resume and target.exists():
        raise UserError(f"resume: {target} is already complete")
    chart_path = target.with_suffix(".png") if sweep_spec.chart else None
    if chart_path is not None and chart_path.exists() and not force:
        raise UserError(f"output: {chart_path} exists; use --force to overwrite it")
    bounds_path = (bounds_target(target) if sweep_spec.chart and sweep_spec.chart.boundaries
                   else None)
    if bounds_path is not None:
        store.check_target(bounds_path, force)

    started = time.perf_counter()
    done = runner.run_sweep(sweep_spec, target, chunk=chunk, workers=workers,
                            scheduler=scheduler, progress=not quiet, resume=resume,
                            force=force)
    elapsed = time.perf_counter() - started
    # opened (with xarray) only for what reads it: the boundaries and the chart
    written = _open_atlas(str(target)) if bounds_path or chart_path else None
    bounds = None
    if bounds_path is not None:
        from sweep.boundaries import refine

        bounds = refine(written, sweep_spec.chart.boundaries, target=bounds_path,
                        workers=workers, force=True, progress=not quiet)
    if chart_path is not None:
        from sweep.chart import design_chart

        c = sweep_spec.chart
        design_chart(written, c.x, c.y, c.color, chart_path, at=c.at_values(),
                     boundaries=bounds, overlay=c.overlay)
    if not quiet:
        counts = file_status_counts(target)
        click.echo(f"atlas: {target.resolve()}")
        if bounds_path is not None:
            click.echo(f"boundaries: {bounds_path.resolve()} ({bounds.sizes['crossing']:,} "
                       f"crossings of {sweep_spec.chart.boundaries})")
        if chart_path is not None:
            click.echo(f"chart: {chart_path.resolve()}")
        if done["reused"]:
            click.echo(f"resumed: {done['reused']} of {done['blocks']} blocks were already "
                       "done")
        click.echo(f"{sweep_spec.size} points in {elapsed:.2f} s; status: "
                   + ", ".join(f"{k} {v}" for k, v in counts.items() if v))
    if written is not None:
        written.close()


def bounds_target(atlas: Path) -> Path:
    """Where the boundaries of an atlas go by default: ATLAS.bounds.nc beside it."""
    return atlas.with_name(atlas.stem + ".bounds.nc")


@cli.command()
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
    from sweep.boundaries import refine

    ds = _open_atlas(atlas_file)
    target = Path(output) if output else bounds_target(Path(atlas_file))
    if target.suffix != ".nc":
        raise UserError(f"output: {target} must end in .nc")
    if target.resolve() == Path(atlas_file).resolve():
        raise UserError("output: would overwrite the atlas itself")
    started = time.perf_counter()
    result = refine(ds, var, tol, target=target, workers=workers, chunk=chunk,
                    resume=resume, force=force, progress=not quiet)
    ds.close()
    if quiet:
        return
    import collections

    from sweep.query import flag_names

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


@cli.command()
@click.argument("name", required=False)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="write the TOML here")
def examples(name, output):
    """List the built-in specs, or print (or write) one of them as TOML."""
    if name is None:
        import tomllib
        width = max(map(len, EXAMPLES))
        for key in sorted(EXAMPLES):
            title = tomllib.loads(_example_text(key)).get("title", "")
            click.echo(f"{key:{width}s}  {title}")
        return
    if name not in EXAMPLES:
        raise UserError(f"name: unknown example {name!r}; allowed: {', '.join(EXAMPLES)}")
    text = _example_text(name)
    if output:
        if Path(output).exists():
            raise UserError(f"output: {output} exists")
        Path(output).write_text(text, encoding="utf-8")
        click.echo(f"wrote {output}")
    else:
        click.echo(text, nl=False)


@cli.command()
@click.argument("mechanism", required=False)
def parameters(mechanism):
    """List the mechanisms, or one mechanism's parameters, method keys, outputs and
    statuses with units, defaults and allowed values."""
    from sweep import registry

    if mechanism is None:
        for name in registry.names():
            click.echo(f"{name:17s} {registry.get(name).declaration.title}")
        return
    if mechanism not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {mechanism!r}; allowed: "
                        + ", ".join(registry.names()))
    from sweep.describe import mechanism_text

    click.echo(mechanism_text(registry.get(mechanism).declaration))


@cli.command()
@click.argument("atlas_file", metavar="ATLAS")
def info(atlas_file):
    """What an atlas's designs were computed with (grid, fixed parameters and method, in words
    and units), the range of every output, status counts and provenance; for a boundaries
    file, its crossings by sides with what explains them."""
    from sweep import registry
    from sweep.describe import atlas_text, boundaries_text

    ds = _open_netcdf(atlas_file, "atlas")
    if _is_boundaries(ds):
        click.echo(boundaries_text(ds, atlas_file))
        return
    ds.close()
    ds = _open_atlas(atlas_file)
    name = ds.attrs.get("mechanism", "")
    mech = registry.get(name).declaration if name in registry.names() else None
    click.echo(atlas_text(ds, atlas_file, mech))


def _at_values(pairs) -> dict[str, float]:
    """--at DIM=VALUE options as a dict (the value in the axis's own units)."""
    at = {}
    for pair in pairs:
        dim, sep, value = pair.partition("=")
        value = value.strip()
        unit = "deg" if value.endswith(("deg", "°")) else ""
        try:
            number = float(value.removesuffix("deg").removesuffix("°"))
        except ValueError:
            sep = ""
        if not sep:
            raise UserError(f"at: {pair!r} must be AXIS=NUMBER in the axis's units, or "
                            "NUMBERdeg for an angle, e.g. crank_angle=90deg")
        at[dim.strip()] = (number, unit)
    return at


@cli.command()
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
@click.option("--format", "fmt", type=click.Choice(["table", "csv", "json"]), default="table")
def query(atlas_file, where, sort, descending, limit, columns, at, degrees, fmt):
    """Select designs from an atlas with a safe expression language; flags print as their
    meanings, the table prints units under its header."""
    import json

    from sweep.query import in_degrees, parse, select, units_of

    if where is not None:
        parse(where)  # syntax errors before the atlas is read
    at_values = _at_values(at)
    ds = _open_atlas(atlas_file)
    cols = [c.strip() for c in columns.split(",") if c.strip()] if columns else None
    frame = select(ds, where, sort=sort, limit=limit, columns=cols, descending=descending,
                   at=at_values)
    matched = frame.attrs["matched"]
    if degrees:
        frame = in_degrees(ds, frame)
    if fmt == "csv":
        click.echo(frame.to_csv(index=False), nl=False)
    elif fmt == "json":
        # Python's shortest repr of each float: no digits beyond what the value carries
        records = [{k: (None if isinstance(v, float) and v != v else
                        v.item() if hasattr(v, "item") else v) for k, v in row.items()}
                   for row in frame.to_dict(orient="records")]
        click.echo(json.dumps(records))
    elif not len(frame):
        click.echo("no matching points")
    else:
        import pandas as pd

        units = units_of(ds, frame.columns, degrees)
        header = pd.MultiIndex.from_arrays([list(frame.columns),
                                            [f"[{'-' if u == '1' else u}]" if u else ""
                                             for u in units]])
        click.echo(frame.set_axis(header, axis=1).to_string(index=False))
    if fmt == "table" or (limit is None and len(frame) > 50):
        total = matched
        shown = f"{len(frame):,} of {total:,} matching points" if len(frame) < total else \
            f"{total:,} matching points"
        click.echo(shown, err=fmt != "table")


@cli.command()
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--x", "x", required=True, help="variable on the x axis")
@click.option("--y", "y", required=True, help="variable on the y axis")
@click.option("--color", required=True, help="variable shown in colour")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="chart.png")
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
def chart(atlas_file, x, y, color, output, all_status, at, radians, bounds_file, overlay):
    """Design chart (PNG) of COLOR over X and Y, with units; a flag variable (regime,
    status) is drawn as categories, cells without a value in greys named by their status."""
    from sweep.chart import design_chart

    if not output.endswith(".png"):
        raise UserError(f"output: {output} must end in .png")
    at_values = _at_values(at)
    ds = _open_atlas(atlas_file)
    bounds = _open_boundaries(bounds_file) if bounds_file else None
    path = design_chart(ds, x, y, color, Path(output), ok_only=not all_status,
                        degrees=not radians, at=at_values, boundaries=bounds,
                        overlay=overlay).path
    click.echo(f"chart: {path.resolve()}")


@cli.command()
@click.argument("atlas_file", metavar="ATLAS")
@click.option("--vars", "names", required=True, help="comma-separated profile variables")
@click.option("--where", default=None, help="condition picking the grid point (first match)")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="profile.png")
@click.option("--radians", is_flag=True, help="angles in radians, ticks at multiples of pi/2")
def profile(atlas_file, names, where, output, radians):
    """Chart of profiles (e.g. joint reactions over crank_angle) at one grid point."""
    from sweep.chart import profile_chart
    from sweep.query import parse

    if not output.endswith(".png"):
        raise UserError(f"output: {output} must end in .png")
    if where is not None:
        parse(where)
    ds = _open_atlas(atlas_file)
    path, at = profile_chart(ds, [n.strip() for n in names.split(",") if n.strip()], where,
                             Path(output), degrees=not radians)
    click.echo(f"profile at {at}: {path.resolve()}")


def main(argv: list[str] | None = None) -> None:
    try:
        cli.main(args=argv, prog_name="sweep", standalone_mode=False)
    except UserError as err:
        click.echo(f"sweep: error: {err}", err=True)
        sys.exit(2)
    except click.exceptions.Exit as err:
        sys.exit(err.exit_code)
    except click.ClickException as err:
        msg = " ".join(err.format_message().split())
        click.echo(f"sweep: error: {msg}", err=True)
        sys.exit(2)
    except (KeyboardInterrupt, click.exceptions.Abort):
        click.echo("sweep: interrupted; nothing was written", err=True)
        sys.exit(130)
    except Exception as err:  # a failure inside: one line, the traceback on request
        if os.environ.get("SWEEP_DEBUG"):
            raise
        click.echo(f"sweep: internal error: {type(err).__name__}: {err} "
                   "(set SWEEP_DEBUG=1 for the traceback)", err=True)
        sys.exit(1)
    sys.exit(0)
