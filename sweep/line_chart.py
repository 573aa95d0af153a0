"""``sweep lines``: outputs against one grid axis, one curve per value of another, the
other grid axes held at one value: the papers' families of curves ([BAL] Fig. 2, the peak
invariants against f for several omega0/p) and any output's trend along an axis.

A point without a design value (its status has none) leaves a gap in its curve, never a
line drawn across it. Labels are the short ones with units; colours run along the family's
axis on the sequential map (a categorical axis takes the categories' colours).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from sweep.errors import UserError

#: curves at most in one chart (a legend of more is not read)
MAX_CURVES = 12


def figure(ds: xr.Dataset, x: str, ys: list[str], by: str | None = None, values=None,
           at: dict | None = None, degrees: bool = True, ax=None):
    """The chart (see the module): ``ys`` over the grid axis ``x``, one curve per value of
    the grid axis ``by`` (its ``values`` nearest, or every one up to MAX_CURVES)."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    from sweep import labels, palettes
    from sweep.charts import made_by
    from sweep.metadata import usable_mask
    from sweep.selection import take_at

    dims = list(ds["status"].dims)
    if x not in dims:
        raise UserError(f"x: {x!r} is not a grid axis; allowed: {', '.join(dims)}")
    if ds[x].dtype.kind not in "fiu":
        raise UserError(f"x: {x} is categorical; a line runs along a numeric axis")
    if not ys:
        raise UserError("y: give at least one output")
    for y in ys:
        if y not in ds.data_vars or not set(ds[y].dims) <= set(dims) or \
                "flag_meanings" in ds[y].attrs or ds[y].dtype.kind != "f":
            raise UserError(f"y: {y!r} is not a numeric output of the atlas with one value "
                            "per grid point")
    if by is not None and (by not in dims or by == x):
        raise UserError(f"by: {by!r} is not another grid axis; allowed: "
                        + ", ".join(d for d in dims if d != x))
    if by is not None and by in (at or {}):
        raise UserError(f"by: {by} is also held in at; give it once")
    held, chosen = take_at(ds, at, grid=True)
    free = [d for d in dims if d not in (x, by) and held.sizes[d] > 1]
    if free:  # a numeric axis is held with at, a categorical one drawn with by
        numeric = [d for d in free if held[d].dtype.kind in "fiu"]
        words = [d for d in free if d not in numeric]
        parts = ([f"hold {', '.join(numeric)} at a value (at={{{numeric[0]!r}: ...}}, "
                  f"--at {numeric[0]}=VALUE)"] if numeric else []) + \
            ([f"draw {words[0]} as one line per value (by={words[0]!r}, --by {words[0]})"]
             if words else [])
        raise UserError("at: " + "; ".join(parts))
    held = held.where(usable_mask(held))
    if by is None:
        families = [(None, held)]
    else:
        axis = held[by]
        if values is None:
            picks = list(range(axis.size))
        else:
            numbers = [values] if np.isscalar(values) else list(values)
            if axis.dtype.kind not in "fiu":
                picks = [list(map(str, axis.values)).index(str(v)) if str(v) in
                         list(map(str, axis.values)) else -1 for v in numbers]
                if -1 in picks:
                    raise UserError(f"values: {by} takes "
                                    + ", ".join(map(str, axis.values)))
            else:
                picks = [int(np.argmin(np.abs(axis.values - float(v)))) for v in numbers]
            picks = list(dict.fromkeys(picks))
        if len(picks) > MAX_CURVES:
            raise UserError(f"by: {by} has {len(picks)} values; pick at most {MAX_CURVES} "
                            "with values (--values)")
        families = [(k, held.isel({by: k})) for k in picks]
    if ax is None:
        fig = Figure(figsize=(7.2, 4.2 + 1.4 * (len(ys) - 1)), layout="constrained")
        axes = fig.subplots(len(ys), 1, sharex=True, squeeze=False)[:, 0]
    else:
        if len(ys) > 1:
            raise UserError("ax: one axes holds one output; give one y, or no ax")
        fig, axes = ax.figure, [ax]
    xs = labels.shown_values(held[x], degrees, ds)
    categorical = by is not None and held[by].dtype.kind not in "fiu"
    cmap = colormaps[palettes.SEQUENTIAL]
    for panel, y in zip(axes, ys):
        for n, (k, part) in enumerate(families):
            values_y = labels.shown_values(part[y].squeeze(drop=True), degrees, ds)
            values_y = np.asarray(values_y).reshape(-1)
            if by is None:
                colour, name = palettes.OKABE_ITO[0], None
            elif categorical:
                colour = palettes.CATEGORY_COLOURS[n % len(palettes.CATEGORY_COLOURS)]
                name = labels.value_text(ds, by, held[by].values[k], degrees)
            else:
                colour = cmap(0.1 + 0.8 * n / max(1, len(families) - 1))
                name = labels.value_text(ds, by, held[by].values[k], degrees)
            panel.plot(xs, values_y, color=colour, lw=1.4, label=name)
        for level, meaning in labels.marks(ds, y):  # the levels it is read against (K = 1)
            panel.axhline(level, color="0.3", lw=0.9, ls="--")
            panel.annotate(meaning, (0.01, level), xycoords=("axes fraction", "data"),
                           fontsize=7, va="bottom", color="0.3")
        panel.set_ylabel(labels.wrapped(labels.axis_label(ds, y, degrees), 36))
        panel.grid(True, alpha=0.3)
    axes[-1].set_xlabel(labels.axis_label(ds, x, degrees))
    if by is not None:
        axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                       frameon=False)
    if ax is None:
        what = ", ".join(labels.label(ds, y) for y in ys)
        title = f"{what} over {labels.label(ds, x)}" + (
            f", one line per {labels.label(ds, by)}" if by is not None else "")
        held_text = ", ".join(labels.value_text(ds, d, held[d].values.item(), degrees)
                              for d in dims if d not in (x, by) and d in held.coords
                              and held[d].size == 1 and ds.sizes[d] > 1)
        if held_text:
            title += f", at {held_text}"
        fig.suptitle(labels.wrapped(title, 100) + "\n" + labels.wrapped(
            f"{ds.attrs.get('title', '')} · {made_by()}", 110), fontsize=9)
    del chosen
    return fig
