"""A mechanism's declaration in words: what ``sweep parameters NAME`` prints."""

from __future__ import annotations

import textwrap

import numpy as np

from kernels.declaration import Mechanism, Quantity, used_when_text
from sweep.selection import flag_names
from sweep.domains import domain_text
from sweep.spec import is_used


def units_text(units: str) -> str:
    return "-" if units in ("", "1") else units


def _default(q: Quantity) -> str:
    if q.default is None:
        return "-"
    return f'"{q.default}"' if isinstance(q.default, str) else f"{q.default:.6g}" \
        if isinstance(q.default, float) else str(q.default)


def _quantity_rows(items) -> list[str]:
    rows = []
    width = max((len(q.name) for q in items), default=4)
    for q in items:
        meaning = q.long_name + (f"; used only with {used_when_text(q)}" if q.used_when
                                 else "")
        head = (f"  {q.name:{width}s}  [{units_text(q.units)}]  default {_default(q)};"
                f" allowed: {domain_text(q)}")
        rows.append(head)
        rows.extend(textwrap.wrap(meaning, 92, initial_indent=" " * (width + 4),
                                  subsequent_indent=" " * (width + 4)))
    return rows


def mechanism_text(mech: Mechanism) -> str:
    """Parameters, method keys, outputs and statuses of a mechanism, with units."""
    lines = [f"{mech.name}: {mech.title}",
             *textwrap.wrap(f"source: {mech.references}", 96, subsequent_indent="  "),
             "", "parameters (grid axes or [fixed] values):"]
    lines += _quantity_rows(mech.parameters)
    if mech.method:
        lines += ["", "method keys ([method]):"]
        lines += _quantity_rows(mech.method)
    width = max(len(o.name) for o in mech.outputs + mech.profiles)
    lines += ["", "outputs (all but the ones on request, unless the spec lists them in "
                  "outputs = [...]):"]
    for o in mech.outputs:
        kind = (" flag: " + ", ".join(o.flags)) if o.is_flag else ""
        asked = " (on request)" if o.on_request else ""
        lines.append(f"  {o.name:{width}s}  [{units_text(o.units)}]{asked}  {o.long_name}"
                     f"{kind}")
    if mech.profiles:
        lines += ["", f"profiles over {mech.profile_dim.name} "
                      f"[{units_text(mech.profile_dim.units)}] (set method.profile_points):"]
        for o in mech.profiles:
            lines.append(f"  {o.name:{width}s}  [{units_text(o.units)}]  {o.long_name}")
    usable = ", ".join(("ok",) + mech.usable)
    lines += [""] + textwrap.wrap(f"statuses: {', '.join(mech.status)} (those with design "
                                  f"values: {usable})", 96, subsequent_indent="  ")
    return "\n".join(lines)


# ---------------------------------------------------------------- sweep info

def value_text(value, units: str) -> str:
    """A value with its units; an angle also in degrees: '0.5236 rad (30°)'."""
    if isinstance(value, str):
        return f'"{value}"'
    if value is None:
        return "-"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        return str(value)
    text = f"{value:.6g}" + ("" if units in ("", "1") else f" {units}")
    if units == "rad" and value != 0:
        text += f" ({np.degrees(value):.4g}°)"
    return text


def _axis_text(ds, name: str) -> str:
    values = ds[name].values
    units = ds[name].attrs.get("units", "")
    if values.dtype.kind in "OUS":
        return ", ".join(f'"{v.decode() if isinstance(v, bytes) else v}"' for v in values)
    if values.size <= 6:
        text = ", ".join(f"{v:.6g}" for v in values)
    else:
        steps = np.diff(values)
        if np.allclose(steps, steps[0], rtol=1e-9, atol=0):
            spacing = f", step {steps[0]:.4g}"
        elif np.all(values > 0) and np.allclose(np.diff(np.log(values)), np.log(values[1] /
                                                                               values[0])):
            spacing = f", ratio {values[1] / values[0]:.4g} (log-spaced)"
        else:
            spacing = ", uneven"
        text = f"{values[0]:.6g} to {values[-1]:.6g}, {values.size} values{spacing}"
    if units == "rad" and values.size:
        text += f" ({np.degrees(values[0]):.4g}° to {np.degrees(values[-1]):.4g}°)"
    return text


def _range_text(var) -> str:
    if var.dtype.kind in "OUS":  # words: how many of each
        words, counts = np.unique([v.decode() if isinstance(v, bytes) else str(v)
                                   for v in np.asarray(var.values).ravel()],
                                  return_counts=True)
        return ", ".join(f'"{w}" {n:,}' for w, n in zip(words, counts))
    values = np.asarray(var.values, dtype=float)
    finite = values[np.isfinite(values)]
    missing = values.size - finite.size
    if not finite.size:
        return "no values"
    lo, hi = finite.min(), finite.max()
    units = var.attrs.get("units", "")
    text = f"{lo:.4g}" if lo == hi else f"{lo:.4g} to {hi:.4g}"
    if units == "rad":
        text += (f" ({np.degrees(lo):.4g}°)" if lo == hi else
                 f" ({np.degrees(lo):.4g}° to {np.degrees(hi):.4g}°)")
    if missing:
        text += f"; no value at {missing:,} of {values.size:,}"
    return text


def _flag_counts(var) -> str:
    values = np.asarray(var.values)
    parts = []
    for code, meaning in flag_names(var).items():
        n = int((values == code).sum())
        if n:
            share = 100 * n / values.size
            parts.append(f"{meaning} {n:,} ("
                         + ("< 0.1" if share < 0.05 else f"{share:.1f}") + " %)")
    return ", ".join(parts)


def atlas_text(ds, path: str, mech: Mechanism | None) -> str:
    """What ``sweep info`` prints: what a design was computed with, in words and units, and
    what the atlas holds (ranges per variable, counts per flag), then its provenance."""
    import json

    spec = json.loads(ds.attrs.get("spec", "{}"))
    method = json.loads(ds.attrs.get("method", "{}"))
    grid_dims = list(ds["status"].dims)
    sizes = " x ".join(f"{d} {ds.sizes[d]}" for d in grid_dims)
    n_points = int(np.prod([ds.sizes[d] for d in grid_dims]))
    lines = [f"{path}: {ds.attrs.get('title', '')}",
             f"mechanism: {ds.attrs.get('mechanism', '?')}"
             + (f" ({mech.title})" if mech else "")]
    lines += textwrap.wrap(f"source: {ds.attrs.get('references', '?')}", 96,
                           subsequent_indent="  ")
    lines += ["", f"grid: {n_points:,} points ({sizes})"]
    width = max([len(str(n)) for n in ds.coords] + [len(str(n)) for n in ds.data_vars]
                + [len(k) for k in spec.get("fixed", {})] + [len(k) for k in method] + [8])
    for name in grid_dims:
        attrs = ds[name].attrs
        lines.append(f"  {name:{width}s}  [{units_text(attrs.get('units', ''))}]  "
                     f"{_axis_text(ds, name)}")
        lines.extend(textwrap.wrap(attrs.get("long_name", ""), 92,
                                   initial_indent=" " * (width + 4),
                                   subsequent_indent=" " * (width + 4)))
    for name in ds.coords:
        if name in grid_dims:
            continue
        units = units_text(ds[name].attrs.get("units", ""))
        if ds[name].dims == (name,):
            lines.append(f"  {name:{width}s}  [{units}]  {_axis_text(ds, name)} (profile axis)")
        else:  # what each design of a chained sweep sets, or where it came from
            lines.append(f"  {name:{width}s}  [{units}]  {_range_text(ds[name])} (per "
                         f"{', '.join(map(str, ds[name].dims))})")
    if "pareto" in ds.attrs:  # a front written by sweep pareto
        front = json.loads(ds.attrs["pareto"])
        lines += textwrap.wrap(
            f"Pareto front of {front.get('candidates', 0):,} feasible designs of "
            f"{front.get('source_atlas') or 'an atlas'}: "
            + ", ".join(front.get("objectives", []))
            + (f"; where {front['where']}" if front.get("where") else "")
            + (f"; requirements {', '.join(front['requirements'])}"
               if front.get("requirements") else "")
            + f"; picked ({front.get('pick')}): design {front.get('picked_design')}", 96,
            initial_indent="  ", subsequent_indent="    ")
    if "source_atlas" in ds.attrs:
        source = json.loads(ds.attrs["source_atlas"])
        lines += textwrap.wrap(
            f"designs from: {source.get('atlas', '?')} ({source.get('title', '')}; "
            f"{source.get('mechanism', '?')}, code {source.get('code_version', '?')})", 96,
            initial_indent="  ", subsequent_indent="    ")
    given = {k: {v} for k, v in spec.get("fixed", {}).items()}
    for name in [*grid_dims, *(c for c in ds.coords if c not in grid_dims
                               and set(ds[c].dims) <= set(grid_dims))]:
        values = ds[name].values
        given[name] = {v.decode() if isinstance(v, bytes) else v for v in values.tolist()}
    fixed, unused = [], []
    for name, value in spec.get("fixed", {}).items():
        q = mech.parameter(name) if mech and name in {p.name for p in mech.parameters} \
            else None
        if q is not None and not is_used(mech, q, "", given):
            unused.append(f"{name} (used only with {used_when_text(q)})")
            continue
        units = q.units if q else ""
        long_name = q.long_name if q else ""
        fixed.append(f"  {name:{width}s}  {value_text(value, units)}")
        fixed.extend(textwrap.wrap(long_name, 92, initial_indent=" " * (width + 4),
                                   subsequent_indent=" " * (width + 4)))
    for q in (mech.parameters if mech else ()):  # not recorded: not used by this design
        if q.name not in spec.get("fixed", {}) and q.name not in grid_dims and q.used_when:
            unused.append(f"{q.name} (used only with {used_when_text(q)})")
    if fixed:
        lines += ["", "fixed parameters:"] + fixed
    if unused:
        lines += textwrap.wrap("not used by this design: " + ", ".join(unused), 96,
                               initial_indent="  ", subsequent_indent="    ")
    keys = {m.name: m for m in (mech.method if mech else ())}
    method_given = {f"method.{k}": {v} for k, v in method.items()}
    options, idle = [], []
    for name, value in method.items():
        if name == "model":
            continue
        q = keys.get(name)
        if q is not None and not is_used(mech, q, "method.", method_given):
            idle.append(name)
            continue
        options.append(f"  {name:{width}s}  {value_text(value, q.units if q else '')}")
        options.extend(textwrap.wrap(q.long_name if q else "", 92,
                                     initial_indent=" " * (width + 4),
                                     subsequent_indent=" " * (width + 4)))
    idle += [m.name for m in (mech.method if mech else ())
             if m.name not in method and m.used_when]
    lines += ["", "method:"] + options
    if idle:
        lines.append("  not used by this method: " + ", ".join(idle))
    if "model" in method:
        lines += textwrap.wrap(f"model: {method['model']}", 96, initial_indent="  ",
                               subsequent_indent="    ")
    if "requirements" in ds.data_vars:
        limits = json.loads(ds["requirements"].attrs.get("requirements", "[]"))
        lines += ["", "requirements (every design is checked; `requirements` names the limit "
                      "it fails by the most):"]
        lines += [f"  {text}" for text in limits]
        lines.append("  " + _flag_counts(ds["requirements"]))
    status = ds["status"]
    lines += ["", "status: " + _flag_counts(status)]
    usable = status.attrs.get("usable_flags")
    if usable and usable != "ok":
        lines.append(f"  statuses with design values: {', '.join(usable.split())}")
    lines += ["", "outputs (range over all points; NaN where a value does not exist):"]
    for name in ds.data_vars:
        if name in ("status", "requirements"):
            continue
        var = ds[name]
        units = units_text(var.attrs.get("units", ""))
        extra = [d for d in var.dims if d not in grid_dims]
        head = f"  {name:{width}s}  [{units}]  "
        body = (_flag_counts(var) if "flag_meanings" in var.attrs else _range_text(var))
        if extra:
            body += f" (profile over {', '.join(extra)})"
        lines += textwrap.wrap(head + body, 100, subsequent_indent=" " * (width + 4))
        lines += textwrap.wrap(var.attrs.get("long_name", ""), 92,
                               initial_indent=" " * (width + 4),
                               subsequent_indent=" " * (width + 4))
    run = spec.get("run", {})
    chunks = ds["status"].encoding.get("chunksizes")
    if run:
        lines += ["", f"run: chunk {run.get('chunk')} points per task"
                  + (f" (blocks of {' x '.join(map(str, chunks))})" if chunks else "")
                  + f", compression level {run.get('compress_level')}"]
    versions = json.loads(ds.attrs.get("package_versions", "{}"))
    lines += [f"code version: {ds.attrs.get('code_version', '?')}",
              *textwrap.wrap("packages: " + ", ".join(f"{k} {v}" for k, v in versions.items()),
                             96, subsequent_indent="  "),
              f"history: {ds.attrs.get('history', '?')}"]
    return "\n".join(lines)


def boundaries_text(ds, path: str) -> str:
    """A boundaries file (``sweep boundaries``) in words: what was refined, how far, and its
    crossings grouped by the two meanings they separate, with what explains them."""
    import collections

    var = ds.attrs.get("variable", "?")
    names = flag_names(ds["side_below"]) or {}
    below = [names.get(int(c), str(c)) for c in ds["side_below"].values]
    above = [names.get(int(c), str(c)) for c in ds["side_above"].values]
    axis = ds["edge_axis"].values.astype(str)
    explanation = ds["explanation"].values.astype(str)
    indicator = ds["indicator"].values.astype(str)
    value = ds["indicator_value"].values
    n = ds.sizes["crossing"]
    lines = [*textwrap.wrap(f"{path}: {ds.attrs.get('title', f'boundaries of {var}')}", 96,
                            subsequent_indent="  "),
             f"{n:,} crossings, each to {float(ds.attrs.get('tolerance', np.nan)):g} x "
             f"max(1, |x|) in its axis's units"
             + (f" (largest reached: {float(ds['accuracy'].max()):.2g})" if n else ""),
             f"{int(ds.attrs.get('rounds', 0))} bisection rounds, "
             f"{int(ds.attrs.get('kernel_evaluations', 0)):,} kernel evaluations; code "
             f"{ds.attrs.get('code_version', '?')} (atlas: "
             f"{ds.attrs.get('source_code_version', '?')})"]
    if not n:
        lines.append(f"{var} is the same at every two neighbouring grid points")
        return "\n".join(lines)
    groups = collections.defaultdict(list)
    for i in range(n):
        groups[" / ".join(sorted((below[i], above[i])))].append(i)
    lines += ["", "crossings by the meanings they separate:"]
    for pair, rows in sorted(groups.items(), key=lambda item: -len(item[1])):
        along = collections.Counter(axis[rows])
        lines.append(f"  {len(rows):6,}  {pair}  (along "
                     + ", ".join(f"{a} {c:,}" for a, c in along.most_common()) + ")")
        reasons = collections.Counter(explanation[rows]).most_common()
        for text, count in reasons:
            lead = f"({count:,}) " if len(reasons) > 1 else ""
            lines += textwrap.wrap(lead + text, 88, initial_indent=" " * 10,
                                   subsequent_indent=" " * 10)
        named = [r for r in rows if indicator[r] and np.isfinite(value[r])]
        if named:
            lines.append(f"          {indicator[named[0]]} at the crossings: "
                         f"{np.min(value[named]):.6g} to {np.max(value[named]):.6g}")
    continuity = flag_names(ds["continuity"]) or {}
    counts = collections.Counter(continuity.get(int(c), str(c))
                                 for c in ds["continuity"].values)
    lines += ["", "the outputs across them: "
              + ", ".join(f"{k} {v:,}" for k, v in counts.most_common())]
    more = int((ds["edge_crossings"].values == 1).sum())
    if more:
        lines.append(f"{more:,} crossings lie on edges with more crossings than were followed")
    return "\n".join(lines)
