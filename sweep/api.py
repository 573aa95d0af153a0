"""The Python API: the functions the ``sweep`` command line calls, for a script or a notebook.

    import sweep

    spec = sweep.example("crank_rocker")             # or Sweep.from_toml / Sweep.from_dict
    atlas = sweep.run(spec)                          # an xarray.Dataset, in memory
    best = sweep.query(atlas, 'status == "ok" and type == "a"',
                       sort="impact_speed", descending=True, limit=5)   # a pandas DataFrame
    fig = sweep.chart(atlas, x="R", y="largest_link", color="impact_transfer_ratio")
    fig.savefig("chart.png")

Every function checks its input before any compute and raises ``sweep.UserError`` (a
``ValueError``) with a one-line message naming the field and what is allowed. An atlas
argument is an ``xarray.Dataset`` of this tool (``run``, ``open_atlas``) or the path of one.
"""

from __future__ import annotations

import contextlib
import os
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from sweep.errors import UserError

if TYPE_CHECKING:
    import pandas
    import xarray
    from matplotlib.figure import Figure

    from sweep.fronts import Front
    from sweep.spec import Sweep

__all__ = ["Sweep", "UserError", "boundaries", "chart", "example", "examples", "info",
           "open_atlas", "open_boundaries", "parameters", "pareto", "profile", "query",
           "run", "with_requirements"]

#: an atlas computed in memory (``run`` without a path) may take at most this much
IN_MEMORY_LIMIT = 2 * 1024**3  # bytes


def __getattr__(name: str):
    # the spec class on first use: it imports numba (through the kernels' declarations),
    # which `sweep query` and `sweep chart` never need
    if name == "Sweep":
        from sweep.spec import Sweep

        return Sweep
    raise AttributeError(f"module 'sweep.api' has no attribute {name!r}")


# ---------------------------------------------------------------- specs

def examples() -> dict[str, str]:
    """The built-in specs, one per mechanism and capability: {name: title}."""
    import tomllib

    return {name: tomllib.loads(example_text(name)).get("title", "")
            for name in sorted(_example_files())}


def example(name: str) -> Sweep:
    """A built-in spec by name (``examples()`` lists them), validated."""
    from sweep import spec

    if name not in _example_files():
        raise UserError(f"name: unknown example {name!r}; allowed: "
                        + ", ".join(sorted(_example_files())))
    return spec.parse(example_text(name), source=f"example {name}")


def example_text(name: str) -> str:
    """The TOML text of a built-in spec."""
    return resources.files("sweep.example_specs").joinpath(_example_files()[name]).read_text(
        "utf-8")


def _example_files() -> dict[str, str]:
    return {entry.name[:-len(".toml")]: entry.name
            for entry in resources.files("sweep.example_specs").iterdir()
            if entry.name.endswith(".toml")}


def as_sweep(spec: Sweep | Mapping | str | os.PathLike) -> Sweep:
    """A validated Sweep from a Sweep, a spec document (dict) or the path of a TOML file."""
    from sweep.spec import Sweep

    if isinstance(spec, Sweep):
        return spec
    if isinstance(spec, Mapping):
        return Sweep.from_dict(spec)
    if isinstance(spec, (str, os.PathLike)):
        return Sweep.from_toml(spec)
    raise UserError(f"spec: a Sweep, a dict or the path of a TOML file, not "
                    f"{type(spec).__name__}")


# ---------------------------------------------------------------- running

def run(spec: Sweep | Mapping | str | os.PathLike, path: str | os.PathLike | None = None, *,
        force: bool = False, resume: bool = False, chunk: int | None = None,
        workers: int | None = None, scheduler: str | None = None,
        progress: bool = False) -> xarray.Dataset:
    """Run a sweep and return its atlas.

    Without ``path`` the atlas is computed in memory (grids up to about 2 GiB of outputs;
    a larger one asks for a path). With ``path`` (a ``.nc`` file) every finished block is
    kept beside the target, the atlas is written atomically and opened: an interrupted run
    continues with ``resume=True``; an existing file is overwritten only with ``force``;
    a spec's ``[chart]`` is drawn beside it (``ATLAS.png``, and its refined boundaries in
    ``ATLAS.bounds.nc`` where it asks for them). ``chunk``, ``workers`` and ``scheduler``
    (a dask.distributed address) override the spec's ``[run]`` settings. The values do not
    depend on any of them.
    """
    sweep = as_sweep(spec)
    if path is None:
        if resume or force:
            raise UserError("resume/force: only with a path (an atlas in memory has "
                            "nothing to resume or overwrite)")
        from sweep import runner

        sweep = sweep.with_run(chunk=chunk, workers=workers, scheduler=scheduler)
        need = runner.memory_estimate(sweep)
        if need > IN_MEMORY_LIMIT:
            raise UserError(f"path: the atlas would take {need / 1024**3:.1f} GiB in memory; "
                            "give a path to write it to a file")
        return runner.run_in_memory(sweep, progress=progress)
    written = write(sweep, Path(path), force=force, resume=resume, chunk=chunk,
                    workers=workers, scheduler=scheduler, progress=progress)
    return open_atlas(written["atlas"])


def write(sweep: Sweep, target: Path, *, force: bool = False, resume: bool = False,
          chunk: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: bool = False) -> dict:
    """A sweep to an atlas file, with its spec's chart and boundaries beside it (what
    ``sweep run`` does). Returns where each file went and how many blocks were reused."""
    from sweep import resources, runner, store

    store.check_target(target, force or resume)
    if sweep.designs is not None and target.resolve() == Path(sweep.designs.record["atlas"]):
        raise UserError("output: would overwrite the atlas this sweep's designs come from "
                        "(grid.from); write to another file")
    if resume and target.exists():
        raise UserError(f"resume: {target} is already complete")
    chart_path = target.with_suffix(".png") if sweep.chart else None
    if chart_path is not None:
        store.check_target(chart_path, force, suffix=".png")
    bounds_path = (bounds_target(target) if sweep.chart and sweep.chart.boundaries
                   else None)
    if bounds_path is not None:
        store.check_target(bounds_path, force)
    with resources.target_lock(target):
        done = runner.run_sweep(sweep, target, chunk=chunk, workers=workers,
                                scheduler=scheduler, progress=progress, resume=resume,
                                force=force)
        result = {"atlas": target, "chart": chart_path, "boundaries": bounds_path,
                  "crossings": None, **done}
        if bounds_path is None and chart_path is None:
            return result
        with open_atlas(target) as atlas:
            bounds = None
            if bounds_path is not None:
                bounds = boundaries(atlas, sweep.chart.boundaries, path=bounds_path,
                                    workers=workers, force=True, progress=progress)
                result["crossings"] = bounds.sizes["crossing"]
            c = sweep.chart
            chart(atlas, c.x, c.y, c.color, path=chart_path, at=c.at, boundaries=bounds,
                  overlay=c.overlay, force=True)
    return result


def bounds_target(atlas: Path) -> Path:
    """Where the boundaries of an atlas go by default: ATLAS.bounds.nc beside it."""
    return atlas.with_name(atlas.stem + ".bounds.nc")


# ---------------------------------------------------------------- reading atlases

def _open_netcdf(path, what: str):
    import xarray as xr

    p = Path(path)
    if not p.is_file():
        raise UserError(f"{what}: no such file: {p}")
    try:
        return xr.open_dataset(p, engine="netcdf4")
    except Exception as err:  # netCDF4 raises OSError/RuntimeError/ValueError alike
        raise UserError(f"{what}: {p} is not a readable netCDF file "
                        f"({type(err).__name__})") from None


def is_boundaries(ds) -> bool:
    """Whether a dataset is a boundaries file of ``sweep boundaries``."""
    return "grid_point" in ds and "variable" in ds.attrs


def open_atlas(path: str | os.PathLike) -> xarray.Dataset:
    """An atlas file, opened lazily with xarray (close it, or use it in a ``with``)."""
    ds = _open_netcdf(path, "atlas")
    if is_boundaries(ds):
        ds.close()
        raise UserError(f"atlas: {path} holds the boundaries of an atlas, not an atlas; "
                        "`sweep info` describes it")
    problem = atlas_problem(ds)
    if problem:
        ds.close()
        raise UserError(f"atlas: {path} is not an atlas of this tool, or it is damaged "
                        f"({problem})")
    return ds


def atlas_problem(ds) -> str | None:
    """What makes a dataset not an atlas of this tool, or None: a status flag and a
    mechanism, and CF flag attributes that agree on every flag variable."""
    import numpy as np

    if "status" not in ds or "mechanism" not in ds.attrs:
        return "no status variable or mechanism attribute"
    for name, var in ds.data_vars.items():
        if name != "status" and "flag_meanings" not in var.attrs:
            continue
        meanings = str(var.attrs.get("flag_meanings", "")).split()
        values = np.atleast_1d(var.attrs.get("flag_values", []))
        if not meanings or len(meanings) != len(values):
            return f"{name} has no matching flag_values and flag_meanings"
    return None


@contextlib.contextmanager
def reading(ds):
    """Reading an atlas's values: a file whose data netCDF cannot read (overwritten in
    the middle, cut short) is a one-line UserError naming it, not an HDF error."""
    try:
        yield
    except (RuntimeError, OSError) as err:
        text = str(err)
        if "NetCDF" in text or "HDF" in text:
            source = ds.encoding.get("source", "the atlas") if hasattr(ds, "encoding") \
                else "the atlas"
            raise UserError(f"atlas: {source} is damaged or not an atlas of this tool: its "
                            f"data cannot be read ({type(err).__name__}: {text[:80]})") \
                from None
        raise


def open_boundaries(path: str | os.PathLike) -> xarray.Dataset:
    """A boundaries file written by ``boundaries`` (``sweep boundaries``)."""
    ds = _open_netcdf(path, "boundaries")
    if not is_boundaries(ds):
        ds.close()
        raise UserError(f"boundaries: {path} was not written by `sweep boundaries`")
    return ds


def _atlas(atlas) -> xarray.Dataset:
    import xarray as xr

    if isinstance(atlas, xr.Dataset):
        problem = atlas_problem(atlas)
        if problem:
            raise UserError(f"atlas: this Dataset is not an atlas of this tool ({problem})")
        return atlas
    if isinstance(atlas, (str, os.PathLike)):
        return open_atlas(atlas)
    raise UserError(f"atlas: an xarray.Dataset or the path of an atlas, not "
                    f"{type(atlas).__name__}")


def with_requirements(atlas, require):
    """The atlas with the requirements ``require`` (limits as text, "impact_speed <= 10")
    evaluated into its ``requirements`` flag and ``requirement_margin``; unchanged for
    none."""
    from sweep import requirements

    if not require:
        return atlas
    if isinstance(require, str):
        require = [require]
    units = {name: var.attrs.get("units", "") for name, var in atlas.data_vars.items()
             if "flag_meanings" not in var.attrs and var.dtype.kind == "f"}
    limits = requirements.check(tuple(requirements.parse_limit(text, units)
                                      for text in require))
    return requirements.with_requirements(atlas, limits)


def query(atlas, where: str | None = None, *, sort: str | None = None,
          descending: bool = False, limit: int | None = None,
          columns: list[str] | None = None, at: Mapping[str, Any] | None = None,
          require: list[str] | None = None, rank_all: bool = False) -> pandas.DataFrame:
    """The designs of an atlas that satisfy ``where``, as a pandas DataFrame: one row per
    grid point, its axes first, flags as their meanings (``status == "ok"``).

    ``where`` is a condition in the safe query language (names of variables and axes,
    numbers, quoted strings, arithmetic, comparisons, and/or/not, abs sqrt log log10 exp
    isnan isfinite degrees radians). ``sort`` orders by a variable (NaN last), largest
    first with ``descending``. ``columns`` picks variables (default: every variable with
    one value per grid point); a profile is shown at the angle ``at`` gives, e.g.
    ``{"crank_angle": "90deg"}`` (or a number in the axis's units). ``limit``: at most
    that many rows; ``frame.attrs["matched"]`` says how many matched in all. ``require``:
    limits ("impact_speed <= 10") evaluated into the ``requirements`` flag (replacing the
    atlas's own); a design that fails the requirements is never ranked above one that meets
    them, unless ``rank_all``.
    """
    from sweep.selection import at_values, parse, select

    if where is not None:
        parse(where)
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, int)
                              or limit < 1):
        raise UserError(f"limit: a whole number >= 1, not {limit!r}")
    ds = _atlas(atlas)
    with reading(ds):
        ds = with_requirements(ds, require)
        return select(ds, where, sort=sort, limit=limit, columns=columns,
                      descending=descending, at=at_values(at), rank_all=rank_all)


def chart(atlas, x: str, y: str, color: str, *, path: str | os.PathLike | None = None,
          at: Mapping[str, Any] | None = None, degrees: bool = True,
          all_status: bool = False, boundaries: Any = None,
          overlay: str | None = None, force: bool = False,
          require: list[str] | None = None) -> Figure:
    """A design chart of ``color`` over ``x`` and ``y`` as a matplotlib Figure (saved as a
    PNG too where ``path`` is given).

    A numeric output is a colour map with contour lines; a flag (``regime``, ``status``)
    or a count that takes few values, categories named in the legend. Cells without a
    design value are drawn in greys named by their status (``all_status``: colour them
    too). One panel per value of a third grid axis; ``at`` takes other axes at one value
    ({axis: number or "60deg"}). Angles are drawn in degrees unless ``degrees=False``.
    ``require``: limits evaluated into the ``requirements`` flag, e.g. to colour by it.
    ``boundaries``: the refined crossings (a Dataset or the path ``boundaries`` wrote),
    drawn as lines; ``overlay``: a numeric output drawn as labelled contour lines on top.
    An existing PNG is overwritten only with ``force``.
    """
    from sweep.charts import design_figure
    from sweep.selection import at_values

    out = _png(path, force)
    if isinstance(boundaries, (str, os.PathLike)):
        boundaries = open_boundaries(boundaries)
    ds = _atlas(atlas)
    with reading(ds):
        ds = with_requirements(ds, require)
        fig = design_figure(ds, x, y, color, ok_only=not all_status, degrees=degrees,
                            at=at_values(at), boundaries=boundaries, overlay=overlay)
    if out is not None:
        save_figure(fig, out)
    return fig


def profile(atlas, variables: list[str] | str, where: str | None = None, *,
            path: str | os.PathLike | None = None, degrees: bool = True,
            force: bool = False) -> Figure:
    """Profiles (values over the crank angle, e.g. joint reactions) at the first grid
    point matching ``where``, as a matplotlib Figure: one panel per unit (saved as a PNG
    too where ``path`` is given; an existing one is overwritten only with ``force``).
    ``fig.grid_point`` says which grid point it shows."""
    from sweep.charts import profile_figure
    from sweep.selection import parse

    out = _png(path, force)
    if where is not None:
        parse(where)
    names = [v.strip() for v in variables.split(",")] if isinstance(variables, str) \
        else list(variables)
    ds = _atlas(atlas)
    with reading(ds):
        fig, fig.grid_point = profile_figure(ds, [n for n in names if n], where, degrees)
    if out is not None:
        save_figure(fig, out)
    return fig


def _png(path, force: bool) -> Path | None:
    """Where a figure goes, checked before anything is drawn (store.check_target)."""
    from sweep.store import check_target

    if path is None:
        return None
    out = Path(path)
    check_target(out, force, suffix=".png")
    return out


def save_figure(fig, out: Path) -> None:
    """A figure as a PNG, written under a temporary name and renamed (never half)."""
    from sweep.store import atomic

    with atomic(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")


def boundaries(atlas, var: str = "status", tol: float = 1e-8, *,
               path: str | os.PathLike | None = None, force: bool = False,
               resume: bool = False, workers: int | None = None, chunk: int | None = None,
               progress: bool = False) -> xarray.Dataset:
    """Every boundary of a flag variable of an atlas (where ``status`` or ``regime``
    changes between neighbouring grid points), bisected on its grid edge through the same
    kernels to ``tol × max(1, |x|)`` in the axis's units: one row per crossing, with the
    meanings on each side and what explains it. Written atomically to ``path`` (a ``.nc``
    file) where given; an interrupted refinement continues with ``resume=True``."""
    from sweep.refinement import refine

    ds = _atlas(atlas)
    target = None if path is None else Path(path)
    if target is not None:
        from sweep.store import check_target

        source = ds.encoding.get("source")
        if source and target.name and target.resolve() == Path(source).resolve():
            raise UserError("output: would overwrite the atlas itself")
        check_target(target, force or resume)
    with reading(ds):
        return refine(ds, var, tol, target=target, workers=workers, chunk=chunk,
                      resume=resume, force=force, progress=progress)


def info(atlas, require: list[str] | None = None) -> str:
    """What an atlas's designs were computed with, in words and units; the range of every
    output; status counts (and with ``require``, how many designs meet those limits);
    provenance. A boundaries file: its crossings by sides."""
    from sweep import registry
    from sweep.describe import atlas_text, boundaries_text

    if isinstance(atlas, (str, os.PathLike)):
        ds = _open_netcdf(atlas, "atlas")
        if is_boundaries(ds):
            with ds:
                return boundaries_text(ds, str(atlas))
        ds.close()
    ds = _atlas(atlas)
    name = ds.attrs.get("mechanism", "")
    mech = registry.get(name).declaration if name in registry.names() else None
    with reading(ds):
        ds = with_requirements(ds, require)
        return atlas_text(ds, str(atlas) if isinstance(atlas, (str, os.PathLike))
                          else "(in memory)", mech)


def pareto(atlas, maximize: list[str] | str = (), minimize: list[str] | str = (), *,
           where: str | None = None, require: list[str] | None = None, pick: str = "knee",
           weights: list[float] | None = None, path: str | os.PathLike | None = None,
           chart: str | os.PathLike | None = None, degrees: bool = True,
           force: bool = False) -> Front:
    """The Pareto front of an atlas's feasible designs (status ok, requirements met,
    ``where``) in the objectives ``maximize`` and ``minimize`` (output names), and the one
    design the rule ``pick`` names: ``knee`` (nearest the ideal point, each objective
    scaled over the front), ``lexicographic`` (the objectives in the order given, maxima
    first) or ``weighted`` (``weights``, one per objective, on the scaled objectives).

    Returns a ``Front``: ``front.designs`` (an xarray Dataset over ``design``, every
    variable with its attributes, ``picked`` marking the pick), ``front.picked_design``.
    ``path``: the selection written as netCDF (a ``.nc``; a chained sweep's source);
    ``chart``: the front over the feasible cloud as a PNG. ``require`` adds limits as in
    ``query``. Existing files are overwritten only with ``force``.
    """
    from sweep import fronts
    from sweep.selection import parse
    from sweep.store import check_target

    if where is not None:
        parse(where)
    target = None if path is None else Path(path)
    if target is not None:
        check_target(target, force)
    picture = _png(chart, force)
    ds = _atlas(atlas)
    source = ds.encoding.get("source", "")
    with reading(ds):
        ds = with_requirements(ds, require)
        result = fronts.front(ds, maximize, minimize, where=where, pick=pick,
                              weights=weights, source=str(source))
        result.designs.load()
        fig = None if picture is None else fronts.figure(ds, result, where, degrees)
    if target is not None:
        write_selection(result.designs, target)
    if fig is not None:
        save_figure(fig, picture)
    return result


def write_selection(ds: xarray.Dataset, target: Path) -> None:
    """A selection of designs (a front) as netCDF, written under a temporary name and
    renamed (never half)."""
    from sweep.metadata import history_line
    from sweep.store import atomic

    ds = ds.copy()
    ds.attrs["history"] = history_line()
    with atomic(target) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")


def parameters(mechanism: str | None = None) -> str:
    """The mechanisms, or one mechanism's parameters, method keys, outputs and statuses,
    with units, defaults and allowed values."""
    from sweep import registry

    if mechanism is None:
        return "\n".join(f"{name:17s} {registry.get(name).declaration.title}"
                         for name in registry.names())
    if mechanism not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {mechanism!r}; allowed: "
                        + ", ".join(registry.names()))
    from sweep.describe import mechanism_text

    return mechanism_text(registry.get(mechanism).declaration)
