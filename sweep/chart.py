"""Design charts from an atlas: matplotlib PNG with units on the axes and colour bar."""

from __future__ import annotations

import platform
import textwrap
from pathlib import Path

import numpy as np
import xarray as xr

from sweep.errors import UserError


def _label(ds: xr.Dataset, name: str) -> str:
    attrs = ds[name].attrs
    units = attrs.get("units", "")
    units = "-" if units in ("1", "") else units
    long_name = textwrap.fill(attrs.get("long_name", name), 48)
    return f"{name} [{units}]\n{long_name}"


def design_chart(ds: xr.Dataset, x: str, y: str, color: str, out: Path,
                 ok_only: bool = True) -> Path:
    """Colour map of ``color`` over (x, y), one panel per value of each other grid axis
    of more than one value (categories such as ``type``); non-ok points are left blank."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for axis, name in (("x", x), ("y", y), ("color", color)):
        if name not in ds.variables:
            raise UserError(f"{axis}: unknown variable {name!r}; allowed: "
                            + ", ".join(sorted(map(str, ds.variables))))
    if ds[color].dtype.kind in "OUS":
        raise UserError(f"color: {color!r} is categorical; pick a numeric variable")
    dims = list(ds["status"].dims)
    facet_dims = [d for d in dims if d not in (x, y) and ds.sizes[d] > 1]
    if len(facet_dims) > 1:
        raise UserError(f"chart: more than one other axis to panel over ({', '.join(facet_dims)});"
                        " select a slice first")
    panels = [None] if not facet_dims else list(range(ds.sizes[facet_dims[0]]))
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels) + 1.2, 4.4),
                             squeeze=False, constrained_layout=True)
    from sweep.metadata import usable_mask

    values = ds[color].where(usable_mask(ds)) if ok_only else ds[color]
    finite = np.asarray(values.values)[np.isfinite(np.asarray(values.values, dtype=float))]
    vmin, vmax = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    # values spanning decades (transfer ratios, speeds) read better on a log colour scale
    norm = (matplotlib.colors.LogNorm(vmin=vmin, vmax=vmax)
            if finite.size and vmin > 0 and vmax / vmin > 20 else
            matplotlib.colors.Normalize(vmin=vmin, vmax=vmax))
    if isinstance(norm, matplotlib.colors.LogNorm):
        levels = matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)).tick_values(vmin, vmax)
    else:
        levels = matplotlib.ticker.MaxNLocator(8).tick_values(vmin, vmax)
    levels = levels[(levels > vmin) & (levels < vmax)]
    mesh = None
    for ax, k in zip(axes[0], panels):
        sub = ds if k is None else ds.isel({facet_dims[0]: k})
        val = values if k is None else values.isel({facet_dims[0]: k})
        sub = sub.squeeze(drop=False)
        val = val.squeeze(drop=False)
        if x in sub.dims and y in sub.dims:
            grid = val.transpose(y, x).values
            mesh = ax.pcolormesh(sub[x].values, sub[y].values, grid, norm=norm,
                                 shading="nearest", cmap="viridis")
            if np.isfinite(grid).sum() > 4 and len(levels):
                lines = ax.contour(sub[x].values, sub[y].values, grid, levels=levels,
                                   norm=norm, colors="white", linewidths=0.6)
                ax.clabel(lines, fontsize=7, fmt="%.3g")
        else:
            xs = sub[x].broadcast_like(val).values.ravel()
            ys = sub[y].broadcast_like(val).values.ravel()
            mesh = ax.scatter(xs, ys, c=val.values.ravel(), norm=norm, s=8, cmap="viridis")
        ax.set_facecolor("0.9")
        ax.set_xlabel(_label(ds, x))
        ax.set_ylabel(_label(ds, y))
        if k is not None:
            ax.set_title(f"{facet_dims[0]} = {ds[facet_dims[0]].values[k]}")
        if y in ds.dims and ds[y].size > 2:
            yv = ds[y].values
            if np.all(yv > 0) and yv[-1] / yv[0] > 5 and np.allclose(np.diff(np.log(yv)),
                                                                      np.log(yv[1] / yv[0])):
                ax.set_yscale("log")
    bar = fig.colorbar(mesh, ax=axes[0].tolist())
    bar.set_label(_label(ds, color))
    fig.suptitle(f"{ds.attrs.get('title', '')}\nblank: no design value (status); "
                 f"made on {platform.node() or 'unknown host'} ({platform.machine()})",
                 fontsize=8)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def profile_chart(ds: xr.Dataset, names: list[str], where: str | None, out: Path) -> tuple:
    """Profiles of ``names`` over the profile dimension at the first grid point matching
    ``where``; where a profile spikes (1/dphi1 reactions) a symmetric-log y axis shows the
    spike and the rest of the cycle."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sweep.query import evaluate

    if not names:
        raise UserError("vars: give at least one profile variable")
    grid_dims = list(ds["status"].dims)
    for name in names:
        if name not in ds.data_vars:
            raise UserError(f"vars: unknown variable {name!r}")
        extra = [d for d in ds[name].dims if d not in grid_dims]
        if len(extra) != 1:
            raise UserError(f"vars: {name} is not a profile (it has no extra dimension)")
    pdim = [d for d in ds[names[0]].dims if d not in grid_dims][0]
    mask = evaluate(ds, where).values if where else np.ones(ds["status"].shape, bool)
    hits = np.argwhere(mask)
    if not len(hits):
        raise UserError("where: no grid point matches")
    at = {d: int(i) for d, i in zip(grid_dims, hits[0])}
    point = ds.isel(at)
    fig, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    x = point[pdim].values
    scale = []
    for name in names:
        y = point[name].values
        ax.plot(x, y, lw=1.0, label=f"{name}: {point[name].attrs.get('long_name', '')}")
        scale.append(np.nanmedian(np.abs(y)))
    units = {point[n].attrs.get("units", "") for n in names}
    top = max(float(np.nanmax(np.abs(point[n].values))) for n in names)
    typical = max(1e-300, float(np.nanmax(scale)))
    if top > 100 * typical:  # a spike (1/dphi1 reactions): a log scale shows it and the rest
        ax.set_yscale("symlog", linthresh=typical)
        ax.set_ylabel(f"[{', '.join(sorted(units))}] (symmetric log)")
    else:
        ax.set_ylabel(f"[{', '.join(sorted(units))}]")
    ax.set_xlabel(_label(ds, pdim))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    where_text = ", ".join(f"{d} = {point[d].values:.4g}" if point[d].dtype.kind == "f"
                           else f"{d} = {point[d].values}" for d in grid_dims)
    ax.set_title(f"{ds.attrs.get('title', '')}\nat {where_text}; made on "
                 f"{platform.node() or 'unknown host'} ({platform.machine()})", fontsize=8)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out, where_text
