"""Design charts from an atlas: a matplotlib Figure a designer reads at a glance.

Every axis, colour bar and legend shows a variable's short label with its units
(``blow energy $E$ [J]``, sweep/labels.py), and the title says what is drawn: the colour
over the two axes, at the values held fixed. A numeric output is a colour map with
labelled contour lines and the output's marked levels (K = 1): a signed one on a diverging
map centred on 0 (sweep/palettes.py). A flag output (``regime``, ``status``,
``requirements``) and a count that takes few values are drawn as categories with their
meanings in a legend: ``requirements`` met in blue, each failing limit in its own warm
shade. Cells without a design value are not left white: they are drawn in greys, one per
status, named in the legend. Figures are built without pyplot (a notebook's backend and a
thread's charts do not interfere), or drawn into a caller's axes (``ax``).

``design_figure`` goes in named steps: the input checked (``_check``), the panels
(``_panels``), the colours of the values (``_colouring``) and of the cells without one
(``_blanks``), each panel drawn (``_draw_panel``: cells, boundaries, overlay, contours,
marks, axes), then the key (``_key``: colour bar or legend) and the title (``_title``).
"""

from __future__ import annotations

import datetime as _dt
import itertools
from pathlib import Path
from typing import NamedTuple

import numpy as np
import xarray as xr

from sweep import labels, palettes
from sweep.errors import UserError
from sweep.selection import first_point, flag_names, matching_points, take_at

#: panels per row of a chart with one panel per value of another axis
PANELS_PER_ROW = 3
#: crossings this close (relative) on one edge are drawn as one
THIN_BAND = 1e-6
#: a count with at most this many distinct values is drawn as categories
MAX_COUNT_CATEGORIES = 12
#: contour levels drawn on a colour map, at most (each labelled)
CONTOUR_LEVELS = 5


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
    title: str


def _undetermined_code(var: xr.DataArray):
    """The code of a flag variable's ``undetermined`` meaning (no value), or None."""
    meanings = var.attrs.get("flag_meanings", "").split()
    if "undetermined" not in meanings:
        return None
    return int(np.atleast_1d(var.attrs["flag_values"])[meanings.index("undetermined")])


def _is_count(ds: xr.Dataset, name: str) -> bool:
    """A declared count whose finite values are few enough to read as categories."""
    output = labels.declared(ds, name)
    if output is None or not getattr(output, "count", False):
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
    """Log-axis ticks written as numbers as the contours write them (30, not 3x10^1;
    2,000,000, not 2e+06 beside 500000)."""
    import matplotlib.ticker as ticker

    axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: _number(v)))
    axis.set_minor_formatter(ticker.FuncFormatter(
        lambda v, _: _number(v) if round(v / 10 ** np.floor(np.log10(v))) in (2, 5) else ""))


def _number(value: float) -> str:
    """A contour label as a plain number: 10000, not 1e+04."""
    text = f"{value:.3g}"
    return f"{value:,.0f}" if "e+" in text else text


def design_chart(ds: xr.Dataset, x: str, y: str, color: str, out: Path,
                 ok_only: bool = True, degrees: bool = True, at: dict | None = None,
                 boundaries: xr.Dataset | None = None, overlay: str | None = None) -> Drawn:
    """``design_figure`` saved as a PNG at ``out``; what it shows, read back (``Drawn``)."""
    fig = design_figure(ds, x, y, color, ok_only=ok_only, degrees=degrees, at=at,
                        boundaries=boundaries, overlay=overlay)
    fig.savefig(out, dpi=110)
    return drawn(fig, out)


class Colouring(NamedTuple):
    """How the colour variable is drawn: its values (a category's index for categories)
    where a design has one, NaN elsewhere; whether each cell has one; the map and norm;
    categories or a scale; the categories' (colour, text) for the legend; the contour
    levels of a scale and its marked levels."""

    shown: xr.DataArray
    has_value: np.ndarray
    cmap: object
    norm: object
    categorical: bool
    legend: list
    levels: np.ndarray
    marks: tuple


class Blanks(NamedTuple):
    """The cells without a value: each one's index among the statuses drawn (NaN where it
    has a value), their grey map and norm, and the legend's (grey, text)."""

    index: xr.DataArray
    cmap: object
    norm: object
    legend: list


def design_figure(ds: xr.Dataset, x: str, y: str, color: str, ok_only: bool = True,
                  degrees: bool = True, at: dict | None = None,
                  boundaries: xr.Dataset | None = None, overlay: str | None = None,
                  ax=None, cmap: str | None = None, figsize: tuple | None = None):
    """Chart of ``color`` over (x, y), one panel per value of the other grid axis of more than
    one value (at most three panels a row), as a matplotlib Figure. ``ok_only``: cells whose
    status has no design values are drawn as their status, not as a value; ``degrees``:
    angles in degrees; ``at``: take other grid axes at one value ({axis: (value, "" or
    "deg")}); ``boundaries``: the refined crossings of ``sweep boundaries``, drawn as lines;
    ``overlay``: a numeric output drawn as labelled contour lines over the colours (the
    stability margin over a regime map), where it has a design value. ``ax``: draw into
    these matplotlib axes (one panel) instead of a new figure; ``cmap``: a colour map for a
    numeric output; ``figsize``: the new figure's size in inches."""
    _check(ds, x, y, color, at, overlay, boundaries)
    grid_dims, grid_shape = list(ds["status"].dims), ds["status"].shape
    ds, chosen = take_at(ds, at, grid=True)
    facet, panels = _panels(ds, grid_dims, x, y, ax)
    if ax is None:
        from matplotlib.figure import Figure

        n_cols = min(len(panels), PANELS_PER_ROW)
        n_rows = -(-len(panels) // n_cols)
        fig = Figure(figsize=figsize or (4.6 * n_cols + 1.8, 4.2 * n_rows + 1.2),
                     layout="constrained")
        axes = fig.subplots(n_rows, n_cols, squeeze=False)
    else:
        fig, axes, n_rows, n_cols = ax.figure, np.array([[ax]]), 1, 1
    colouring = _colouring(ds, color, ok_only, degrees, cmap)
    blanks = _blanks(ds, color, colouring.has_value)
    layer = _overlay(ds, overlay, ok_only, degrees) if overlay is not None else None
    mesh = None
    for panel_ax, k in zip(axes.ravel(), panels):
        pick = {} if k is None else {facet: k}
        mesh = _draw_panel(panel_ax, ds, x, y, pick, colouring, blanks, layer, boundaries,
                           grid_dims, grid_shape, degrees)
        if k is not None:
            panel_ax.set_title(labels.value_text(ds, facet, ds[facet].values[k], degrees),
                               fontsize=9)
    for unused in axes.ravel()[len(panels):]:
        unused.set_visible(False)
    _key(fig, axes, ds, color, overlay, boundaries, colouring, blanks, mesh, degrees,
         own=ax is None)
    _title(fig, axes, ds, x, y, color, chosen, grid_dims, facet, degrees, own=ax is None)
    _thin_labels(fig)
    fig.layout_shape = (n_rows, n_cols)  # read back by ``drawn``
    fig.colour_bar = not colouring.categorical
    return fig


def _check(ds, x, y, color, at, overlay, boundaries) -> None:
    """The chart's input, each fault one line naming the argument."""
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


def _panels(ds, grid_dims, x, y, ax) -> tuple:
    """(the axis panelled over, or None; the panels: its indices, or [None])."""
    facet_dims = [d for d in grid_dims if d not in (x, y) and ds.sizes[d] > 1]
    if len(facet_dims) > 1:
        raise UserError(f"chart: more than one other axis to panel over ({', '.join(facet_dims)});"
                        " take one at a value with --at AXIS=VALUE")
    if facet_dims and ax is not None:
        raise UserError(f"ax: one axes holds one panel; take {facet_dims[0]} at a value "
                        "(at=) or let the chart make its own figure")
    if not facet_dims:
        return None, [None]
    return facet_dims[0], list(range(ds.sizes[facet_dims[0]]))


def _colouring(ds, color, ok_only, degrees, cmap_name) -> Colouring:
    """The colours of the colour variable's values (see Colouring)."""
    import matplotlib
    import matplotlib.colors as mcolors
    import matplotlib.ticker as ticker

    from sweep.metadata import usable_mask

    var = ds[color]
    is_flag = "flag_meanings" in var.attrs
    is_count = not is_flag and _is_count(ds, color)
    declared = labels.declared(ds, color)
    # status, and an output that exists at every status (a regime, a threshold), is drawn
    # wherever it has a value; a design value only where the status is usable
    everywhere = color in ("status", "requirements") or (
        declared is not None and getattr(declared, "at_every_status", False))
    usable = (usable_mask(ds).values if ok_only and not everywhere
              else np.ones(var.shape, bool))
    if is_flag or is_count:
        if is_flag:
            names = flag_names(var)
            has_value = usable & (np.asarray(var.values) != _undetermined_code(var))
            present = sorted(int(c) for c in np.unique(np.asarray(var.values)[has_value])
                             if int(c) in names)
            colour_of = palettes.flag_colours(color, names)
            text = {c: names[c].replace("_", " ") for c in present}
        else:  # a count: each value its own category, in the order of the values
            values = np.asarray(var.values, dtype=float)
            has_value = usable & np.isfinite(values)
            present = sorted(int(v) for v in np.unique(values[has_value]))
            colour_of = {c: palettes.CATEGORY_COLOURS[i % len(palettes.CATEGORY_COLOURS)]
                         for i, c in enumerate(present)}
            text = {c: f"{c:d}" for c in present}
        index = {code: i for i, code in enumerate(present)}
        cmap = mcolors.ListedColormap([colour_of[c] for c in present] or ["1.0"])
        norm = mcolors.BoundaryNorm(np.arange(max(len(present), 1) + 1) - 0.5,
                                    max(len(present), 1))
        codes = np.where(has_value, np.asarray(var.values, dtype=float), np.nan)
        shown = np.full(codes.shape, np.nan)
        for code, i in index.items():
            shown[codes == code] = i
        return Colouring(xr.DataArray(shown, dims=var.dims), has_value, cmap, norm, True,
                         [(colour_of[c], text[c]) for c in present], np.array([]), ())
    shown = labels.shown_values(var, degrees, ds).astype(float)
    has_value = usable & np.isfinite(shown)
    shown = np.where(has_value, shown, np.nan)
    finite = shown[has_value]
    vmin, vmax = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    if vmin == vmax:
        vmin, vmax = vmin - 0.5 * max(abs(vmin), 1.0), vmax + 0.5 * max(abs(vmax), 1.0)
    # values spanning decades (transfer ratios, speeds) read better on a log colour scale;
    # a signed quantity on a diverging map centred on 0
    log_colour = bool(finite.size) and vmin > 0 and vmax / vmin > 20
    diverging = not log_colour and palettes.signed(finite)
    if log_colour:
        norm = mcolors.LogNorm(vmin=vmin, vmax=vmax)
    elif diverging:
        norm = mcolors.TwoSlopeNorm(vcenter=0.0, vmin=vmin, vmax=vmax)
    else:
        norm = mcolors.Normalize(vmin=vmin, vmax=vmax)
    cmap = matplotlib.colormaps[cmap_name or (palettes.DIVERGING if diverging
                                              else palettes.SEQUENTIAL)]
    locator = (ticker.LogLocator(subs=(1.0,)) if log_colour
               else ticker.MaxNLocator(CONTOUR_LEVELS))
    levels = np.asarray(locator.tick_values(vmin, vmax))
    levels = levels[(levels > vmin) & (levels < vmax)]
    if log_colour and levels.size < 3:
        levels = np.asarray(ticker.LogLocator(subs=(1.0, 3.0)).tick_values(vmin, vmax))
        levels = levels[(levels > vmin) & (levels < vmax)]
    marks = labels.marks(ds, color)
    levels = levels[~np.isin(levels, [value for value, _ in marks])]  # drawn as marks
    return Colouring(xr.DataArray(shown, dims=var.dims), has_value, cmap, norm, False, [],
                     levels, marks)


def _blanks(ds, color, has_value) -> Blanks:
    """The cells without a value, drawn as their status, each grey named in the legend."""
    import matplotlib.colors as mcolors

    var, status = ds[color], ds["status"]
    status_names = flag_names(status)
    codes = np.where(has_value, -1, status.transpose(*var.dims).values
                     if set(var.dims) == set(status.dims) else -1)
    present = [int(c) for c in np.unique(codes) if c >= 0]
    grey_of = {c: palettes.BLANK_GREYS[i % len(palettes.BLANK_GREYS)]
               for i, c in enumerate(present)}
    index = (np.vectorize(lambda c: present.index(int(c)) if c >= 0 else np.nan,
                          otypes=[float])(codes) if present else np.full(var.shape, np.nan))
    cmap = mcolors.ListedColormap([grey_of[c] for c in present] or ["1.0"])
    norm = mcolors.BoundaryNorm(np.arange(max(len(present), 1) + 1) - 0.5,
                                max(len(present), 1))
    legend = [(grey_of[c], f"no value: {status_names.get(c, c).replace('_', ' ')} "
                           f"({int((codes == c).sum()):,})") for c in present]
    return Blanks(xr.DataArray(index, dims=var.dims), cmap, norm, legend)


def _overlay(ds, overlay, ok_only, degrees) -> tuple:
    """(the overlay's values where they are design values, its contour levels)."""
    import matplotlib.ticker as ticker

    from sweep.metadata import usable_mask

    lay = labels.shown_values(ds[overlay], degrees, ds).astype(float)
    lay = xr.DataArray(np.where(usable_mask(ds).values if ok_only else True, lay, np.nan),
                       dims=ds[overlay].dims)
    finite = lay.values[np.isfinite(lay.values)]
    levels = (ticker.MaxNLocator(CONTOUR_LEVELS).tick_values(finite.min(), finite.max())
              if finite.size else [])
    return lay, levels


def _draw_panel(ax, ds, x, y, pick, colouring, blanks, layer, boundaries, grid_dims,
                grid_shape, degrees):
    """One panel: the greys of cells without a value, the colours, the refined
    boundaries, the overlay's and the scale's labelled contour lines, the marked levels,
    the axes' labels and scales. Returns the colour mesh."""
    import matplotlib.colors as mcolors
    from matplotlib.collections import LineCollection

    x_values = labels.shown_values(ds[x], degrees, ds)
    y_values = labels.shown_values(ds[y], degrees, ds)

    def panel(array):
        array = array.isel(pick) if pick else array
        return array.squeeze([d for d in array.dims if d not in (x, y)],
                             drop=True).transpose(y, x).values

    grid = panel(colouring.shown)
    ax.pcolormesh(x_values, y_values, panel(blanks.index), cmap=blanks.cmap, norm=blanks.norm,
                  shading="nearest")
    mesh = ax.pcolormesh(x_values, y_values, grid, norm=colouring.norm, cmap=colouring.cmap,
                         shading="nearest")
    if boundaries is not None:
        fixed = {d: ds[d].values[pick.get(d, 0)] for d in grid_dims
                 if d not in (x, y) and (d in pick or ds.sizes[d] == 1)}
        segments = boundary_segments(boundaries, grid_dims, grid_shape, x, y, fixed)
        fx, fy = (float(labels.shown_values(xr.DataArray(1.0, name=n, attrs=ds[n].attrs),
                                            degrees, ds)) for n in (x, y))
        segments = [[(a * fx, b * fy) for a, b in seg] for seg in segments]
        ax.add_collection(LineCollection(segments, colors="black", linewidths=1.3))
    if layer is not None:
        values, levels = layer
        values = _without_jumps(panel(values))
        if np.isfinite(values).sum() > 4 and len(levels):
            lines = ax.contour(x_values, y_values, values, levels=levels, colors="black",
                               linewidths=0.9, linestyles="-")
            _label_contours(ax, lines)
    if not colouring.categorical and np.isfinite(grid).sum() > 4:
        if len(colouring.levels):
            # white over a sequential map's dark end, dark grey over a diverging map
            # (whose middle is white); solid at negative levels too
            diverging = isinstance(colouring.norm, mcolors.TwoSlopeNorm)
            lines = ax.contour(x_values, y_values, grid, levels=colouring.levels,
                               norm=colouring.norm, colors="0.25" if diverging else "white",
                               linewidths=0.6, linestyles="solid")
            _label_contours(ax, lines)
        for value, meaning in colouring.marks:
            if np.nanmin(grid) < value < np.nanmax(grid):
                mark = ax.contour(x_values, y_values, grid, levels=[value],
                                  colors="#D55E00", linewidths=1.6, linestyles="--")
                ax.clabel(mark, fmt={value: meaning.split(":")[0]}, fontsize=8)
    ax.set_xlabel(labels.axis_label(ds, x, degrees))
    ax.set_ylabel(labels.axis_label(ds, y, degrees))
    for name, values, axis, scale in ((x, x_values, ax.xaxis, ax.set_xscale),
                                      (y, y_values, ax.yaxis, ax.set_yscale)):
        if name in ds.dims and _log_spaced(np.asarray(values)):
            scale("log")
            _plain_log_axis(axis)
    return mesh


def _label_contours(ax, lines) -> None:
    """One label on every level drawn, at the middle (by length) of its longest line: away
    from the axes' edges, where matplotlib's own placement often puts them; those that
    collide are thinned once the figure is laid out (``_thin_labels``)."""
    places, levels = [], []
    for level, segments in zip(lines.levels, lines.allsegs):
        if not segments:
            continue
        longest = max(segments, key=lambda seg: np.sum(np.hypot(*np.diff(seg, axis=0).T)))
        if len(longest) < 2:
            continue
        length = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(longest, axis=0).T))))
        middle = int(np.searchsorted(length, 0.5 * length[-1]))
        places.append(tuple(longest[min(middle, len(longest) - 1)]))
        levels.append(level)
    if not places:
        return
    texts = ax.clabel(lines, levels, fontsize=7, fmt=_number, inline_spacing=2,
                      manual=places)
    ax.contour_labels = getattr(ax, "contour_labels", []) + list(texts)


def _thin_labels(fig) -> None:
    """Drop a contour label that overlaps one kept (or an axes' edge), unless it is its
    level's last one: every level drawn keeps a label, none sits on another."""
    if not any(getattr(ax, "contour_labels", []) for ax in fig.axes):
        return  # nothing to thin: spare the layout pass the extents need
    fig.draw_without_rendering()
    renderer = fig._get_renderer()
    for ax in fig.axes:
        texts = getattr(ax, "contour_labels", [])
        left: dict[str, int] = {}
        for t in texts:
            left[t.get_text()] = left.get(t.get_text(), 0) + 1
        frame = ax.get_window_extent(renderer)
        kept = []
        for t in texts:
            box = t.get_window_extent(renderer)
            inside = (frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0
                      and box.y1 <= frame.y1)
            if (not inside or any(box.overlaps(other) for other in kept)) and \
                    left[t.get_text()] > 1:
                left[t.get_text()] -= 1
                t.remove()
                continue
            kept.append(box)


def _key(fig, axes, ds, color, overlay, boundaries, colouring, blanks, mesh, degrees,
         own: bool) -> None:
    """The colour bar of a scale (with its marked levels), and the legend: categories, the
    overlay's and boundaries' lines, the greys of cells without a value."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = []
    if overlay is not None:
        handles.append(Line2D([], [], color="black", lw=0.9,
                              label=f"{labels.axis_label(ds, overlay, degrees)} (lines)"))
    if boundaries is not None:
        handles.append(Line2D([], [], color="black", lw=1.3, label=(
            f"{labels.label(ds, str(boundaries.attrs.get('variable')))} boundaries, to "
            f"{float(boundaries.attrs.get('tolerance', np.nan)):g}")))
    if colouring.categorical:
        handles += [Patch(color=colour, label=text) for colour, text in colouring.legend]
    else:
        bar = fig.colorbar(mesh, ax=axes.ravel().tolist() if own else axes[0, 0],
                           shrink=0.9)
        bar.set_label(labels.axis_label(ds, color, degrees))
        import matplotlib.colors as mcolors

        if isinstance(colouring.norm, mcolors.LogNorm):
            _plain_log_axis(bar.ax.yaxis)
        for value, meaning in colouring.marks:
            if colouring.norm.vmin < value < colouring.norm.vmax:
                bar.ax.axhline(value, color="#D55E00", lw=1.6, ls="--")
                handles.append(Line2D([], [], color="#D55E00", lw=1.6, ls="--",
                                      label=meaning))
    handles += [Patch(color=grey, label=text) for grey, text in blanks.legend]
    if not handles:
        return
    if own:
        # as many columns as the figure's width holds of the longest label (8 pt text)
        longest = max(len(h.get_label()) for h in handles)
        fits = int(fig.get_figwidth() / (0.075 * longest + 0.6))
        fig.legend(handles=handles, loc="outside lower center", fontsize=8,
                   ncols=max(1, min(len(handles), 4, fits)), frameon=False)
    else:
        axes[0, 0].legend(handles=handles, fontsize=7)


def _title(fig, axes, ds, x, y, color, chosen, grid_dims, facet, degrees, own) -> None:
    """What is drawn: the colour over the two axes, at the values held fixed (the axes taken
    at a value and those of one value), one line of the atlas's title and the code's
    version under it."""
    held = [labels.value_text(ds, d, ds[d].values[0], degrees) for d in grid_dims
            if d not in (x, y, facet) and d in ds.dims and ds.sizes[d] == 1]
    what = f"{labels.label(ds, color)} over {labels.label(ds, x)} and {labels.label(ds, y)}"
    if held:
        what += ", at " + ", ".join(held)
    if not own:
        axes[0, 0].set_title(labels.wrapped(what, 60), fontsize=9)
        return
    width = int(fig.get_figwidth() * 12)  # characters a line of 9 pt text holds
    caption = ds.attrs.get("title", "")
    fig.suptitle(labels.wrapped(what, width) + "\n" + labels.wrapped(
        f"{caption} · {made_by()}" if caption else made_by(), width), fontsize=9)


def drawn(fig, out: Path) -> Drawn:
    """What a design figure shows, read back from it (for the CLI and the tests)."""
    import matplotlib.colors as mcolors
    from matplotlib.patches import Patch

    fig.draw_without_rendering()
    used = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    handles = fig.legends[0].legend_handles if fig.legends else []
    n_rows, n_cols = fig.layout_shape
    texts = [t.get_text() for t in fig.legends[0].get_texts()] if fig.legends else []
    return Drawn(out, texts, [ax.get_title() for ax in used],
                 n_rows, n_cols, used[0].get_xlabel(), used[0].get_ylabel(),
                 used[0].get_xscale(), used[0].get_yscale(),
                 [t.get_text() for t in used[0].get_xticklabels() if t.get_text()],
                 [t.get_text() for t in used[0].get_yticklabels() if t.get_text()],
                 fig.colour_bar,
                 [mcolors.to_hex(h.get_facecolor() if isinstance(h, Patch) else h.get_color())
                  for h in handles],
                 fig.get_suptitle())


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
                  degrees: bool = True, against: str | None = None,
                  each: str | None = None, every: bool = False) -> tuple:
    """``profile_figure`` saved as a PNG at ``out``; (out, the grid point's description)."""
    fig, where_text = profile_figure(ds, names, where, degrees, against=against, each=each,
                                     every=every)
    fig.savefig(out, dpi=110)
    return out, where_text


def profile_figure(ds: xr.Dataset, names: list[str], where: str | None = None,
                   degrees: bool = True, at: dict | None = None,
                   against: str | None = None, each: str | None = None,
                   every: bool = False) -> tuple:
    """Profiles of ``names`` over the profile dimension at the first grid point matching
    ``where``, as (Figure, the grid point in words). One panel per unit, stacked over a
    shared angle axis (N and N m on one axis would flatten the smaller); where a profile
    spikes (1/dphi1 reactions) a symmetric-log y axis shows the spike and the rest of the
    cycle. Angles on both axes in degrees, or both in radians; the angle axis ticks every
    90° (or pi/2); the crank angles of special positions and impacts the atlas records are
    marked. ``at``: the grid point {dim: index} instead of ``where``. ``against``: another
    profile on the x axis instead of the profile dimension (phi5 against phi3). ``each``: a
    grid axis, one curve per value of it at the point's other values. ``every``: one curve
    per grid point matching ``where`` (at most MAX_CURVES; [CR] Fig. 2's three
    mechanisms)."""
    from matplotlib.figure import Figure

    grid_dims = list(ds["status"].dims)
    pdim = _profile_dimension(ds, names, grid_dims, against, each)
    if every:
        picks = matching_points(ds, where)
        if len(picks) > MAX_CURVES:
            raise UserError(f"where: {len(picks)} grid points match; one curve each is at "
                            f"most {MAX_CURVES}")
    else:
        at = first_point(ds, where) if at is None else at
        picks = [at] if each is None else [{**at, each: k} for k in range(ds.sizes[each])]
    points = [ds.isel(pick) for pick in picks]
    point = points[0]
    # the axes the curves differ in (each's, or those of the matching points) name them
    varying = [d for d in grid_dims if len({pick[d] for pick in picks}) > 1]
    by_unit: dict[str, list[str]] = {}
    for name in names:
        by_unit.setdefault(labels.units(point, name, degrees), []).append(name)
    fig = Figure(figsize=(8, 2.0 + 2.6 * len(by_unit)), layout="constrained")
    axes = fig.subplots(len(by_unit), 1, sharex=True, squeeze=False)[:, 0]
    xname = against or pdim
    for n, (ax, (units, group)) in enumerate(zip(axes, by_unit.items())):
        # one legend of the designs, unless a panel's variables need their own
        legend = n == 0 or len(group) > 1
        _profile_panel(ax, ds, points, group, units, xname, degrees, varying, legend)
        if point[xname].attrs.get("units") == "rad" and against is None:
            _angle_ticks(ax, degrees)
            if len(points) == 1:  # each design has its own events
                _mark_events(ax, point, labels.shown_values(point[xname], degrees), degrees)
    axes[-1].set_xlabel(labels.axis_label(ds, xname, degrees))
    held = [d for d in grid_dims if d not in varying]
    at_text = design_text(point, held, degrees) if held else ""
    fig.suptitle(labels.wrapped(
        f"{', '.join(labels.label(ds, n) for n in names)} "
        f"{'against' if against else 'over'} {labels.label(ds, xname)}"
        + (f", one curve per {', '.join(labels.label(ds, d) for d in varying)}"
           if varying else "")
        + (f", at {at_text}" if at_text else ""), 100), fontsize=9)
    where_text = design_text(point, held, degrees, plain=True) if held else "every point"
    caption = ds.attrs.get("title", "")
    fig.suptitle(fig.get_suptitle() + "\n" + labels.wrapped(
        f"{caption} · {made_by()}" if caption else made_by(), 110), fontsize=9)
    return fig, where_text


def _profile_dimension(ds: xr.Dataset, names: list[str], grid_dims: list[str],
                       against: str | None, each: str | None) -> str:
    """The profiles' own dimension, after checking the names, ``against`` and ``each``."""
    if not names:
        raise UserError("variables: give at least one profile variable")
    for name in names:
        if name not in ds.data_vars:
            raise UserError(f"variables: unknown variable {name!r}")
        extra = [d for d in ds[name].dims if d not in grid_dims]
        if len(extra) != 1:
            raise UserError(f"variables: {name} is not a profile (it has no extra dimension)")
    pdim = [d for d in ds[names[0]].dims if d not in grid_dims][0]
    if against is not None and (against not in ds.data_vars or pdim not in ds[against].dims):
        raise UserError(f"against: {against!r} is not a profile of this atlas; allowed: "
                        + ", ".join(n for n in ds.data_vars if pdim in ds[n].dims))
    if each is not None and each not in grid_dims:
        raise UserError(f"each: {each!r} is not a grid axis of this atlas; allowed: "
                        + ", ".join(grid_dims))
    return pdim


#: curves one profile chart draws at most (one per grid point)
MAX_CURVES = 12


def _profile_panel(ax, ds: xr.Dataset, points: list, group: list[str], units: str,
                   xname: str, degrees: bool, varying: list[str], legend: bool) -> None:
    """One unit's curves: each variable at each point (colour by curve), the y axis
    labelled, symmetric-log where a spike would flatten the rest, a legend for several."""
    curves = [(name, p) for p in points for name in group]
    scale, top = [], 0.0
    for (name, p), colour in zip(curves, itertools.cycle(palettes.CATEGORY_COLOURS)):
        x = labels.shown_values(p[xname], degrees, ds if xname in ds.data_vars else None)
        y = labels.shown_values(p[name], degrees, ds)
        text = labels.label(ds, name)
        if varying:
            value = design_text(p, varying, degrees)
            text = f"{text}, {value}" if len(group) > 1 else value
        ax.plot(x, y, lw=1.1, color=colour, label=text)
        if np.isfinite(y).any():
            scale.append(np.nanmedian(np.abs(y)))
            top = max(top, float(np.nanmax(np.abs(y))))
    typical = max(1e-300, float(np.nanmax(scale)) if scale else 1.0)
    name = (labels.axis_label(ds, group[0], degrees) if len(group) == 1 else
            f"{QUANTITY_OF_UNITS.get(units, 'value')} [{labels.pretty_units(units)}]")
    if top > 100 * typical:  # a spike (1/dphi1 reactions): a log scale shows it and the rest
        ax.set_yscale("symlog", linthresh=typical)
        name += ", symlog"
    ax.set_ylabel(labels.wrapped(name, 34))
    ax.grid(True, which="both", alpha=0.3)
    if legend and len(curves) > 1:  # beside the panel, or under it where names are long
        handles, texts = ax.get_legend_handles_labels()
        if max(len(t) for t in texts) > 30:
            ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12),
                      frameon=False, ncol=1)
        else:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                      frameon=False)


def _mark_events(ax, point: xr.Dataset, x: np.ndarray, degrees: bool) -> None:
    """Dotted lines at the crank angles of the special positions and impacts the point
    records; a special position recurs every turn (a free path's profile has two)."""
    period = 360.0 if degrees else 2 * np.pi
    for value, kind in _angle_marks(point):
        if not np.isfinite(value):
            continue
        shown = np.degrees(value) if degrees else value
        while shown > x.max() + 1e-9:  # marks of a 4 pi cycle on a 2 pi profile
            shown -= period
        every = [shown + k * period for k in range(int(np.ptp(x) // period) + 2)
                 if shown + k * period <= x.max() + 1e-9] if "special" in kind else [shown]
        for where_at in every:
            ax.axvline(where_at, color="0.3", lw=0.8, ls=":")
            ax.annotate(kind, (where_at, 1.0), xycoords=("data", "axes fraction"),
                        fontsize=7, rotation=90, va="top", ha="right")


#: what a profile panel of several variables in one unit shows, by the unit
QUANTITY_OF_UNITS = {"N": "force", "N m": "moment", "J": "energy", "W": "power",
                     "rad": "angle", "deg": "angle", "rad s-1": "angular speed",
                     "rad s-2": "angular acceleration", "m s-1": "speed", "1": "ratio"}


def design_text(point: xr.Dataset, grid_dims: list[str], degrees: bool,
                plain: bool = False) -> str:
    """One design in words: each grid axis held at its value, and a chained design by the
    parameters it sets (``design`` alone says nothing of the machine); ``plain``: by the
    variables' names (a terminal's text), not their labels."""
    def text(name, value):
        return labels.value_text(point, name, value, degrees, 4, plain=plain)

    parts = []
    for dim in grid_dims:
        if dim == "design":
            names = [n for n in point.coords if n not in grid_dims and point[n].ndim == 0
                     and not str(n).startswith("source_") and n != "grid_point"
                     and point[n].dtype.kind in "fiuOSU"]
            parts += [text(str(n), point[n].values) for n in names] or [
                f"design {int(point[dim].values)}"]
        else:
            parts.append(text(dim, point[dim].values))
    return ", ".join(parts)


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
