"""From an atlas to a decision: the Pareto front of its feasible designs and one pick.

A design is feasible when its status is usable (``ok``), it meets the atlas's requirements
(its ``requirements`` flag is ``met``, where it has one) and it satisfies ``where``. The front
is the feasible designs no other feasible design dominates in the objectives (each
maximised or minimised), computed exactly by ``kernels.pareto``. A pick rule then names one:

- ``knee``: the design nearest the ideal point, each objective scaled over the front to 0
  at its best and 1 at its worst (the compromise design; on a two-objective front, where
  the front bends most towards the ideal);
- ``lexicographic``: best in the first objective, ties broken by the next, and so on;
- ``weighted``: the least weighted sum of the scaled objectives.

Ties of a rule go to the first design of the front (ordered by the first objective).

Objective values that agree to a relative tolerance (``tie_tol``, 1e-9 by default, recorded
in the front) are ties: each objective's candidate values are sorted and cut into runs
whose neighbours differ by at most ``tie_tol`` times their magnitude, and every value of a
run stands at the run's least. Round-off (a fixed envelope that comes out as three values
in its last bits) then neither adds designs to the front nor slows it down: an objective
left with one value orders no design and is dropped from the dominance check.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from sweep.errors import UserError

PICK_RULES = ("knee", "lexicographic", "weighted")
#: objective values that agree to this relative tolerance are ties (see the docstring)
TIE_TOL = 1e-9
FEASIBLE = "feasible"
OUTSIDE_WHERE = "outside_where"


@dataclass(frozen=True)
class Objective:
    """An output to maximise or minimise (``sense``: "max" or "min")."""

    name: str
    sense: str

    def minimised(self, values: np.ndarray) -> np.ndarray:
        return -values if self.sense == "max" else values

    @property
    def text(self) -> str:
        return f"{self.sense} {self.name}"


@dataclass
class Front:
    """The non-dominated feasible designs of an atlas and the one a rule picked.

    ``designs``: one entry per front design along the dimension ``design`` (ordered by the
    first objective, best first): every variable of the atlas at that design with its
    attributes, the grid axes as coordinates, ``grid_point`` (the design's flat index in
    the atlas's grid) and ``picked`` (yes at the picked design). ``candidates``: how many
    feasible designs had a value of every objective.
    """

    designs: xr.Dataset
    objectives: tuple[Objective, ...]
    picked: int
    rule: str
    candidates: int
    #: the picked design's sheet (page, PDF or None) where one was asked for
    sheet: tuple | None = None

    @property
    def picked_design(self) -> xr.Dataset:
        """The picked design: every variable at it."""
        return self.designs.isel(design=self.picked)


def objectives(ds: xr.Dataset, maximize=(), minimize=()) -> tuple[Objective, ...]:
    """The objectives, checked: numeric variables with one value per design, each once."""
    wanted = [Objective(str(n), "max") for n in _names(maximize, "maximize")] + \
        [Objective(str(n), "min") for n in _names(minimize, "minimize")]
    if not wanted:
        raise UserError("maximize: give at least one objective (maximize=NAME or "
                        "minimize=NAME)")
    dims = set(ds["status"].dims)
    numeric = sorted(str(v) for v in ds.variables if set(ds[v].dims) <= dims and ds[v].ndim
                     and "flag_meanings" not in ds[v].attrs and ds[v].dtype.kind in "fiu")
    seen = set()
    for o in wanted:
        if o.name in seen:
            raise UserError(f"pareto: {o.name} is given twice; an objective is maximised or "
                            "minimised once")
        seen.add(o.name)
        if o.name not in ds.variables:
            raise UserError(f"pareto: {o.name!r} is not a variable of this atlas; allowed: "
                            + ", ".join(numeric))
        var = ds[o.name]
        if "flag_meanings" in var.attrs:
            raise UserError(f"pareto: {o.name} is a flag ({var.attrs['flag_meanings']}), not "
                            "a value to optimise; filter with --where or --require")
        if not set(var.dims) <= dims:
            raise UserError(f"pareto: {o.name} is a profile over "
                            f"{', '.join(d for d in var.dims if d not in dims)}; an "
                            "objective has one value per design")
        if o.name not in numeric:
            raise UserError(f"pareto: {o.name} is not numeric; allowed: " + ", ".join(numeric))
    return tuple(wanted)


def _names(names, where: str) -> list[str]:
    if names is None:
        return []
    if isinstance(names, str):
        return [names]
    try:
        return [str(n) for n in names]
    except TypeError:
        raise UserError(f"{where}: a name or a list of names of outputs") from None


def pick_weights(rule: str, weights, objectives_: tuple[Objective, ...]) -> np.ndarray | None:
    """The rule's weights, checked: only for ``weighted``, one positive number per
    objective."""
    if rule not in PICK_RULES:
        raise UserError(f"pick: {rule!r} is not a rule; allowed: {', '.join(PICK_RULES)}")
    if rule != "weighted":
        if weights is not None:
            raise UserError("weights: only with pick = weighted")
        return None
    if weights is None:
        raise UserError("weights: pick = weighted needs one weight per objective, e.g. "
                        "--weights 1,2")
    if isinstance(weights, str):
        weights = weights.split(",")
    try:
        w = np.array([float(x) for x in weights])
    except (TypeError, ValueError):
        raise UserError(f"weights: {weights!r} must be numbers, e.g. 1,2") from None
    if len(w) != len(objectives_):
        raise UserError(f"weights: {len(w)} given for {len(objectives_)} objectives; give one "
                        "per objective, in their order")
    if not np.all(np.isfinite(w) & (w >= 0)) or not np.any(w > 0):
        raise UserError("weights: finite numbers >= 0, at least one > 0")
    return w


def classify(ds: xr.Dataset, where: str | None) -> tuple[np.ndarray, list[str]]:
    """Each grid point's reason to be left out (0: feasible), and the reasons' names: the
    status meaning where it is not usable, the requirement it fails (its flag meaning:
    above_impact_speed), or outside_where."""
    from sweep.metadata import usable_mask
    from sweep.selection import evaluate, flag_names

    dims = list(ds["status"].dims)
    names = [FEASIBLE]
    code = np.zeros(ds["status"].shape, np.int16)

    def mark(mask, name):
        nonlocal code
        mask = mask & (code == 0)
        if mask.any():
            if name not in names:
                names.append(name)
            code = np.where(mask, np.int16(names.index(name)), code)

    status = np.asarray(ds["status"].values)
    usable = np.asarray(usable_mask(ds).values)
    for value, meaning in (flag_names(ds["status"]) or {}).items():
        mark(~usable & (status == value), meaning)
    if "requirements" in ds.variables:
        flags = np.asarray(ds["requirements"].transpose(*dims).values)
        for value, meaning in (flag_names(ds["requirements"]) or {}).items():
            if meaning != "met":
                mark(flags == value, meaning)
    if where:
        mark(~np.asarray(evaluate(ds, where).values), OUTSIDE_WHERE)
    return code, names


def values_of(ds: xr.Dataset, objectives_: tuple[Objective, ...]) -> np.ndarray:
    """The objectives at every grid point as (n_points, k), minimised form, C order."""
    dims = list(ds["status"].dims)
    columns = [o.minimised(np.asarray(ds[o.name].broadcast_like(ds["status"])
                                      .transpose(*dims).values, dtype=float).ravel())
               for o in objectives_]
    return np.stack(columns, axis=1)


def tied(values: np.ndarray, tol: float) -> np.ndarray:
    """Each column of ``values`` (finite) with the values that agree to ``tol`` made equal:
    sorted, cut where neighbours differ by more than tol times their magnitude, each run
    at its least value."""
    out = np.array(values, dtype=float, copy=True)
    for j in range(out.shape[1]):
        order = np.argsort(out[:, j], kind="stable")
        v = out[order, j]
        if v.size == 0:
            continue
        gap = np.diff(v) > tol * np.maximum(np.abs(v[1:]), np.abs(v[:-1]))
        runs = np.concatenate(([0], np.cumsum(gap)))
        starts = np.concatenate(([0], np.flatnonzero(gap) + 1))
        out[order, j] = v[starts][runs]
    return out


def front(ds: xr.Dataset, maximize=(), minimize=(), where: str | None = None,
          pick: str = "knee", weights=None, source: str = "",
          tie_tol: float = TIE_TOL) -> Front:
    """The Pareto front of an atlas's feasible designs and the design ``pick`` names;
    objective values that agree to ``tie_tol`` (relative) are ties."""
    from kernels.pareto import non_dominated

    if isinstance(tie_tol, bool) or not isinstance(tie_tol, (int, float)) \
            or not 0.0 <= tie_tol < 1e-2:
        raise UserError(f"tie_tol: a relative tolerance in [0, 0.01), not {tie_tol!r}")
    objectives_ = objectives(ds, maximize, minimize)
    w = pick_weights(pick, weights, objectives_)
    code, reasons = classify(ds, where)
    values = values_of(ds, objectives_)
    feasible = (code.ravel() == 0)
    candidates = np.nonzero(feasible & np.all(np.isfinite(values), axis=1))[0]
    if candidates.size == 0:
        raise UserError("pareto: " + _why_empty(code, reasons, feasible, where))
    compared = tied(values[candidates], float(tie_tol))
    varying = [j for j in range(compared.shape[1]) if compared[:, j].min() < compared[:, j].max()]
    if varying:
        keep = non_dominated(np.ascontiguousarray(compared[:, varying]))
    else:  # every objective one value: every candidate is on the front
        keep = np.arange(candidates.size)
    points = candidates[keep]
    points = points[np.lexsort(values[points].T[::-1])]  # best in the first objective first
    chosen = _pick(values[points], pick, w)
    designs = _selection(ds, points, chosen, objectives_, pick, w, where, len(candidates),
                         source, float(tie_tol))
    return Front(designs, objectives_, chosen, pick, len(candidates))


def _why_empty(code, reasons, feasible, where) -> str:
    counts = np.bincount(code.ravel(), minlength=len(reasons))
    if feasible.any():
        return ("no feasible design has a value of every objective (an output computed "
                "only on request, or not at these designs)")
    told = ", ".join(f"{reasons[k]} {counts[k]:,}" for k in np.argsort(-counts) if counts[k])
    return ("no design is feasible (status ok, requirements met"
            + (", where" if where else "") + f"): {told}")


def scaled(values: np.ndarray) -> np.ndarray:
    """Each objective over the front scaled to 0 at its best and 1 at its worst (0 where
    the front has one value of it)."""
    lo, hi = values.min(axis=0), values.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return (values - lo) / span


def _pick(values: np.ndarray, rule: str, weights) -> int:
    if rule == "lexicographic":
        return int(np.lexsort(values.T[::-1])[0])
    s = scaled(values)
    if rule == "weighted":
        return int(np.argmin(s @ weights))
    return int(np.argmin(np.sqrt(np.sum(s * s, axis=1))))


def _selection(ds, points, chosen, objectives_, rule, weights, where, candidates, source,
               tie_tol):
    dims = list(ds["status"].dims)
    index = np.unravel_index(points, ds["status"].shape)
    sel = ds.isel({d: xr.DataArray(index[j], dims="design") for j, d in enumerate(dims)})
    sel = sel.assign_coords(grid_point=xr.DataArray(points.astype(np.int64), dims="design",
                                                    attrs={"long_name": "flat (C-order) "
                                                           "index of the design in the "
                                                           "atlas's grid", "units": "1"}))
    picked = np.zeros(len(points), np.int8)
    picked[chosen] = 1
    sel["picked"] = xr.DataArray(picked, dims="design", attrs={
        "long_name": f"the design the {rule} rule picks", "units": "1",
        "flag_values": np.array([0, 1], np.int8), "flag_meanings": "no yes"})
    sel.attrs["pareto"] = json.dumps({
        "objectives": [o.text for o in objectives_], "where": where or "",
        "requirements": json.loads(ds["requirements"].attrs.get("requirements", "[]"))
        if "requirements" in ds.variables else [],
        "pick": rule, "weights": None if weights is None else [float(x) for x in weights],
        "picked_design": int(chosen), "front_designs": int(len(points)),
        "candidates": int(candidates), "source_atlas": source, "tie_tol": tie_tol})
    sel.attrs["title"] = f"Pareto front of {ds.attrs.get('title', 'an atlas')}"
    for name in sel.variables:
        sel[name].encoding = {}
        if sel[name].dtype.kind in "OUS":
            # fixed-width chars, not HDF5 vlen strings (xarray #8289; see metadata.annotate)
            sel[name].encoding["dtype"] = "S1"
        elif "flag_meanings" in sel[name].attrs or sel[name].dtype.kind in "iu":
            sel[name].encoding["_FillValue"] = None
    return sel


def figure(ds: xr.Dataset, result: Front, where: str | None = None, degrees: bool = True):
    """The front over the feasible designs' cloud (the first two objectives; a third, if
    any, colours the front), the designs left out in greys named by why, and the pick. The
    front is drawn as its designs, with the staircase of the region they dominate (two
    objectives), not as a line through empty space."""
    from matplotlib.figure import Figure

    from sweep import labels, palettes
    from sweep.charts import made_by

    objectives_ = result.objectives
    if len(objectives_) < 2:
        raise UserError("chart: a front chart needs two objectives or more")
    x, y = objectives_[0].name, objectives_[1].name
    code, reasons = classify(ds, where)
    dims = list(ds["status"].dims)

    def shown(name):
        var = ds[name].broadcast_like(ds["status"]).transpose(*dims)
        return np.asarray(labels.shown_values(var, degrees, ds), dtype=float).ravel()

    xs, ys = shown(x), shown(y)
    code = code.ravel()
    fig = Figure(figsize=(7.5, 6.0), layout="constrained")
    ax = fig.add_subplot()
    finite = np.isfinite(xs) & np.isfinite(ys)
    for k, reason in enumerate(reasons):
        mask = finite & (code == k)
        if not mask.any():
            continue
        if k == 0:
            ax.plot(xs[mask], ys[mask], ".", ms=3, color="#56B4E9", rasterized=True,
                    label=f"feasible ({mask.sum():,})", zorder=2)
        else:
            ax.plot(xs[mask], ys[mask], ".", ms=3, rasterized=True, zorder=1,
                    color=palettes.BLANK_GREYS[(k - 1) % len(palettes.BLANK_GREYS)],
                    label=f"{reason.replace('_', ' ')} ({mask.sum():,})")
    front_ds = result.designs
    fx = np.asarray(labels.shown_values(front_ds[x], degrees, ds), dtype=float)
    fy = np.asarray(labels.shown_values(front_ds[y], degrees, ds), dtype=float)
    if len(objectives_) > 2:
        z = objectives_[2].name
        marks = ax.scatter(fx, fy, c=np.asarray(labels.shown_values(front_ds[z], degrees, ds),
                                                float), s=26, zorder=4, cmap="viridis",
                           edgecolors="k", linewidths=0.4, label=f"front ({len(fx):,})")
        fig.colorbar(marks, ax=ax, label=labels.axis_label(ds, z, degrees))
    else:
        sx, sy = staircase(fx, fy, objectives_[0].sense, objectives_[1].sense)
        ax.plot(sx, sy, "-", color="#0072B2", lw=1.0, zorder=3)
        ax.plot(fx, fy, "o", color="#0072B2", ms=4.5, zorder=4, label=f"front ({len(fx):,})")
    ax.plot(fx[result.picked], fy[result.picked], "*", ms=14, color="#D55E00", zorder=5,
            markeredgecolor="k", label=f"picked ({result.rule})")
    feasible = finite & (code == 0)
    for axis, values in ((ax.set_xlim, xs[feasible]), (ax.set_ylim, ys[feasible])):
        lo, hi = float(values.min()), float(values.max())  # the feasible designs, padded:
        pad = 0.05 * (hi - lo) if hi > lo else 0.05 * max(abs(hi), 1.0)  # not the rest
        axis(lo - pad, hi + pad)
    ax.set_xlabel(f"{labels.axis_label(ds, x, degrees)}, {objectives_[0].sense}imised")
    ax.set_ylabel(f"{labels.axis_label(ds, y, degrees)}, {objectives_[1].sense}imised")
    fig.legend(loc="outside lower center", fontsize=8, ncols=3, frameon=False)
    what = (f"Pareto front of {len(fx):,} designs: "
            + ", ".join(f"{o.sense} {labels.label(ds, o.name)}" for o in objectives_))
    caption = ds.attrs.get("title", "")
    fig.suptitle(labels.wrapped(what, 88) + "\n" + labels.wrapped(
        f"{caption} · {made_by()}" if caption else made_by(), 88), fontsize=9)
    return fig


def describe(result: Front, degrees: bool = False) -> list[tuple[str, str, str, str]]:
    """The picked design's every variable as (name, value, units, long name) rows."""
    from sweep.selection import flag_names

    design = result.picked_design
    rows = []
    for name in list(design.coords) + list(design.data_vars):
        var = design[name]
        if var.ndim:
            continue  # a profile: in the netCDF selection
        value = var.values.item()
        names = flag_names(var)
        units = var.attrs.get("units", "")
        if names is not None:
            text = names.get(int(value), str(value))
        elif isinstance(value, (bytes, str)):
            text = value.decode() if isinstance(value, bytes) else value
        elif isinstance(value, float) and math.isnan(value):
            text = "-"
        else:
            if degrees and units == "rad":
                value, units = math.degrees(value), "deg"
            text = f"{value:.10g}"
        rows.append((str(name), text, "" if units == "1" else units,
                     var.attrs.get("long_name", "")))
    return rows


def staircase(fx: np.ndarray, fy: np.ndarray, x_sense: str, y_sense: str) -> tuple:
    """The boundary of the region a two-objective front dominates: from design to design
    (ordered along x), a step along x then one along y, so that the corners are where no
    design lies and every design is a corner of the region."""
    order = np.argsort(fx, kind="stable")
    px, py = fx[order], fy[order]
    # the region a design dominates reaches towards worse x: where x is minimised it
    # extends to larger x, so from a design the boundary runs across at its y to the next
    # design's x; where x is maximised it runs at the next design's y (up or down first)
    across_first = x_sense == "min"
    sx, sy = [px[0]], [py[0]]
    for i in range(1, len(px)):
        if across_first:
            sx += [px[i], px[i]]
            sy += [py[i - 1], py[i]]
        else:
            sx += [px[i - 1], px[i]]
            sy += [py[i], py[i]]
    return np.array(sx), np.array(sy)
