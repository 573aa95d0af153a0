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
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from sweep import example_specs
from sweep.errors import UserError

if TYPE_CHECKING:
    import pandas
    import xarray
    from matplotlib.figure import Figure

    from sweep.fronts import Front
    from sweep.spec import Sweep

    #: an atlas: a Dataset of this tool, or the path of one
    AtlasLike = xarray.Dataset | str | os.PathLike

__all__ = ["Sweep", "UserError", "boundaries", "chart", "decode", "example", "examples",
           "explore", "info", "open_atlas", "open_boundaries", "parameters", "pareto", "profile",
           "query", "robust", "run", "sensitivity", "sheet", "tolerance", "design_spec",
           "lines", "warmup", "with_requirements"]

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
    """The built-in specs, one per mechanism and capability.

    Returns:
        {name: title} of every built-in spec, sorted by name.

    Example:
        >>> import sweep
        >>> "crank_rocker" in sweep.examples()
        True
    """
    return example_specs.titles()


def example(name: str) -> Sweep:
    """A built-in spec by name, validated.

    Parameters:
        name: a name ``examples()`` lists.

    Returns:
        The validated ``Sweep``.

    Raises:
        UserError: ``name`` is not a built-in spec (the message lists them).

    Example:
        >>> import sweep
        >>> sweep.example("six_link").mechanism.name
        'six_link'
    """
    from sweep import spec

    if name not in example_specs.names():
        raise UserError(f"name: unknown example {name!r}; allowed: "
                        + ", ".join(example_specs.names()))
    return spec.parse(example_text(name), source=f"example {name}")


def example_text(name: str) -> str:
    """The TOML text of a built-in spec."""
    return example_specs.text(name)


def as_sweep(spec: Sweep | Mapping | str | os.PathLike) -> Sweep:
    """A validated Sweep from a Sweep, a spec document (dict) or the path of a TOML file."""
    from sweep.spec import Sweep

    if isinstance(spec, Sweep):
        return spec
    if isinstance(spec, Mapping):
        return Sweep.from_dict(spec)
    if isinstance(spec, str) and "\n" in spec:
        raise UserError("spec: TOML text, not the path of a file: pass "
                        "sweep.Sweep.from_text(text), or write it to a file")
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
    ``ATLAS.bounds.nc`` where it asks for them). The values do not depend on ``chunk``,
    ``workers`` or ``scheduler``.

    Parameters:
        spec: a ``Sweep``, a spec document as a dict (grid axes as lists, tuples, ranges or
            numpy arrays), or the path of a TOML file.
        path: where to write the atlas (``.nc``); ``None`` keeps it in memory.
        force: overwrite an existing atlas at ``path`` (never one of the run's inputs).
        resume: continue an interrupted run on ``path``.
        chunk: points per block (overrides the spec's ``[run] chunk``).
        workers: threads (default: every core).
        scheduler: the address of a dask.distributed scheduler to run on.
        progress: show a progress bar on standard error.

    Returns:
        The atlas, an ``xarray.Dataset``: every output with its units and long_name, a
        ``status`` flag per design, and the spec, method and provenance in its attributes.

    Raises:
        UserError: bad input (a spec, an argument), before any compute and before anything
            is written; a run that cannot fit the disk or the memory.

    Example:
        >>> import sweep
        >>> atlas = sweep.run({"mechanism": "crank_rocker",
        ...                    "grid": {"R": [0.2, 0.3], "largest_link": (2.0, 3.0)}})
        >>> dict(atlas.sizes)
        {'R': 2, 'largest_link': 2}
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
    written = write(sweep, path_argument(path, "path"), force=force, resume=resume, chunk=chunk,
                    workers=workers, scheduler=scheduler, progress=progress)
    return open_atlas(written["atlas"])


def write(sweep: Sweep, target: Path, *, force: bool = False, resume: bool = False,
          chunk: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: bool = False) -> dict:
    """A sweep to an atlas file, with its spec's chart and boundaries beside it (what
    ``sweep run`` does). Returns where each file went and how many blocks were reused."""
    from sweep import resources, runner, store

    inputs = [sweep.designs.record["atlas"]] if sweep.designs is not None else []
    store.check_target(target, force or resume, inputs=inputs)
    if resume and target.exists():
        raise UserError(f"resume: {target} is already complete")
    chart_path = target.with_suffix(".png") if sweep.chart else None
    if chart_path is not None:
        store.check_target(chart_path, force, suffix=".png", inputs=inputs)
    bounds_path = (bounds_target(target) if sweep.chart and sweep.chart.boundaries
                   else None)
    if bounds_path is not None:
        store.check_target(bounds_path, force, inputs=inputs)
    runner.check_run(sweep.with_run(chunk=chunk, workers=workers, scheduler=scheduler),
                     target)  # disk and memory before the lock: a full disk takes no lock
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


def warmup(mechanisms: list[str] | str | None = None, *, workers: int | None = None,
           progress: bool = False) -> dict[str, float]:
    """Compile ahead what the first sweeps of these mechanisms need.

    Each built-in example of them and, for the rotary pendulum, each system under the
    default method, compiled in parallel processes into the compile cache every later run
    loads (once per installation).

    Parameters:
        mechanisms: a name or a list of names (default: every mechanism).
        workers: processes compiling at once (default: the cores).
        progress: show a progress bar.

    Returns:
        The CPU seconds of each compile job, by name.

    Raises:
        UserError: an unknown mechanism, or ``workers`` not a whole number >= 1.
    """
    from sweep.compile_ahead import warm_up_mechanisms

    if isinstance(mechanisms, str):
        mechanisms = [mechanisms]
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise UserError(f"workers: a whole number of processes, at least 1, not {workers!r}")
    return warm_up_mechanisms(mechanisms, workers, progress)


def bounds_target(atlas: Path) -> Path:
    """Where the boundaries of an atlas go by default: ATLAS.bounds.nc beside it."""
    return atlas.with_name(atlas.stem + ".bounds.nc")


# ---------------------------------------------------------------- reading atlases

def path_argument(value, name: str) -> Path:
    """A path argument of the API as a Path, or a UserError naming the argument."""
    if isinstance(value, (str, os.PathLike)):
        return Path(value)
    raise UserError(f"{name}: the path of a file (a str or os.PathLike), not "
                    f"{type(value).__name__}")


def _open_netcdf(path, what: str):
    import xarray as xr

    p = path_argument(path, what)
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
    """An atlas file, opened lazily with xarray.

    Parameters:
        path: the atlas (a ``.nc`` written by ``run`` or ``sweep run``).

    Returns:
        The atlas as an ``xarray.Dataset``; close it, or use it in a ``with``.

    Raises:
        UserError: no such file, not a netCDF file, not an atlas of this tool (a
            boundaries file is named as one), or ``path`` is not a path.
    """
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
    """A boundaries file written by ``boundaries`` (``sweep boundaries``).

    Parameters:
        path: the file (``ATLAS.bounds.nc``).

    Returns:
        The crossings as an ``xarray.Dataset``.

    Raises:
        UserError: no such file, or not a file ``boundaries`` wrote.
    """
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


def decode(atlas: AtlasLike) -> xarray.Dataset:
    """The atlas with every flag variable as its meanings, for plain xarray.

    A flag variable (``status``, ``regime``, ``requirements``, ...) holds small integer
    codes with CF ``flag_values`` and ``flag_meanings``; here it holds the meanings as
    text, so that xarray compares them by name. The flag attributes stay, for reference.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).

    Returns:
        A copy of the atlas with its flags as text.

    Raises:
        UserError: ``atlas`` is not an atlas of this tool.

    Example:
        >>> import sweep
        >>> atlas = sweep.run({"mechanism": "crank_rocker",
        ...                    "grid": {"R": [0.2], "largest_link": [1.5, 3.0]}})
        >>> sweep.decode(atlas).status.values.ravel().tolist()
        ['second_special_position', 'ok']
        >>> int((sweep.decode(atlas).status == "ok").sum())
        1
    """
    import numpy as np

    from sweep.selection import flag_names

    ds = _atlas(atlas).copy()
    for name, var in list(ds.variables.items()):
        if "flag_meanings" not in var.attrs:
            continue
        meaning = flag_names(var)
        codes = np.unique(var.values)
        words = np.array([meaning.get(int(code), "") for code in codes])
        ds[name] = var.copy(data=words[np.searchsorted(codes, var.values)])
    return ds


def with_requirements(atlas: AtlasLike,
                      require: list[str] | str | None) -> xarray.Dataset:
    """The atlas with requirements evaluated into its ``requirements`` flag.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        require: limits as text (``"impact_speed <= 10"``, ``"transmission_angle_working
            >= 40deg"``), one or a list; replacing the atlas's own. None or empty: the
            atlas unchanged.

    Returns:
        The atlas with the flag ``requirements`` (``met``, ``no_value``, or the limit
        failed by the most) and ``requirement_margin`` (the smallest relative slack). A
        design that fails a limit is named by it even where another limit's output has no
        value there: a failure takes precedence over ``no_value``.

    Raises:
        UserError: a limit that is not ``NAME OP NUMBER`` on a numeric output.

    Example:
        >>> import sweep
        >>> atlas = sweep.run({"mechanism": "crank_rocker",
        ...                    "grid": {"R": [0.2, 0.3], "largest_link": [3.0]}})
        >>> flagged = sweep.with_requirements(atlas, "impact_speed <= 1")
        >>> sweep.decode(flagged).requirements.values.ravel().tolist()
        ['above_impact_speed', 'above_impact_speed']
    """
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


def query(atlas: AtlasLike, where: str | None = None, *, sort: str | None = None,
          descending: bool = False, limit: int | None = None,
          columns: list[str] | str | None = None, at: Mapping[str, Any] | None = None,
          require: list[str] | str | None = None,
          rank_all: bool = False) -> pandas.DataFrame:
    """The designs of an atlas that satisfy a condition, as a table.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        where: a condition in the safe query language: names of variables and axes,
            numbers, quoted strings, arithmetic, comparisons, and/or/not, abs sqrt log
            log10 exp isnan isfinite degrees radians; flags compare by meaning
            (``status == "ok"``).
        sort: a variable to order by (NaN last).
        descending: largest first.
        limit: at most this many rows (``frame.attrs["matched"]`` says how many matched).
        columns: the variables to show, a list or a string of names separated by commas
            (default: every variable with one value per grid point).
        at: profiles at this value of their axis, e.g. ``{"crank_angle": "90deg"}``.
        require: limits evaluated into the ``requirements`` flag (``with_requirements``).
        rank_all: rank designs that fail a requirement among those that meet them.

    Returns:
        A ``pandas.DataFrame``, one row per grid point, its axes first, flags as their
        meanings.

    Raises:
        UserError: a condition, name or argument that is not allowed (one line naming it).

    Example:
        >>> import sweep
        >>> atlas = sweep.run({"mechanism": "crank_rocker",
        ...                    "grid": {"R": [0.2, 0.3], "largest_link": [3.0]}})
        >>> frame = sweep.query(atlas, 'status == "ok"', sort="impact_speed",
        ...                     descending=True, columns="impact_speed")
        >>> list(frame.columns), len(frame)
        (['R', 'largest_link', 'impact_speed'], 2)
    """
    from sweep.selection import at_values, parse, select

    if where is not None:
        parse(where)
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, int)
                              or limit < 1):
        raise UserError(f"limit: a whole number >= 1, not {limit!r}")
    if isinstance(columns, str):
        columns = [c.strip() for c in columns.split(",") if c.strip()]
    ds = _atlas(atlas)
    with reading(ds):
        ds = with_requirements(ds, require)
        return select(ds, where, sort=sort, limit=limit, columns=columns,
                      descending=descending, at=at_values(at), rank_all=rank_all)


def chart(atlas: AtlasLike, x: str, y: str, color: str, *, path: str | os.PathLike | None = None,
          at: Mapping[str, Any] | None = None, degrees: bool = True,
          all_status: bool = False, boundaries: Any = None,
          overlay: str | None = None, force: bool = False,
          require: list[str] | None = None, ax: Any = None, cmap: str | None = None,
          figsize: tuple[float, float] | None = None) -> Figure:
    """A design chart of one variable over two grid axes.

    A numeric output is a colour map with contour lines; a flag (``regime``, ``status``)
    or a count that takes few values, categories named in the legend. Cells without a
    design value are drawn in greys named by their status. One panel per value of a third
    grid axis. Angles are drawn in degrees unless ``degrees=False``.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        x: the grid axis across the chart.
        y: the grid axis up the chart.
        color: the variable drawn in colour.
        path: a PNG to save the chart to (an existing one only with ``force``).
        at: other grid axes taken at one value, {axis: number or "60deg"}.
        degrees: angles in degrees.
        all_status: colour the cells of every status, not only the usable ones.
        boundaries: refined crossings (a Dataset or the path ``boundaries`` wrote), drawn
            as lines.
        overlay: a numeric output drawn as labelled contour lines on top.
        force: overwrite an existing PNG (never the atlas itself).
        require: limits evaluated into the ``requirements`` flag, e.g. to colour by it.
        ax: draw into these matplotlib axes (one panel: hold a third grid axis with
            ``at``), e.g. beside the user's own plots; the colour bar or legend goes
            beside them, the title is left to the user.
        cmap: a matplotlib colour map's name for a numeric colour variable (a flag keeps
            its meaning's colours).
        figsize: (width, height) of a new figure in inches.

    Returns:
        The ``matplotlib.figure.Figure`` (the one ``ax`` belongs to, where given).

    Raises:
        UserError: a variable or axis the atlas does not have, or a path that cannot be
            written.
    """
    from sweep.charts import design_figure
    from sweep.selection import at_values

    ds = _atlas(atlas)
    _drawing_options(ax, cmap, figsize)
    out = _png(path, force, ds, boundaries)
    if isinstance(boundaries, (str, os.PathLike)):
        boundaries = open_boundaries(boundaries)
    with reading(ds):
        ds = with_requirements(ds, require)
        fig = design_figure(ds, x, y, color, ok_only=not all_status, degrees=degrees,
                            at=at_values(at), boundaries=boundaries, overlay=overlay,
                            ax=ax, cmap=cmap, figsize=figsize)
    if out is not None:
        save_figure(fig, out)
    return fig


def _drawing_options(ax, cmap, figsize) -> None:
    """The chart's matplotlib options checked: a UserError naming the argument."""
    import numbers

    import matplotlib
    from matplotlib.axes import Axes

    if ax is not None and not isinstance(ax, Axes):
        raise UserError(f"ax: a matplotlib Axes, not {type(ax).__name__}")
    if cmap is not None and (not isinstance(cmap, str) or cmap not in matplotlib.colormaps):
        raise UserError(f"cmap: {cmap!r} is not a matplotlib colour map's name; e.g. "
                        "'viridis', 'cividis', 'RdBu_r'")
    if figsize is not None:
        if ax is not None:
            raise UserError("figsize: the figure is ax's; give figsize or ax, not both")
        if not (isinstance(figsize, (tuple, list)) and len(figsize) == 2 and all(
                isinstance(v, numbers.Real) and not isinstance(v, bool) and 0 < v <= 100
                for v in figsize)):
            raise UserError(f"figsize: (width, height) in inches, each in (0, 100], not "
                            f"{figsize!r}")


def lines(atlas: AtlasLike, x: str, y: list[str] | str, *, by: str | None = None,
          values: list[Any] | None = None, at: Mapping[str, Any] | None = None,
          path: str | os.PathLike | None = None, degrees: bool = True, ax: Any = None,
          force: bool = False) -> Figure:
    """Outputs against one grid axis, one curve per value of another (a family of curves,
    as the papers draw them), the other grid axes held at one value.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        x: the grid axis along the curves.
        y: one output or several (a panel each; a list or names separated by commas).
        by: a grid axis giving one curve per value; values: those of its values to draw
            (the nearest grid values; default every one, at most 12).
        at: other grid axes held at one value, {axis: number or "60deg"}.
        path: a PNG to save the chart to (an existing one only with ``force``).
        degrees: angles in degrees; ax: draw into these matplotlib axes (one y).

    Returns:
        The ``matplotlib.figure.Figure``.

    Raises:
        UserError: an axis or output the atlas does not have, a grid axis left neither
            held nor drawn, too many curves, or a path that cannot be written.
    """
    from sweep import line_chart
    from sweep.selection import at_values

    ds = _atlas(atlas)
    if ax is not None:
        _drawing_options(ax, None, None)
    out = _png(path, force, ds)
    names = [v.strip() for v in y.split(",") if v.strip()] if isinstance(y, str) else list(y)
    with reading(ds):
        fig = line_chart.figure(ds, x, names, by, values, at_values(at), degrees, ax)
    if out is not None:
        save_figure(fig, out)
    return fig


def profile(atlas: AtlasLike, variables: list[str] | str, where: str | None = None, *,
            path: str | os.PathLike | None = None, degrees: bool = True,
            force: bool = False, against: str | None = None,
            each: str | None = None, every: bool = False) -> Figure:
    """Profiles (values over the crank angle, e.g. joint reactions) at one grid point.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        variables: profile variables, a list or names separated by commas.
        where: a condition picking the grid point (the first that matches).
        path: a PNG to save the figure to (an existing one only with ``force``).
        degrees: angles in degrees.
        force: overwrite an existing PNG.
        against: a profile for the x axis instead of the crank angle (e.g. the six-link's
            rocker_angle against link3_angle, [SIX] Fig. 6).
        each: a grid axis: one curve per value of it, the other axes held at the point
            ``where`` picks (e.g. ``"type"``).
        every: one curve per grid point matching ``where`` (at most 12; [CR] Fig. 2's
            three mechanisms).

    Returns:
        The ``matplotlib.figure.Figure``, one panel per unit; ``fig.grid_point`` says which
        grid point it shows.

    Raises:
        UserError: a variable that is not a profile, or no grid point matches ``where``.
    """
    from sweep.charts import profile_figure
    from sweep.selection import parse

    ds = _atlas(atlas)
    out = _png(path, force, ds)
    if where is not None:
        parse(where)
    names = [v.strip() for v in variables.split(",")] if isinstance(variables, str) \
        else list(variables)
    with reading(ds):
        fig, fig.grid_point = profile_figure(ds, [n for n in names if n], where, degrees,
                                             against=against, each=each, every=every)
    if out is not None:
        save_figure(fig, out)
    return fig


def _png(path, force: bool, *inputs, name: str = "path") -> Path | None:
    """Where a figure goes, checked before anything is drawn (store.check_target); the
    command's ``inputs`` (atlases, their files) are never written over."""
    from sweep.store import check_target

    if path is None:
        return None
    out = path_argument(path, name)
    check_target(out, force, suffix=".png", inputs=input_files(*inputs))
    return out


def input_files(*inputs) -> list[str]:
    """The files a command reads: paths as given, and the files Datasets were opened from."""
    files = []
    for item in inputs:
        if isinstance(item, (str, os.PathLike)):
            files.append(str(item))
        elif item is not None and hasattr(item, "encoding"):
            source = item.encoding.get("source")
            if source:
                files.append(source)
    return files


def save_figure(fig, out: Path) -> None:
    """A figure as a PNG, written under a temporary name and renamed (never half)."""
    from sweep.store import atomic

    with atomic(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")


def boundaries(atlas: AtlasLike, var: str = "status", tol: float = 1e-8, *,
               path: str | os.PathLike | None = None, force: bool = False,
               resume: bool = False, workers: int | None = None, chunk: int | None = None,
               progress: bool = False) -> xarray.Dataset:
    """Every boundary of a flag variable of an atlas, refined.

    Where ``var`` (``status``, ``regime``, ``requirements``) changes between neighbouring
    grid points, the crossing is bisected on its grid edge through the same kernels to
    ``tol × max(1, |x|)`` in the axis's units.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        var: the flag variable.
        tol: the tolerance of each crossing, relative to max(1, |x|).
        path: a ``.nc`` to write the crossings to (atomically); never the atlas itself.
        force: overwrite an existing file at ``path``.
        resume: continue an interrupted refinement on ``path``.
        workers: threads (default: every core).
        chunk: crossings per task.
        progress: show a progress bar.

    Returns:
        An ``xarray.Dataset``, one row per crossing: its place, the meanings on each side
        and what explains it.

    Raises:
        UserError: ``var`` is not a flag of the atlas, or ``path`` cannot be written.
    """
    from sweep.refinement import refine

    ds = _atlas(atlas)
    target = None if path is None else path_argument(path, "path")
    if target is not None:
        from sweep.store import check_target

        check_target(target, force or resume, inputs=input_files(atlas, ds))
    with reading(ds):
        return refine(ds, var, tol, target=target, workers=workers, chunk=chunk,
                      resume=resume, force=force, progress=progress)


def info(atlas: AtlasLike, require: list[str] | None = None) -> str:
    """What an atlas holds and how it was made, in words and units.

    Parameters:
        atlas: an atlas or a boundaries file (a Dataset, or the path of one).
        require: limits to count the designs that meet (``with_requirements``).

    Returns:
        The text: grid, fixed parameters and method; the range of every output; status
        counts; provenance. For a boundaries file, its crossings by sides.

    Raises:
        UserError: not an atlas or boundaries file of this tool.
    """
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


def pareto(atlas: AtlasLike, maximize: list[str] | str = (), minimize: list[str] | str = (), *,
           where: str | None = None, require: list[str] | None = None, pick: str = "knee",
           weights: list[float] | None = None, path: str | os.PathLike | None = None,
           chart: str | os.PathLike | None = None, degrees: bool = True,
           force: bool = False, tie_tol: float = 1e-9,
           sheet: str | os.PathLike | None = None) -> Front:
    """The Pareto front of an atlas's feasible designs, and the one a rule picks.

    A design is a candidate when its status is ``ok``, it meets the requirements and
    ``where``, and it has a value of every objective; the front is the candidates no other
    dominates. Pick rules: ``knee`` (nearest the ideal point, each objective scaled over
    the front), ``lexicographic`` (the objectives in the order given, maxima first) or
    ``weighted`` (``weights``, one per objective, on the scaled objectives).

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        maximize: outputs to maximise (a name or a list).
        minimize: outputs to minimise (a name or a list).
        where: a condition the candidates must meet.
        require: limits replacing the atlas's own (``with_requirements``).
        pick: the rule that picks one design.
        weights: with ``pick="weighted"``, one weight per objective.
        path: a ``.nc`` to write the front to (a chained sweep's source).
        chart: a PNG of the front over the feasible designs.
        degrees: angles in degrees on the chart.
        force: overwrite existing files (never the atlas itself).
        tie_tol: objective values that agree to this relative tolerance are ties.
        sheet: a design sheet (``.html``, and a PDF beside it where Chromium is installed)
            of the picked design, its place drawn on this front (``sheet``).

    Returns:
        A ``Front``: ``front.designs`` (an xarray Dataset over ``design``, ``picked``
        marking the pick) and ``front.picked_design``.

    Raises:
        UserError: no objective, an objective the atlas does not have, no feasible design,
            or a file that cannot be written.

    Example:
        >>> import sweep
        >>> atlas = sweep.run({"mechanism": "crank_rocker",
        ...                    "grid": {"R": [0.1, 0.2, 0.3], "largest_link": [2.0, 3.0]},
        ...                    "fixed": {"rocker_inertia": 0.05},
        ...                    "outputs": ["impact_speed", "blow_energy", "envelope"]})
        >>> front = sweep.pareto(atlas, maximize="blow_energy", minimize="envelope")
        >>> int(front.designs.sizes["design"]) >= 1
        True
    """
    from sweep import fronts
    from sweep.selection import parse
    from sweep.store import check_target

    if where is not None:
        parse(where)
    ds = _atlas(atlas)
    target = None if path is None else path_argument(path, "path")
    if target is not None:
        check_target(target, force, inputs=input_files(atlas, ds))
    picture = _png(chart, force, atlas, ds, name="chart")
    sheet_targets = None if sheet is None else _sheet_targets(sheet, True, force, atlas, ds)
    source = ds.encoding.get("source", "")
    with reading(ds):
        ds = with_requirements(ds, require)
        result = fronts.front(ds, maximize, minimize, where=where, pick=pick,
                              weights=weights, source=str(source), tie_tol=tie_tol)
        result.designs.load()
        fig = None if picture is None and sheet is None else \
            fronts.figure(ds, result, where, degrees)
    if target is not None:
        write_selection(result.designs, target)
    if picture is not None:
        save_figure(fig, picture)
    if sheet_targets is not None:
        from sweep import design_sheet as sheets

        text = sheets.page(result.designs, {"design": int(result.picked)},
                           front_png=sheets.figure_png(fig), source=str(source))
        result.sheet = _write_sheet(text, *sheet_targets)
    return result


def explore(atlas: AtlasLike, path: str | os.PathLike, *,
            variables: list[str] | str | None = None, max_designs: int | None = None,
            force: bool = False) -> Path:
    """An atlas as one self-contained HTML page to explore offline (every script inlined).

    A chart of any two variables coloured by any variable, the other grid axes held at
    values set by menus ("all": every value); a scatter matrix where brushing a box, a
    lasso or the ranges selects designs in every view; hover on a design for its
    parameters and outputs with units; a table of the selected designs with a CSV
    download; a front's picked design marked. Every design is shown up to ``max_designs``;
    beyond, every k-th in grid order, which the page says.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        path: the ``.html`` to write (an existing one only with ``force``; never the atlas).
        variables: 2 to 4 numeric variables of the scatter matrix (a list or names
            separated by commas); default: a front's objectives, the chart's colour and
            overlay, then the outputs.
        max_designs: designs shown at most (default ``sweep.explorer.MAX_DESIGNS``).
        force: overwrite an existing page.

    Returns:
        The page's path.

    Raises:
        UserError: not an atlas, a variable it does not have, or a path that cannot be
            written.
    """
    from sweep import explorer
    from sweep.store import atomic, check_target

    ds = _atlas(atlas)
    target = path_argument(path, "path")
    check_target(target, force, suffix=".html", inputs=input_files(atlas, ds))
    names = [v.strip() for v in variables.split(",") if v.strip()] \
        if isinstance(variables, str) else variables
    if max_designs is None:
        max_designs = explorer.MAX_DESIGNS
    if isinstance(max_designs, bool) or not isinstance(max_designs, int) or max_designs < 1:
        raise UserError(f"max_designs: a positive whole number, not {max_designs!r}")
    with reading(ds):
        text = explorer.page(ds, names, max_designs)
    with atomic(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return target


def sheet(atlas: AtlasLike, path: str | os.PathLike, *, design: int | None = None,
          where: str | None = None, pdf: bool = True, force: bool = False
          ) -> tuple[Path, Path | None]:
    """One page for one design: its parameters and every output with unit and meaning,
    the requirement margins, its place on the front (an atlas written by ``pareto``), its
    profiles over the cycle where the atlas has them, and the provenance (spec, code and
    package versions, date).

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        path: the ``.html`` to write (an existing one only with ``force``).
        design: the design's grid point, its flat (C-order) index (as ``query`` lists it);
            or
        where: a condition; the first grid point that matches.
        pdf: also print it to a PDF beside it (``PATH.pdf``) where the distribution's
            Chromium is installed.
        force: overwrite existing files (never the atlas).

    Returns:
        (the page, the PDF or None where no Chromium is installed).

    Raises:
        UserError: not an atlas, neither or both of design and where, a design out of
            range, no match, or a path that cannot be written.
    """
    from sweep import design_sheet as sheets

    ds = _atlas(atlas)
    target, printed = _sheet_targets(path, pdf, force, atlas, ds)
    with reading(ds):
        at = sheets.point_of(ds, design, where)
        text = sheets.page(ds, at, source=str(ds.encoding.get("source", "")))
    return _write_sheet(text, target, printed)


def _sheet_targets(path, pdf: bool, force: bool, *inputs) -> tuple[Path, Path | None]:
    from sweep.store import check_target

    target = path_argument(path, "sheet")
    check_target(target, force, suffix=".html", inputs=input_files(*inputs))
    printed = target.with_suffix(".pdf") if pdf else None
    if printed is not None:
        check_target(printed, force, suffix=".pdf", inputs=input_files(*inputs))
    return target, printed


def _write_sheet(text: str, target: Path, printed: Path | None) -> tuple[Path, Path | None]:
    from sweep import design_sheet as sheets
    from sweep.store import atomic

    with atomic(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
    if printed is not None and not sheets.print_pdf(target, printed):
        printed = None
    return target, printed


def sensitivity(spec: Sweep | Mapping | str | os.PathLike,
                inputs: Mapping[str, Any] | None = None, outputs: list[str] | None = None,
                *, samples: int = 1024, seed: int = 0, path: str | os.PathLike | None = None,
                chart: str | os.PathLike | None = None, force: bool = False,
                workers: int | None = None) -> xarray.Dataset:
    """Variance-based sensitivity of outputs to inputs, with failed and infeasible designs
    counted (``sweep.sensitivity_study``: the method in full).

    Parameters:
        spec: the study's base (a Sweep, a dict or a TOML file): its mechanism, fixed
            parameters, method, outputs and requirements; without ``inputs``, its grid axes
            are the inputs, each uniform between its least and greatest value.
        inputs: {parameter: (low, high)} (uniform) or {parameter: (distribution,
            numbers...)} with SALib's distributions: ``("norm", mean, sd)``,
            ``("triang", low, high, mode)``, ``("lognorm", mu, sigma)``,
            ``("truncnorm", low, high, mean, sd)``; values in the atlas's units (SI,
            radians).
        outputs: the outputs to apportion (default: the spec's numeric outputs).
        samples: base samples, a power of two; the kernel runs samples x (inputs + 2).
        seed: the scrambling's and the bootstrap's seed (the same seed, the same result).
        path: a ``.nc`` to write the result to; chart: a PNG of the indices.
        force: overwrite existing files.
        workers: threads (default: every core).

    Returns:
        An ``xarray.Dataset`` over (quantity, input): ``first_order``, ``total`` and their
        confidence half-widths for every output (where it exists) and for the indicator
        of every status met and of meeting the requirements; ``probability`` of each of
        those events with its Wilson interval.

    Raises:
        UserError: an input that is not a parameter, a band outside its domain, a
            categorical input, a sample too large, or a path that cannot be written.
    """
    from sweep import sensitivity_study as sens

    document = _document(spec, "spec", "a Sweep, a dict or the path of a TOML file")
    target, picture = _study_targets(path, chart, force, spec)
    result = sens.study(document, None if inputs is None else dict(inputs), outputs,
                        samples, seed, workers)
    return _written_study(result, target, picture, sens.figure)


def _document(spec, name: str, what: str) -> dict:
    """A spec document (the dict as given) from a Sweep, a dict or a TOML file."""
    from sweep.spec import Sweep, load

    if isinstance(spec, Sweep):
        return dict(spec.source)
    if isinstance(spec, Mapping):
        return dict(spec)
    if isinstance(spec, (str, os.PathLike)):
        return dict(load(spec).source)
    raise UserError(f"{name}: {what}, not {type(spec).__name__}")


def _study_targets(path, chart, force: bool, spec) -> tuple[Path | None, Path | None]:
    """Where a study's result (.nc) and chart (.png) go, checked before any compute."""
    from sweep.store import check_target

    target = None if path is None else path_argument(path, "path")
    if target is not None:
        check_target(target, force, inputs=input_files(spec))
    return target, _png(chart, force, spec, name="chart")


def _written_study(result, target, picture, figure):
    """A study's result written (atomically) and charted where asked."""
    from sweep.store import atomic

    if target is not None:
        with atomic(target) as tmp:
            result.to_netcdf(tmp, engine="netcdf4")
    if picture is not None:
        save_figure(figure(result), picture)
    return result


def design_spec(atlas: AtlasLike, *, design: int | None = None,
                where: str | None = None) -> dict:
    """The spec (a dict, as ``Sweep.from_dict`` takes it) of one design of an atlas, as
    built: its recorded fixed values, its grid axes' and a chain's values at the design,
    an inverted input replaced by the value it gave (``envelope`` by ``crank_length``),
    a synthesised crank-rocker by the four-bar it gave (type ``general``). Running it
    gives the atlas's values at that design.

    Parameters:
        atlas: an atlas (a Dataset of this tool, or the path of one).
        design: the design's grid point, its flat (C-order) index; or
        where: a condition; the first grid point that matches.

    Returns:
        The spec document of one design (a one-point grid).

    Raises:
        UserError: not an atlas, neither or both of design and where, a design out of
            range, or no match.
    """
    from sweep import design_sheet, tolerance_study

    ds = _atlas(atlas)
    with reading(ds):
        return tolerance_study.design_spec(ds, design_sheet.point_of(ds, design, where))


def tolerance(design: Sweep | Mapping | str | os.PathLike, tolerances: Mapping[str, Any], *,
              method: Mapping[str, Any] | None = None,
              samples: int = 4096, seed: int = 0, path: str | os.PathLike | None = None,
              chart: str | os.PathLike | None = None, force: bool = False,
              workers: int | None = None) -> xarray.Dataset:
    """One design under workshop tolerances and a material band: the distribution of its
    outputs and statuses (``sweep.tolerance_study``: the method in full).

    Parameters:
        design: the design's spec, one point (a dict, a TOML file or a Sweep;
            ``design_spec`` makes one from an atlas).
        tolerances: {parameter: +-value in its units (``1e-4``: a length +-0.1 mm),
            ``"5%"`` (relative) or ``(low, high)`` (a band, e.g. the material's R)}.
        method: method options replacing the design's, e.g. ``{"geometry_tol": 1e-3}``:
            linkages within that relative band of a change point are modelled as exact
            change points (a special position's condition is exact; a workshop's is not).
        samples: a power of two; seed: the scrambling's seed.
        path: a ``.nc`` for the result; chart: a PNG of the spreads.
        force: overwrite existing files; workers: threads (default: every core).

    Returns:
        An ``xarray.Dataset``: ``quantiles`` of every output where it exists, its
        ``nominal`` value, ``samples_with_value``, and the ``probability`` of each status
        and of meeting the requirements with Wilson intervals.

    Raises:
        UserError: a tolerance on a parameter the mechanism does not take or that is
            categorical, a band outside the parameter's domain, a design of more than one
            point, a sample too large, or a path that cannot be written.
    """
    from sweep import tolerance_study

    document = _document(design, "design", "a spec of one design (dict, TOML file or Sweep)")
    if method:
        if not isinstance(method, Mapping):
            raise UserError("method: a dict of method options, e.g. {'geometry_tol': 1e-3}")
        document["method"] = {**(document.get("method") or {}), **dict(method)}
    target, picture = _study_targets(path, chart, force, design)
    result = tolerance_study.study(document, dict(tolerances) if isinstance(
        tolerances, Mapping) else tolerances, samples, seed, workers)
    return _written_study(result, target, picture, tolerance_study.figure)


def robust(atlas: AtlasLike | Sweep | Mapping, over: str | Mapping[str, Any], *,
           refine: list[str] | str | None = None, path: str | os.PathLike | None = None,
           force: bool = False) -> xarray.Dataset:
    """An atlas reduced over a band of one of its grid axes: each design's least and
    greatest value of every output over the band and its spread, and whether it is usable
    and meets its requirements at every point (``sweep.robust_study``: the method).

    Over the material's R of an ``impact_machine`` atlas (its linkage is designed for
    ``design_restitution`` and strikes whatever the site gives), a design that is
    robustly feasible meets its limits for every rock in the band.

    Parameters:
        atlas: an atlas (a Dataset or its path), or a spec (dict or Sweep), run first.
        over: a grid axis (its whole range) or {axis: (low, high)} inside its range.
        refine: outputs whose extremes are refined between the samples on the kernel
            (default: those the requirements name; [] for none).
        path: a ``.nc`` to write the reduced atlas to; force: overwrite it.

    Returns:
        An atlas over the other grid axes (``NAME_min``, ``NAME_max``, ``NAME_spread``,
        ``status``, ``requirements``) that ``pareto``, ``chart`` and ``explore`` read.

    Raises:
        UserError: an axis the atlas does not have or that is not numeric, a band outside
            the atlas's range, an output to refine it does not have, or a path that
            cannot be written.
    """
    import xarray as xr

    from sweep import robust_study
    from sweep.spec import Sweep

    if isinstance(atlas, (Sweep, Mapping)) and not isinstance(atlas, xr.Dataset):
        atlas = run(atlas)
    ds = _atlas(atlas)
    target = None if path is None else path_argument(path, "path")
    if target is not None:
        from sweep.store import check_target

        check_target(target, force, inputs=input_files(atlas, ds))
    with reading(ds):
        result = robust_study.reduce(ds.load(), over, refine)
    if target is not None:
        write_selection(result, target)
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
    """The mechanisms, or one mechanism's parameters, method keys, outputs and statuses.

    Parameters:
        mechanism: a mechanism's name; ``None`` lists the mechanisms.

    Returns:
        The text ``sweep parameters`` prints: units, defaults and allowed values.

    Raises:
        UserError: an unknown mechanism (the message lists them).
    """
    from sweep import registry

    if mechanism is None:
        return "\n".join(f"{name:17s} {registry.get(name).declaration.title}"
                         for name in registry.names())
    if mechanism not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {mechanism!r}; allowed: "
                        + ", ".join(registry.names()))
    from sweep.describe import mechanism_text

    return mechanism_text(registry.get(mechanism).declaration)
