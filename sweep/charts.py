"""Design charts from an atlas: matplotlib PNG with units on the axes and colour bar.

A numeric output is a colour map with contour lines and the output's marked levels (K = 1);
a flag output (``regime``, ``status``) and a count that takes few values (``attractor_count``)
are drawn as categories with their meanings in a legend.
Cells without a design value are not left white: they are drawn in greys, one per status,
named in the legend. Angles are drawn in degrees unless asked otherwise (a rotor angle of
many turns, in turns); the atlas stays in radians. Figures are built without pyplot, so
that a notebook's backend and a thread's charts do not interfere.
"""

from __future__ import annotations

import datetime as _dt
import textwrap
from pathlib import Path
from typing import NamedTuple

import numpy as np
import xarray as xr

from sweep.errors import UserError
from sweep.selection import evaluate, flag_names, take_at

#: panels per row of a chart with one panel per value of another axis
PANELS_PER_ROW = 3
#: the categories' colours (a qualitative map), and the greys of cells without a value
CATEGORY_COLOURS = ("#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#b07aa1", "#edc948",
                    "#76b7b2", "#ff9da7", "#9c755f", "#bab0ac")
UNDETERMINED_COLOUR = "#7f7f7f"  # a flag's negative code: no category was decided
#: crossings this close (relative) on one edge are drawn as one
THIN_BAND = 1e-6
BLANK_GREYS = ("0.86", "0.72", "0.58", "0.93", "0.65", "0.79")
#: a count with at most this many distinct values is drawn as categories
MAX_COUNT_CATEGORIES = 12


class Drawn(NamedTuple):
    """What a design chart shows, read back from the figure (for the CLI and the tests)."""

    path: Path
    legend: list[str]
    panel_titles: list[str]
    rows: int
    columns: int
    xlabel: str
    ylabel: str
    xscale: str
    yscale: str
    xticks: list[str]
    yticks: list[str]
    colour_bar: bool
    legend_colours: list[str]


def category_colour(code: int, codes) -> str:
    """A category's colour, the same in every atlas of a mechanism whatever else it holds:
    by the meaning's place among the flag's codes >= 0; a negative code (undetermined)
    grey. Ranked among the codes present, period_1 was orange in one blade chart and blue
    in the next."""
    if code < 0:
        return UNDETERMINED_COLOUR
    decided = sorted(c for c in codes if c >= 0)
    return CATEGORY_COLOURS[decided.index(code) % len(CATEGORY_COLOURS)]


def _declared(ds: xr.Dataset, name: str):
    """The declaration of an atlas variable's output, or None (a coordinate, status, or an
    atlas of an unknown mechanism)."""
    from sweep import registry

    mech = ds.attrs.get("mechanism", "")
    if mech not in registry.names():
        return None
    try:
        return registry.get(mech).declaration.output(name)
    except KeyError:
        return None


def _undetermined_code(var: xr.DataArray):
    """The code of a flag variable's ``undetermined`` meaning (no value), or None."""
    meanings = var.attrs.get("flag_meanings", "").split()
    if "undetermined" not in meanings:
        return None
    return int(np.atleast_1d(var.attrs["flag_values"])[meanings.index("undetermined")])


def _chart_units(ds: xr.Dataset, name: str) -> tuple[str, float] | None:
    """(units, factor) a chart shows a variable in instead of its own, if declared."""
    output = _declared(ds, name)
    return output.chart_units if output is not None else None


def _units(ds: xr.Dataset, name: str, degrees: bool) -> str:
    units = ds[name].attrs.get("units", "")
    other = _chart_units(ds, name)
    if other is not None:
        return other[0]
    if degrees and units == "rad":
        return "deg"
    return "-" if units in ("1", "") else units


def _label(ds: xr.Dataset, name: str, degrees: bool = False, width: int = 48) -> str:
    """An axis label: the name, its units and its long name wrapped at ``width``
    characters (narrower along a vertical axis, which is shorter than the text)."""
    long_name = textwrap.fill(ds[name].attrs.get("long_name", name), width)
    return f"{name} [{_units(ds, name, degrees)}]\n{long_name}"


#: the wrap of a label along a vertical axis: a 4-inch axis holds about 36 characters
VERTICAL_LABEL_WIDTH = 32


def _shown(var: xr.DataArray, degrees: bool, ds: xr.Dataset | None = None) -> np.ndarray:
    """A variable's values as drawn: in its declared chart units (a rotor angle in turns),
    radians in degrees when asked."""
    values = np.asarray(var.values)
    other = _chart_units(ds, str(var.name)) if ds is not None else None
    if other is not None:
        return values * other[1]
    if degrees and var.attrs.get("units") == "rad":
        return np.degrees(values)
    return values


def _is_count(ds: xr.Dataset, name: str) -> bool:
    """A declared count whose finite values are few enough to read as categories."""
    output = _declared(ds, name)
    if output is None or not output.count:
        return False
    values = np.asarray(ds[name].values, dtype=float)
    distinct = np.unique(values[np.isfinite(values)])
    return 0 < distinct.size <= MAX_COUNT_CATEGORIES and bool(
        np.all(distinct == np.round(distinct)))


def made_by() -> str:
    """The caption's last line: the code that drew a chart, and when (not the host)."""
    from sweep.metadata import code_version

    today = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d")
    return f"impact-sweep {code_version()}, {today}"


def _log_spaced(values: np.ndarray) -> bool:
    return (values.size > 2 and values.dtype.kind == "f" and bool(np.all(values > 0))
            and values[-1] / values[0] > 5
            and bool(np.allclose(np.diff(np.log(values)), np.log(values[1] / values[0]))))


def _plain_log_axis(axis) -> None:
    """Log-axis ticks written as numbers (30, not 3x10^1)."""
    import matplotlib.ticker as ticker

    axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(ticker.FuncFormatter(
        lambda v, _: f"{v:g}" if round(v / 10 ** np.floor(np.log10(v))) in (2, 5) else ""))


def _number(value: float) -> str:
    """A contour label as a plain number: 10000, not 1e+04."""
    text = f"{value:.3g}"
    return f"{value:,.0f}" if "e+" in text else text


def _marks(ds: xr.Dataset, name: str) -> tuple:
    """The declared (value, meaning) levels of an output (from the mechanism's declaration)."""
    output = _declared(ds, name)
    return output.marks if output is not None else ()


def _panel_title(ds: xr.Dataset, dim: str, k: int, degrees: bool) -> str:
    value = ds[dim].values[k]
    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, str):
        return f"{dim} = {value}"
    units = _units(ds, dim, degrees)
    shown = np.degrees(value) if units == "deg" else value
    return f"{dim} = {shown:.6g}" + ("" if units == "-" else f" {units}")


def design_chart(ds: xr.Dataset, x: str, y: str, color: str, out: Path,
                 ok_only: bool = True, degrees: bool = True, at: dict | None = None,
                 boundaries: xr.Dataset | None = None, overlay: str | None = None) -> Drawn:
    """``design_figure`` saved as a PNG at ``out``; what it shows, read back (``Drawn``)."""
    fig = design_figure(ds, x, y, color, ok_only=ok_only, degrees=degrees, at=at,
                        boundaries=boundaries, overlay=overlay)
    fig.savefig(out, dpi=110)
    return drawn(fig, out)


def design_figure(ds: xr.Dataset, x: str, y: str, color: str, ok_only: bool = True,
                  degrees: bool = True, at: dict | None = None,
                  boundaries: xr.Dataset | None = None, overlay: str | None = None):
    """Chart of ``color`` over (x, y), one panel per value of the other grid axis of more than
    one value (at most three panels a row), as a matplotlib Figure. ``ok_only``: cells whose
    status has no design values are drawn as their status, not as a value; ``degrees``:
    angles in degrees; ``at``: take other grid axes at one value ({axis: (value, "" or
    "deg")}); ``boundaries``: the refined crossings of ``sweep boundaries``, drawn as lines;
    ``overlay``: a numeric output drawn as labelled contour lines over the colours (the
    stability margin over a regime map), where it has a design value."""
    import matplotlib
    import matplotlib.colors as mcolors
    import matplotlib.ticker as ticker
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from sweep.metadata import usable_mask

    for axis, name in (("x", x), ("y", y), ("color", color)):
        if name in ("requirements", "requirement_margin") and name not in ds.variables:
            raise UserError(f"{axis}: this atlas has no requirements; give them with "
                            "--require 'NAME <= NUMBER' (or a spec's [requirements])")
        if name not in ds.variables:
            raise UserError(f"{axis}: unknown variable {name!r}; allowed: "
                            + ", ".join(sorted(map(str, ds.variables))))
    grid_dims = list(ds["status"].dims)
    if x == y:
        raise UserError(f"y: {y!r} is also the x axis; pick two different variables")
    for axis, name in (("x", x), ("y", y)):
        if name in (at or {}):
            raise UserError(f"at: {name!r} is the chart's {axis} axis; take another axis at "
                            "one value")
        if name not in grid_dims or ds[name].dtype.kind not in "fiu":
            raise UserError(f"{axis}: {name!r} is not a numeric grid axis; a design chart is "
                            "drawn over two of them (" + ", ".join(
                                d for d in grid_dims if ds[d].dtype.kind in "fiu") + ")")
    if any(d not in grid_dims for d in ds[color].dims):
        raise UserError(f"color: {color!r} is a profile; chart it with `sweep profile`, or "
                        "`sweep query --at` for its value at one angle")
    if ds[color].dtype.kind in "OUS":
        raise UserError(f"color: {color!r} is categorical; pick a numeric or flag variable")
    if overlay is not None:
        if overlay not in ds.data_vars or "flag_meanings" in ds[overlay].attrs or any(
                d not in grid_dims for d in ds[overlay].dims):
            numeric = [n for n, v in ds.data_vars.items() if "flag_meanings" not in v.attrs
                       and set(v.dims) <= set(grid_dims) and n != "status"]
            raise UserError(f"overlay: {overlay!r} is not a numeric output of this atlas; "
                            "allowed: " + ", ".join(numeric))
    if boundaries is not None:
        check_boundaries(ds, boundaries)
    grid_shape = ds["status"].shape
    ds, chosen = take_at(ds, at, grid=True)
    facet_dims = [d for d in grid_dims if d not in (x, y) and ds.sizes[d] > 1]
    if len(facet_dims) > 1:
        raise UserError(f"chart: more than one other axis to panel over ({', '.join(facet_dims)});"
                        " take one at a value with --at AXIS=VALUE")
    panels = [None] if not facet_dims else list(range(ds.sizes[facet_dims[0]]))
    n_cols = min(len(panels), PANELS_PER_ROW)
    n_rows = -(-len(panels) // n_cols)
    fig = Figure(figsize=(4.6 * n_cols + 1.8, 4.2 * n_rows + 0.9), layout="constrained")
    axes = fig.subplots(n_rows, n_cols, squeeze=False)
    var = ds[color]
    status = ds["status"]
    status_names = flag_names(status)
    is_flag = "flag_meanings" in var.attrs
    is_count = not is_flag and _is_count(ds, color)
    declared = _declared(ds, color)
    # status, and an output that exists at every status (a regime, a threshold), is drawn
    # wherever it has a value; a design value only where the status is usable
    everywhere = color == "status" or (declared is not None and declared.at_every_status)
    usable = (usable_mask(ds).values if ok_only and not everywhere
              else np.ones(var.shape, bool))
    if is_flag or is_count:
        if is_flag:
            names = flag_names(var)
            has_value = usable & (np.asarray(var.values) != _undetermined_code(var))
            present = sorted(int(c) for c in np.unique(np.asarray(var.values)[has_value])
                             if int(c) in names)
            colour_of = {c: category_colour(c, names) for c in present}
        else:  # a count: each value its own category, in the order of the values
            values = np.asarray(var.values, dtype=float)
            has_value = usable & np.isfinite(values)
            present = sorted(int(v) for v in np.unique(values[has_value]))
            names = {c: f"{c:d}" for c in present}
            colour_of = {c: CATEGORY_COLOURS[i % len(CATEGORY_COLOURS)]
                         for i, c in enumerate(present)}
        index = {code: i for i, code in enumerate(present)}
        cmap = mcolors.ListedColormap([colour_of[c] for c in present] or ["1.0"])
        norm = mcolors.BoundaryNorm(np.arange(max(len(present), 1) + 1) - 0.5,
                                    max(len(present), 1))
        codes = np.where(has_value, np.asarray(var.values, dtype=float), np.nan)
        shown = np.full(codes.shape, np.nan)
        for code, i in index.items():
            shown[codes == code] = i
    else:
        shown = _shown(var, degrees, ds).astype(float)
        has_value = usable & np.isfinite(shown)
        shown = np.where(has_value, shown, np.nan)
        finite = shown[has_value]
        vmin, vmax = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
        # values spanning decades (transfer ratios, speeds) read better on a log colour scale
        log_colour = finite.size and vmin > 0 and vmax / vmin > 20
        norm = (mcolors.LogNorm(vmin=vmin, vmax=vmax) if log_colour
                else mcolors.Normalize(vmin=vmin, vmax=vmax))
        cmap = matplotlib.colormaps["viridis"]
        locator = (ticker.LogLocator(subs=(1.0, 2.0, 5.0)) if log_colour
                   else ticker.MaxNLocator(6))
        levels = locator.tick_values(vmin, vmax)
        levels = levels[(levels > vmin) & (levels < vmax)]
        marks = _marks(ds, color)
        levels = levels[~np.isin(levels, [value for value, _ in marks])]  # drawn as marks
        labelled = (levels[np.isclose(np.log10(levels), np.round(np.log10(levels)))]
                    if log_colour else levels[::2])
    categorical = is_flag or is_count
    shown = xr.DataArray(shown, dims=var.dims)
    # cells without a value, drawn as their status (greys), each named in the legend
    blank_codes = np.where(has_value, -1, status.transpose(*var.dims).values
                           if set(var.dims) == set(status.dims) else -1)
    blank_present = [int(c) for c in np.unique(blank_codes) if c >= 0]
    grey_of = {c: BLANK_GREYS[i % len(BLANK_GREYS)] for i, c in enumerate(blank_present)}
    blank_index = xr.DataArray(np.vectorize(lambda c: blank_present.index(int(c))
                                            if c >= 0 else np.nan, otypes=[float])(blank_codes)
                               if blank_present else np.full(var.shape, np.nan), dims=var.dims)
    grey_map = mcolors.ListedColormap([grey_of[c] for c in blank_present] or ["1.0"])
    grey_norm = mcolors.BoundaryNorm(np.arange(max(len(blank_present), 1) + 1) - 0.5,
                                     max(len(blank_present), 1))
    if categorical:
        marks = ()
    x_values, y_values = _shown(ds[x], degrees, ds), _shown(ds[y], degrees, ds)
    if overlay is not None:
        lay = _shown(ds[overlay], degrees, ds).astype(float)
        lay = xr.DataArray(np.where(usable_mask(ds).values if ok_only else True, lay, np.nan),
                           dims=ds[overlay].dims)
        finite = lay.values[np.isfinite(lay.values)]
        overlay_levels = (ticker.MaxNLocator(5).tick_values(finite.min(), finite.max())
                          if finite.size else [])
    mesh = None
    for ax, k in zip(axes.ravel(), panels):
        pick = {} if k is None else {facet_dims[0]: k}
        val = shown.isel(pick) if pick else shown
        blank = blank_index.isel(pick) if pick else blank_index
        others = [d for d in val.dims if d not in (x, y)]
        val, blank = val.squeeze(others, drop=True), blank.squeeze(others, drop=True)
        grid = val.transpose(y, x).values
        ax.pcolormesh(x_values, y_values, blank.transpose(y, x).values, cmap=grey_map,
                      norm=grey_norm, shading="nearest")
        mesh = ax.pcolormesh(x_values, y_values, grid, norm=norm, cmap=cmap,
                             shading="nearest")
        if boundaries is not None:
            panel = {d: ds[d].values[pick.get(d, 0)] for d in grid_dims
                     if d not in (x, y) and (d in pick or ds.sizes[d] == 1)}
            segments = boundary_segments(boundaries, grid_dims, grid_shape, x, y, panel)
            fx, fy = (float(_shown(xr.DataArray(1.0, name=n, attrs=ds[n].attrs),
                                   degrees, ds)) for n in (x, y))
            segments = [[(a * fx, b * fy) for a, b in seg] for seg in segments]
            ax.add_collection(LineCollection(segments, colors="black", linewidths=1.3))
        if overlay is not None:
            lay_panel = lay.isel(pick) if pick else lay
            lay_panel = lay_panel.squeeze([d for d in lay_panel.dims if d not in (x, y)],
                                          drop=True).transpose(y, x).values
            lay_panel = _without_jumps(lay_panel)
            if np.isfinite(lay_panel).sum() > 4 and len(overlay_levels):
                lines = ax.contour(x_values, y_values, lay_panel, levels=overlay_levels,
                                   colors="black", linewidths=0.9, linestyles="-")
                ax.clabel(lines, fontsize=7, fmt=_number, inline_spacing=2)
        if not categorical and np.isfinite(grid).sum() > 4:
            if len(levels):
                lines = ax.contour(x_values, y_values, grid, levels=levels, norm=norm,
                                   colors="white", linewidths=0.6)
                # decades (log) or every other level labelled: labels do not pile up
                ax.clabel(lines, labelled, fontsize=7, fmt=_number, inline_spacing=2)
            for value, meaning in marks:
                if np.nanmin(grid) < value < np.nanmax(grid):
                    mark = ax.contour(x_values, y_values, grid, levels=[value],
                                      colors="#d62728", linewidths=1.6, linestyles="--")
                    ax.clabel(mark, fmt={value: meaning.split(":")[0]}, fontsize=8)
        ax.set_xlabel(_label(ds, x, degrees))
        ax.set_ylabel(_label(ds, y, degrees, VERTICAL_LABEL_WIDTH))
        if k is not None:
            ax.set_title(_panel_title(ds, facet_dims[0], k, degrees), fontsize=9)
        for name, values, axis, scale in ((x, x_values, ax.xaxis, ax.set_xscale),
                                          (y, y_values, ax.yaxis, ax.set_yscale)):
            if name in ds.dims and _log_spaced(np.asarray(values)):
                scale("log")
                _plain_log_axis(axis)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    handles = []
    if overlay is not None:
        handles.append(Line2D([], [], color="black", lw=0.9,
                              label=f"{_label(ds, overlay, degrees)} (contour lines)"))
    if boundaries is not None:
        handles.append(Line2D([], [], color="black", lw=1.3, label=(
            f"boundaries of {boundaries.attrs.get('variable')}, refined to "
            f"{float(boundaries.attrs.get('tolerance', np.nan)):g}")))
    if categorical:
        handles += [Patch(color=colour_of[c], label=names[c]) for c in present]
    else:
        bar = fig.colorbar(mesh, ax=axes.ravel().tolist(), shrink=0.9)
        bar.set_label(_label(ds, color, degrees, VERTICAL_LABEL_WIDTH))
        if isinstance(norm, mcolors.LogNorm):
            _plain_log_axis(bar.ax.yaxis)
        for value, meaning in marks:
            if norm.vmin < value < norm.vmax:
                bar.ax.axhline(value, color="#d62728", lw=1.6, ls="--")
                handles.append(Line2D([], [], color="#d62728", lw=1.6, ls="--",
                                      label=meaning))
    counts = {c: int((blank_codes == c).sum()) for c in blank_present}
    handles += [Patch(color=grey_of[c], label=f"no {color} value: {status_names.get(c, c)} "
                                             f"({counts[c]:,} points)")
                for c in blank_present]
    if handles:
        # as many columns as the figure's width holds of the longest label (8 pt text)
        longest = max(len(h.get_label()) for h in handles)
        fits = int(fig.get_figwidth() / (0.075 * longest + 0.6))
        fig.legend(handles=handles, loc="outside lower center", fontsize=8,
                   ncols=max(1, min(len(handles), 3, fits)),
                   title=(f"{color}: {var.attrs.get('long_name')}"
                                                      if categorical else None),
                   title_fontsize=8)
    caption = ds.attrs.get("title", "")
    if chosen:
        caption += f"\nat {chosen}"
    caption += f"\n{made_by()}"
    fig.suptitle(caption, fontsize=8)
    fig.layout_shape = (n_rows, n_cols)  # read back by ``drawn``
    fig.colour_bar = not categorical
    return fig


def drawn(fig, out: Path) -> Drawn:
    """What a design figure shows, read back from it (for the CLI and the tests)."""
    import matplotlib.colors as mcolors
    from matplotlib.patches import Patch

    fig.draw_without_rendering()
    used = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    handles = fig.legends[0].legend_handles if fig.legends else []
    n_rows, n_cols = fig.layout_shape
    labels = [t.get_text() for t in fig.legends[0].get_texts()] if fig.legends else []
    return Drawn(out, labels, [ax.get_title() for ax in used],
                 n_rows, n_cols, used[0].get_xlabel(), used[0].get_ylabel(),
                 used[0].get_xscale(), used[0].get_yscale(),
                 [t.get_text() for t in used[0].get_xticklabels() if t.get_text()],
                 [t.get_text() for t in used[0].get_yticklabels() if t.get_text()],
                 fig.colour_bar,
                 [mcolors.to_hex(h.get_facecolor() if isinstance(h, Patch) else h.get_color())
                  for h in handles])


def check_boundaries(ds: xr.Dataset, bounds: xr.Dataset) -> None:
    """A boundaries file drawn on an atlas must come from the same sweep (grid, fixed
    parameters and method; run settings and chart may differ)."""
    import json

    def sweep_of(spec_text):
        spec = json.loads(spec_text)
        return {k: v for k, v in spec.items() if k not in ("run", "chart", "title", "outputs")}

    if "grid_point" not in bounds or "spec" not in bounds.attrs:
        raise UserError("boundaries: not a file written by `sweep boundaries`")
    if sweep_of(bounds.attrs["spec"]) != sweep_of(ds.attrs.get("spec", "{}")):
        raise UserError("boundaries: refined from another sweep (its grid, fixed parameters "
                        "or method differ from this atlas's)")


def boundary_segments(bounds: xr.Dataset, grid_dims: list[str], shape: tuple, x: str, y: str,
                      panel: dict) -> list:
    """Line segments through the refined crossings of one panel, cell by cell (marching
    squares with each edge's crossing bisected instead of interpolated): in each grid cell,
    two crossings between the same pair of meanings are joined; four are joined in pairs
    around the cell."""
    if x not in grid_dims or y not in grid_dims:
        return []
    axis = bounds["edge_axis"].values.astype(str)
    keep = np.isin(axis, [x, y])
    for dim, value in panel.items():
        values = bounds[dim].values
        keep &= (values.astype(str) == str(value)) if values.dtype.kind in "OUS" \
            else (values == value)
    edge = bounds["grid_point"].values
    index = np.unravel_index(edge, shape)
    ix, iy = index[grid_dims.index(x)], index[grid_dims.index(y)]
    px, py = bounds[x].values, bounds[y].values
    below, above = bounds["side_below"].values, bounds["side_above"].values
    # a band thinner than any drawing (the crank-rocker's double change point at gamma,
    # 1e-9 wide) is one crossing between its outer meanings, as a neighbouring edge that
    # steps over the band sees it
    rows = []
    for r in np.flatnonzero(keep):
        position = px[r] if axis[r] == x else py[r]
        last = rows[-1] if rows else None
        if (last is not None and axis[last[0]] == axis[r]
                and edge[last[0]] == edge[r]
                and abs(position - last[2]) <= THIN_BAND * max(1.0, abs(position))):
            rows[-1] = (last[0], last[1], position, int(above[r]))
        else:
            rows.append((r, int(below[r]), position, int(above[r])))
    cells: dict = {}
    for r, lower, _, upper in rows:
        pair = frozenset((lower, upper))
        if axis[r] == x:  # an edge along x borders the cells below and above it
            around = ((ix[r], iy[r] - 1), (ix[r], iy[r]))
        else:
            around = ((ix[r] - 1, iy[r]), (ix[r], iy[r]))
        for cell in around:
            cells.setdefault((cell, pair), []).append((px[r], py[r]))
    segments = []
    for (cell, _), points in cells.items():
        if len(points) == 2:
            segments.append(points)
        elif len(points) == 4:  # a saddle cell: join neighbours around the cell's centre
            cx, cy = np.mean(points, axis=0)
            points = sorted(points, key=lambda p: np.arctan2(p[1] - cy, p[0] - cx))
            segments += [points[:2], points[2:]]
    return segments


def _without_jumps(grid: np.ndarray) -> np.ndarray:
    """The grid with the cells beside a jump of more than a quarter of its range blanked:
    contour lines of an overlay follow its smooth variation inside a regime instead of
    piling up where the regime (and the overlay with it) jumps."""
    finite = grid[np.isfinite(grid)]
    if finite.size < 2:
        return grid
    limit = 0.25 * (finite.max() - finite.min())
    jump = np.zeros(grid.shape, bool)
    for axis in (0, 1):
        step = np.abs(np.diff(grid, axis=axis)) > limit
        lead = [slice(None)] * 2
        lead[axis] = slice(1, None)
        trail = [slice(None)] * 2
        trail[axis] = slice(None, -1)
        jump[tuple(lead)] |= step
        jump[tuple(trail)] |= step
    return np.where(jump, np.nan, grid)


def _angle_ticks(ax, degrees: bool) -> None:
    """Crank-angle ticks at multiples of 90° (pi/2)."""
    import matplotlib.ticker as ticker

    if degrees:
        ax.xaxis.set_major_locator(ticker.MultipleLocator(90))
        ax.xaxis.set_minor_locator(ticker.MultipleLocator(30))
        return
    ax.xaxis.set_major_locator(ticker.MultipleLocator(np.pi / 2))
    names = {0: "0", 1: "π/2", 2: "π", 3: "3π/2", 4: "2π"}
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(
        lambda v, _: names.get(int(round(2 * v / np.pi)), f"{2 * v / np.pi:g}π/2")
        if abs(2 * v / np.pi - round(2 * v / np.pi)) < 1e-6 else ""))


def profile_chart(ds: xr.Dataset, names: list[str], where: str | None, out: Path,
                  degrees: bool = True) -> tuple:
    """``profile_figure`` saved as a PNG at ``out``; (out, the grid point's description)."""
    fig, where_text = profile_figure(ds, names, where, degrees)
    fig.savefig(out, dpi=110)
    return out, where_text


def profile_figure(ds: xr.Dataset, names: list[str], where: str | None = None,
                   degrees: bool = True) -> tuple:
    """Profiles of ``names`` over the profile dimension at the first grid point matching
    ``where``, as (Figure, the grid point in words). One panel per unit, stacked over a
    shared angle axis (N and N m on one axis would flatten the smaller); where a profile
    spikes (1/dphi1 reactions) a symmetric-log y axis shows the spike and the rest of the
    cycle. Angles on both axes in degrees, or both in radians; the angle axis ticks every
    90° (or pi/2); the crank angles of special positions and impacts the atlas records are
    marked."""
    from matplotlib.figure import Figure

    if not names:
        raise UserError("variables: give at least one profile variable")
    grid_dims = list(ds["status"].dims)
    for name in names:
        if name not in ds.data_vars:
            raise UserError(f"variables: unknown variable {name!r}")
        extra = [d for d in ds[name].dims if d not in grid_dims]
        if len(extra) != 1:
            raise UserError(f"variables: {name} is not a profile (it has no extra dimension)")
    pdim = [d for d in ds[names[0]].dims if d not in grid_dims][0]
    mask = evaluate(ds, where).values if where else np.ones(ds["status"].shape, bool)
    hits = np.argwhere(mask)
    if not len(hits):
        raise UserError("where: no grid point matches")
    at = {d: int(i) for d, i in zip(grid_dims, hits[0])}
    point = ds.isel(at)
    by_unit: dict[str, list[str]] = {}
    for name in names:
        by_unit.setdefault(_units(point, name, degrees), []).append(name)
    fig = Figure(figsize=(8, 2.2 + 2.6 * len(by_unit)), layout="constrained")
    axes = fig.subplots(len(by_unit), 1, sharex=True, squeeze=False)[:, 0]
    angle = point[pdim].attrs.get("units") == "rad"
    x = _shown(point[pdim], degrees)
    for ax, (units, group) in zip(axes, by_unit.items()):
        scale = []
        for name in group:
            y = _shown(point[name], degrees, ds)
            ax.plot(x, y, lw=1.0, label=f"{name}: {point[name].attrs.get('long_name', '')}")
            scale.append(np.nanmedian(np.abs(y)))
        top = max(float(np.nanmax(np.abs(_shown(point[n], degrees, ds)))) for n in group)
        typical = max(1e-300, float(np.nanmax(scale)))
        if top > 100 * typical:  # a spike (1/dphi1 reactions): a log scale shows it and the rest
            ax.set_yscale("symlog", linthresh=typical)
            ax.set_ylabel(f"[{units}] (symmetric log)")
        else:
            ax.set_ylabel(f"[{units}]")
        if angle:
            _angle_ticks(ax, degrees)
            for value, kind in _angle_marks(point):
                if np.isfinite(value):
                    shown = np.degrees(value) if degrees else value
                    period = 360.0 if degrees else 2 * np.pi
                    while shown > x.max() + 1e-9:  # marks of a 4 pi cycle on a 2 pi profile
                        shown -= period
                    ax.axvline(shown, color="0.3", lw=0.8, ls=":")
                    ax.annotate(kind, (shown, 1.0), xycoords=("data", "axes fraction"),
                                fontsize=7, rotation=90, va="top", ha="right")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[-1].set_xlabel(_label(ds, pdim, degrees))
    where_text = ", ".join(_point_text(point, d, degrees) for d in grid_dims)
    axes[0].set_title(f"{ds.attrs.get('title', '')}\nat {where_text}; {made_by()}",
                      fontsize=8)
    return fig, where_text


def _angle_marks(point: xr.Dataset) -> list[tuple[str, str]]:
    """Scalar outputs that are crank angles of events (``impact_crank_angle_1``,
    ``special_crank_angle``): (variable, label)."""
    marks = []
    for name in point.data_vars:
        if point[name].ndim == 0 and point[name].attrs.get("units") == "rad" and (
                "impact_crank_angle" in name or "special_crank_angle" in name):
            label = name.replace("_crank_angle", "").replace("_", " ")
            marks.append((float(point[name].values), label + " position"
                          if label == "special" else label))
            status = flag_names(point["status"]).get(int(point["status"].values))
            if label == "special" and status == "second_special_position":
                marks.append((float(point[name].values) + np.pi, "second special position"))
    return marks


def _point_text(point: xr.Dataset, dim: str, degrees: bool) -> str:
    value = point[dim].values
    if point[dim].dtype.kind != "f":
        return f"{dim} = {value}"
    units = _units(point, dim, degrees)
    shown = np.degrees(value) if units == "deg" else value
    return f"{dim} = {shown:.4g}" + ("" if units == "-" else f" {units}")
