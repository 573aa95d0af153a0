"""``sweep tolerance``: one design built to a tolerance, its outputs' distributions.

The design is a spec of one point (``design_spec`` makes it from an atlas's grid point: a
picked design of a front, a row of a query). Tolerances are bands around its values: an
absolute ± in the parameter's units (a link ± 0.1 mm is ``1e-4``), a relative ± (``"5%"``)
or a band of its own (``(0.05, 0.3)``: the material's restitution over the rock band). A
scrambled Sobol' sample (scipy.stats.qmc) fills the box uniformly; the kernel runs every
sample; the result gives each output's quantiles where it exists, with how many samples
have it, and the probability of each status and of meeting the requirements. A band of
zero width leaves its parameter at the design's value, so a zero tolerance reproduces the
design bit for bit.

A design is built with its lengths and speed, not with the limits they were derived from:
an inverted input (``envelope``, ``impact_speed_limit``, the machine's crank speed) is
replaced by the value it gave (``crank_length``, ``omega1``, ``idle_speed``), and a
crank-rocker synthesised for a material (types a, b, c) becomes the four-bar it gave (type
``general`` with its ratios lambda0, lambda2, lambda3: a tolerance of d on lambda2 is
d l1 on the coupler), so that a tolerance acts on what the workshop makes.
"""

from __future__ import annotations

import json
import math
import numpy as np
import xarray as xr

from sweep.errors import UserError

#: samples at most (a power of two: the Sobol' points keep their balance)
MAX_SAMPLES = 2 ** 20
QUANTILES = (0.0, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 1.0)


def _plain(value):
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.generic):
        return value.item()
    return value


def design_spec(ds: xr.Dataset, at: dict) -> dict:
    """The spec document of the design at grid point ``at`` ({dim: index}) of an atlas: its
    recorded spec's fixed values, its grid axes' and a chain's values there, inverted
    inputs replaced by the values they gave."""
    from sweep import registry
    from sweep.selection import flag_names

    spec = json.loads(ds.attrs.get("spec", "{}") or "{}")
    name = ds.attrs.get("mechanism", "")
    if name not in registry.names():
        raise UserError(f"atlas: mechanism {name!r} is not one of this tool's")
    mech = registry.get(name).declaration
    point = ds.isel(at)
    values = dict(spec.get("fixed") or {})
    dims = set(ds["status"].dims)
    for p in mech.parameters:
        if p.name in ds.coords and set(ds[p.name].dims) <= dims:
            var = point[p.name]
            names = flag_names(ds[p.name]) if "flag_meanings" in ds[p.name].attrs else None
            value = _plain(var.values.item() if var.ndim == 0 else var.values)
            values[p.name] = names[int(value)] if names else value
    for p in mech.parameters:
        if p.replaces and p.name in values and p.replaces in ds.data_vars:
            derived = float(point[p.replaces].values)
            if math.isfinite(derived):
                del values[p.name]
                values[p.replaces] = derived
    if name == "crank_rocker" and values.get("type") in ("a", "b", "c") and all(
            f"lambda{k}" in ds.data_vars for k in (0, 2, 3)):
        # the linkage as built: its ratios, no longer a synthesis for a material
        for key in ("R", "largest_link", "base_root", "lambda0", "lambda2", "lambda3"):
            values.pop(key, None)
        values["type"] = "general"
        values.update({f"lambda{k}": float(point[f"lambda{k}"].values) for k in (0, 2, 3)})
    if isinstance(values.get("flywheel_inertia"), str) and "flywheel_inertia" in ds.data_vars:
        values["flywheel_inertia"] = float(point["flywheel_inertia"].values)
    first = next(iter(values))
    document = {"mechanism": name, "title": f"design at {at} of {spec.get('title', name)}",
                "grid": {first: [values.pop(first)]}, "fixed": values,
                "method": spec.get("method") or {}, "outputs": spec.get("outputs") or []}
    if spec.get("requirements"):
        document["requirements"] = spec["requirements"]
    return document


def bands(document: dict, tolerances: dict, mech) -> dict:
    """{parameter: (low, high)} of each tolerance around the design's value, checked."""
    from sweep.domains import check_value

    nominal = {**(document.get("fixed") or {}),
               **{k: v[0] for k, v in (document.get("grid") or {}).items()}}
    known = {p.name: p for p in mech.parameters}
    out = {}
    if not isinstance(tolerances, dict) or not tolerances:
        raise UserError("tolerances: at least one, {parameter: +-value, 'N%' or "
                        "(low, high)}")
    for name, entry in tolerances.items():
        where = f"tolerances.{name}"
        if name not in known:
            raise UserError(f"{where}: not a parameter of {mech.name}; allowed: "
                            + ", ".join(known))
        q = known[name]
        if q.choices is not None:
            raise UserError(f"{where}: {name} is categorical; a tolerance is on a number")
        value = nominal.get(name, q.default)
        if isinstance(entry, (tuple, list)):
            if len(entry) != 2 or not all(isinstance(v, (int, float)) and not
                                          isinstance(v, bool) for v in entry):
                raise UserError(f"{where}: a band is (low, high), two numbers")
            low, high = float(entry[0]), float(entry[1])
        else:
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                raise UserError(f"{where}: the design has no value of {name} to vary; "
                                "give a band (low, high)")
            if isinstance(entry, str) and entry.strip().endswith("%"):
                try:
                    half = abs(float(value)) * float(entry.strip()[:-1]) / 100.0
                except ValueError:
                    raise UserError(f"{where}: {entry!r} is not a percentage") from None
            elif isinstance(entry, (int, float)) and not isinstance(entry, bool):
                half = float(entry)
            else:
                raise UserError(f"{where}: +-value, 'N%' or (low, high), not {entry!r}")
            if not (math.isfinite(half) and half >= 0):
                raise UserError(f"{where}: a tolerance is >= 0, not {entry!r}")
            low, high = float(value) - half, float(value) + half
        if not low <= high:
            raise UserError(f"{where}: low {low:g} must not be above high {high:g}")
        for end in (low, high):
            problem = check_value(q, end)
            if problem is not None:
                raise UserError(f"{where}: {end:g} is outside {name}'s domain ({problem})")
        out[name] = (low, high)
    return out


def study(document: dict, tolerances: dict, samples: int = 4096, seed: int = 0,
          workers: int | None = None) -> xr.Dataset:
    """The design's outputs under its tolerances (see the module)."""
    from scipy.stats import qmc

    from sweep import engine, spec
    from sweep.requirements import evaluate as evaluate_requirements
    from sweep.sensitivity_study import wilson, check_sampling, evaluate

    check_sampling(samples, seed, MAX_SAMPLES)
    for key, entry in (document.get("grid") or {}).items():
        if not (isinstance(entry, list) and len(entry) == 1):
            raise UserError(f"grid.{key}: a design is one point; give one value")
    base = spec.validate(document)
    mech = base.mechanism
    box = bands(document, tolerances, mech)
    varied = [k for k, (low, high) in box.items() if high > low]
    params = engine.point_parameters(base, np.zeros(samples, dtype=np.int64))
    nominal = params[:, :1].copy()
    order = [p.name for p in mech.parameters]
    if varied:
        unit = qmc.Sobol(len(varied), scramble=True, seed=seed).random_base2(
            int(math.log2(samples)))
        scaled = qmc.scale(unit, [box[k][0] for k in varied], [box[k][1] for k in varied])
        for j, key in enumerate(varied):
            params[order.index(key)] = scaled[:, j]
    for key, (low, high) in box.items():
        if high == low:
            params[order.index(key)] = low
            nominal[order.index(key)] = low

    out, status = evaluate(base, params, workers)
    own_out, own_status, _ = base.kernel(np.ascontiguousarray(nominal), base.method_record)
    index = mech.output_index
    names = [o for o in base.scalar_outputs if not mech.output(o).is_flag]
    values = np.array([out[getattr(index, o)] for o in names])
    with np.errstate(all="ignore"):
        quantiles = np.array([np.nanquantile(v, QUANTILES) if np.isfinite(v).any()
                              else np.full(len(QUANTILES), np.nan) for v in values])
    events, probability, low, high = [], [], [], []

    def event(what, hits):
        count = int(hits.sum())
        if count:
            events.append(what)
            probability.append(count / samples)
            interval = wilson(count, samples)
            low.append(interval[0])
            high.append(interval[1])

    codes = mech.status_codes._asdict()  # {word: code}
    for word, code in codes.items():
        event(f"status = {word}", status == code)
    if base.requirements:
        code, _ = evaluate_requirements({limit.name: out[getattr(index, limit.name)]
                                         for limit in base.requirements}, base.requirements)
        event("meets the requirements", (code == 0) & (status == 0))
    ds = xr.Dataset(
        {"quantiles": (("output", "probability_level"), quantiles),
         "nominal": (("output",), np.array([own_out[getattr(index, o), 0] for o in names])),
         "samples_with_value": (("output",), np.isfinite(values).sum(axis=1)),
         "probability": (("event",), np.array(probability)),
         "probability_low": (("event",), np.array(low)),
         "probability_high": (("event",), np.array(high)),
         "band_low": (("parameter",), np.array([box[k][0] for k in box])),
         "band_high": (("parameter",), np.array([box[k][1] for k in box]))},
        coords={"output": names, "probability_level": list(QUANTILES), "event": events,
                "parameter": list(box),
                "output_units": (("output",), np.array([mech.output(o).units for o in names],
                                                       dtype=object))})
    for name, (unit, long_name) in {
            "quantiles": ("", "the output's quantiles over the samples where it exists"),
            "nominal": ("", "the output at the design itself"),
            "samples_with_value": ("1", "samples where the output has a value"),
            "probability": ("1", "share of the samples"),
            "probability_low": ("1", "Wilson 95% interval's lower end"),
            "probability_high": ("1", "Wilson 95% interval's upper end"),
            "band_low": ("", "the band's lower end, in the parameter's units"),
            "band_high": ("", "the band's upper end, in the parameter's units")}.items():
        ds[name].attrs.update(units=unit or "see output_units", long_name=long_name)
    ds.attrs.update(
        title=f"Tolerance analysis of a {mech.name} design", mechanism=mech.name,
        method="scrambled Sobol' sample (scipy.stats.qmc) uniform over each band, the "
               "kernel at every sample; quantiles over the samples where an output exists "
               "(numpy's linear interpolation)",
        samples=samples, seed=seed, own_status=next(w for w, c in codes.items() if c == int(own_status[0])),
        spec=json.dumps(base.spec), tolerances=json.dumps(
            {k: _plain(v) if not isinstance(v, (tuple, list)) else list(v)
             for k, v in tolerances.items()}))
    return ds


def figure(ds: xr.Dataset):
    """Each output's spread: the 1-99 % and 5-95 % ranges and the median, relative to the
    design's own value; the statuses' shares beside."""
    from matplotlib.figure import Figure

    from sweep import labels, palettes

    names = [str(o) for o in ds.output.values
             if np.isfinite(ds.quantiles.sel(output=o).values).any()
             and np.isfinite(ds.nominal.sel(output=o)) and float(ds.nominal.sel(output=o))]
    fig = Figure(figsize=(9.0, 1.2 + 0.34 * max(1, len(names))), layout="constrained")
    ax, bars = fig.subplots(1, 2, width_ratios=(3, 1))
    for y, name in enumerate(names):
        q = ds.quantiles.sel(output=name).values / float(ds.nominal.sel(output=name)) - 1
        ax.plot([q[1] * 100, q[7] * 100], [y, y], color=palettes.OKABE_ITO[4], lw=3)
        ax.plot([q[2] * 100, q[6] * 100], [y, y], color=palettes.OKABE_ITO[0], lw=6)
        ax.plot(q[4] * 100, y, "|", color="black", ms=12)
    ax.set_yticks(range(len(names)), [labels.label(ds, n) for n in names], fontsize=8)
    ax.axvline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("change from the design's value [%]  (thin: 1-99 %, thick: 5-95 %, "
                  "tick: median)", fontsize=8)
    ax.invert_yaxis()
    ax.grid(True, axis="x", alpha=0.3)
    words = [str(e) for e in ds.event.values]
    bars.barh(range(len(words)), ds.probability.values * 100, height=0.5,
              xerr=[np.clip((ds.probability - ds.probability_low).values, 0, None) * 100,
                    np.clip((ds.probability_high - ds.probability).values, 0, None) * 100],
              color=palettes.OKABE_ITO[1], capsize=2)
    bars.set_yticks(range(len(words)), words, fontsize=8)
    bars.invert_yaxis()
    bars.set_xlabel("share of the samples [%]", fontsize=8)
    bars.set_xlim(0, 100)
    tol = json.loads(ds.attrs["tolerances"])
    fig.suptitle(labels.wrapped(f"{ds.attrs['title']}: " + ", ".join(
        f"{k} {'±' + str(v) if not isinstance(v, list) else v}" for k, v in tol.items())
        + f" ({ds.attrs['samples']:,} samples)", 110), fontsize=9)
    return fig
