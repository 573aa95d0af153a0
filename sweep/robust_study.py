"""``sweep robust``: an atlas reduced over a band of one of its grid axes (the material's R
over the rock band, a crank speed over +-5 %): every design's worst and best value of each
output over the band and its spread, and whether the design is usable and meets its
requirements at every point of it.

The extremes are the grid's samples inside the band (and at its ends, computed where the
grid has no sample there), then, for the outputs asked (by default those the requirements
name), refined between the samples on the kernel: a golden-section search in the bracket
of the best sample and its neighbours, for every design at once (one kernel call per step),
to ``REFINE_TOL`` of the band's width. The search takes the output to be unimodal in that
bracket, as a refined boundary of ``sweep boundaries`` takes a single crossing.

The result is an atlas of the other grid axes: ``NAME_min``, ``NAME_max``, ``NAME_spread``
of every numeric output, ``status`` the design's worst over the band (ok only where every
point is usable), ``requirements`` met only where every point meets them (with the refined
extremes), so that ``sweep pareto``, the charts and the explorer read it like any other.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import xarray as xr

from sweep.errors import UserError

#: the refined extreme's abscissa to this fraction of the band's width
REFINE_TOL = 1e-9
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def band_of(ds: xr.Dataset, over) -> tuple[str, float, float]:
    """(axis, low, high) of ``over``: an axis name (its whole range) or {axis: (low,
    high)} inside the axis's range, checked."""
    if isinstance(over, str):
        axis, band = over, None
    elif isinstance(over, dict) and len(over) == 1:
        (axis, band), = over.items()
    else:
        raise UserError("over: a grid axis's name, or {axis: (low, high)}")
    dims = list(ds["status"].dims)
    if axis not in dims:
        raise UserError(f"over: {axis!r} is not a grid axis of the atlas; allowed: "
                        + ", ".join(dims))
    values = np.asarray(ds[axis].values)
    if values.dtype.kind not in "fiu" or values.size < 2:
        raise UserError(f"over.{axis}: a band is over a numeric axis of two values or more")
    if band is None:
        return axis, float(values.min()), float(values.max())
    if not (isinstance(band, (tuple, list)) and len(band) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in band)):
        raise UserError(f"over.{axis}: (low, high), two numbers")
    low, high = float(band[0]), float(band[1])
    if not low < high:
        raise UserError(f"over.{axis}: low {low:g} must be below high {high:g}")
    if low < values.min() - 1e-12 * abs(values.min()) or \
            high > values.max() + 1e-12 * abs(values.max()):
        raise UserError(f"over.{axis}: ({low:g}, {high:g}) reaches outside the atlas's "
                        f"{values.min():g} .. {values.max():g}; run the atlas over the band")
    return axis, low, high


def reduce(ds: xr.Dataset, over, refine=None) -> xr.Dataset:
    """The atlas reduced over the band (see the module)."""
    from sweep import requirements, spec
    from sweep.metadata import usable_mask

    axis, low, high = band_of(ds, over)
    limits = requirements.of_dataset(ds)
    names = [str(n) for n, v in ds.data_vars.items()
             if n not in ("status", "requirements", "requirement_margin")
             and set(v.dims) <= set(ds["status"].dims) and axis in v.dims
             and "flag_meanings" not in v.attrs and v.dtype.kind == "f"]
    if refine is None:
        refine = [limit.name for limit in limits]
    refine = [refine] if isinstance(refine, str) else list(refine)
    for name in refine:
        if name not in names:
            raise UserError(f"refine: {name!r} is not a numeric output of the atlas over "
                            f"{axis}; allowed: " + ", ".join(names))
    values = np.asarray(ds[axis].values, dtype=float)
    inside = np.flatnonzero((values >= low) & (values <= high))
    ends = [x for x in (low, high) if not np.any(values[inside] == x)]
    sweep = spec.validate(json.loads(ds.attrs["spec"])) if ends or refine else None
    band = ds.isel({axis: inside})
    usable = usable_mask(band)
    status = band["status"]
    # usable at every point: the status of the band's first sample (a usable one); else
    # the greatest code of a point that is not usable
    everywhere = usable.all(axis)
    worst_status = xr.where(everywhere, status.isel({axis: 0}),
                            status.where(~usable).max(axis)).astype(np.int8)
    data = {}
    extra = _ends(ds, sweep, axis, ends, names) if ends else None
    order = [d for d in ds["status"].dims if d != axis]
    for name in names:
        var = band[name].where(usable).transpose(*order, axis).values
        if extra is not None:
            var = np.concatenate([var, extra[name]], axis=-1)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a design with no value
            lo, hi = np.nanmin(var, axis=-1), np.nanmax(var, axis=-1)
        data[name] = [lo, hi]
    if extra is not None:
        end_usable = extra["_usable"]
        inside_ok = everywhere.transpose(*order).values
        worst_status = xr.DataArray(np.where(
            end_usable.all(axis=-1), worst_status.transpose(*order).values,
            np.where(inside_ok, extra["_worst"], np.maximum(
                worst_status.transpose(*order).values, extra["_worst"]))), dims=order)
    refined = {}
    if refine:
        refined = _refine(ds, sweep, axis, low, high, refine, data, order)
    out = xr.Dataset(coords={d: ds[d] for d in order})
    for name in names:
        lo, hi = data[name]
        if name in refined:
            lo, hi = np.fmin(lo, refined[name][0]), np.fmax(hi, refined[name][1])
        base = ds[name].attrs
        units = base.get("units", "1")
        label = base.get("label", name)
        for suffix, value, words in (("min", lo, "least"), ("max", hi, "greatest"),
                                     ("spread", hi - lo, "spread (greatest - least)")):
            out[f"{name}_{suffix}"] = xr.DataArray(value, dims=order, attrs={
                "units": units, "label": f"{label} {suffix} over {axis}",
                "long_name": f"{words} of {base.get('long_name', name)} over {axis} in "
                             f"[{low:g}, {high:g}]" + (" (refined between samples)"
                                                        if name in refined else "")})
    status_var = xr.DataArray(worst_status.transpose(*order).values, dims=order,
                              attrs=dict(ds["status"].attrs))
    status_var.attrs["long_name"] = (f"the design's worst status over {axis} in "
                                     f"[{low:g}, {high:g}] (usable only where every "
                                     "point is)")
    out["status"] = status_var.astype(np.int8)
    if limits:
        worst = {}
        for limit in limits:
            lo, hi = (out[f"{limit.name}_min"].values, out[f"{limit.name}_max"].values)
            worst[limit.name] = hi if limit.upper else lo
        code, margin = requirements.evaluate(worst, limits)
        out["requirements"] = xr.DataArray(code, dims=order,
                                           attrs=requirements.attributes(limits))
        out["requirements"].attrs["long_name"] = (
            f"the requirement the design fails at its worst over {axis} in [{low:g}, "
            f"{high:g}], or met at every point")
        out["requirement_margin"] = xr.DataArray(margin, dims=order,
                                                 attrs=requirements.MARGIN_ATTRIBUTES)
    robust = {"axis": axis, "band": [low, high], "samples_in_band": int(inside.size),
              "ends_computed": ends, "refined": sorted(refined),
              "refine_tol": REFINE_TOL if refined else None,
              "method": "extremes of the grid's samples in the band; the refined outputs "
                        "by golden section on the kernel in the bracket of the best sample "
                        "(unimodal there) to refine_tol of the band's width"}
    out.attrs.update({k: v for k, v in ds.attrs.items()})
    out.attrs["title"] = f"{ds.attrs.get('title', '')}, over {axis} in [{low:g}, {high:g}]"
    out.attrs["robust"] = json.dumps(robust)
    return out


def _columns(ds, sweep, axis, order):
    """The kernel's parameter columns of every design (the other axes' points), the band
    axis at its first value, and the band parameter's row."""
    from sweep import engine

    dims = list(ds["status"].dims)
    shape = ds["status"].shape
    others = [ds.sizes[d] for d in order]
    index = np.indices(others).reshape(len(others), -1)
    full = [index[order.index(d)] if d != axis else np.zeros(index.shape[1], dtype=int)
            for d in dims]
    flat = np.ravel_multi_index(full, shape)
    params = engine.point_parameters(sweep, flat)
    row = [p.name for p in sweep.mechanism.parameters].index(axis)
    return params, row, tuple(others)


def _run(sweep, params, names):
    from sweep.sensitivity_study import evaluate

    out, status = evaluate(sweep, params)
    index = sweep.mechanism.output_index
    codes = sweep.mechanism.status_codes._asdict()
    ok = np.isin(status, [codes[w] for w in ("ok", *sweep.mechanism.usable)])
    return {n: np.where(ok, out[getattr(index, n)], np.nan) for n in names}, ok, status


def _ends(ds, sweep, axis, ends, names):
    """Each design's outputs at band ends the grid has no sample at."""
    order = [d for d in ds["status"].dims if d != axis]
    params, row, shape = _columns(ds, sweep, axis, order)
    values = {n: [] for n in names}
    usable, worst = [], []
    for x in ends:
        params[row] = x
        outs, ok, status = _run(sweep, params, names)
        for n in names:
            values[n].append(outs[n].reshape(shape))
        usable.append(ok.reshape(shape))
        worst.append(np.where(ok, 0, status).reshape(shape))
    result = {n: np.stack(v, axis=-1) for n, v in values.items()}
    result["_usable"] = np.stack(usable, axis=-1)
    result["_worst"] = np.max(np.stack(worst, axis=-1), axis=-1)
    return result


def _refine(ds, sweep, axis, low, high, refine, data, order):
    """{output: (refined least, refined greatest)} per design: golden section in the
    bracket of the best sample, every design and sense at once."""
    values = np.asarray(ds[axis].values, dtype=float)
    grid = np.unique(np.concatenate([values[(values >= low) & (values <= high)],
                                     [low, high]]))
    from sweep.metadata import usable_mask

    params, row, shape = _columns(ds, sweep, axis, order)
    n = params.shape[1]
    result = {}
    for name in refine:
        sampled = ds[name].where(usable_mask(ds)).transpose(*order, axis).values
        sampled = sampled.reshape(n, -1)
        found = []
        for sense in (-1.0, 1.0):  # -1: the least, +1: the greatest
            score = np.where(np.isfinite(sampled), sense * sampled, -np.inf)
            x = values[np.argmax(score, axis=1)]
            position = np.searchsorted(grid, x)
            a = grid[np.maximum(position - 1, 0)]
            b = grid[np.minimum(position + 1, grid.size - 1)]
            best = _golden(sweep, params, row, name, a, b, sense, (high - low) * REFINE_TOL)
            found.append(best.reshape(shape))
        result[name] = (found[0], found[1])
    return result


def _golden(sweep, params, row, name, a, b, sense, tol):
    """The best (sense * value greatest) of ``name`` in [a, b] per column: golden section,
    one kernel call per step for every column; NaN where no point has a value."""
    a, b = a.copy(), b.copy()
    c = b - GOLDEN * (b - a)
    d = a + GOLDEN * (b - a)

    def f(x):
        params[row] = x
        value = _run(sweep, params, [name])[0][name]
        return np.where(np.isfinite(value), sense * value, -np.inf), value

    fc, vc = f(c)
    fd, vd = f(d)
    best = np.where(fc >= fd, vc, vd)
    while np.any(b - a > tol):
        left = fc >= fd  # the best lies in [a, d]
        b = np.where(left, d, b)
        a = np.where(left, a, c)
        c_new = b - GOLDEN * (b - a)
        d_new = a + GOLDEN * (b - a)
        x = np.where(left, c_new, d_new)
        fx, vx = f(x)
        fc, fd, vc, vd, c, d = (np.where(left, fx, fd), np.where(left, fc, fx),
                                np.where(left, vx, vd), np.where(left, vc, vx),
                                np.where(left, c_new, d), np.where(left, c, d_new))
        better = np.where(np.isfinite(vx), sense * vx, -np.inf) > \
            np.where(np.isfinite(best), sense * best, -np.inf)
        best = np.where(better, vx, best)
    for x in (a, b):  # the bracket's ends: a sample's own value
        fx, vx = f(x)
        better = np.where(np.isfinite(vx), sense * vx, -np.inf) > \
            np.where(np.isfinite(best), sense * best, -np.inf)
        best = np.where(better, vx, best)
    return best
