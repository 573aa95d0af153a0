"""``sweep sensitivity``: variance-based sensitivity of a mechanism's outputs to its inputs,
with failed and infeasible designs counted, not dropped.

The inputs vary over a box (uniform between two values) or by a distribution; the other
parameters are the spec's. A Saltelli design over a scrambled Sobol' sequence (SALib) is
evaluated on the kernel, and SALib's estimators give the first-order and total indices
with bootstrap confidence intervals (Saltelli 2010, Jansen 1999). What a design that does
not exist contributes is said, not hidden:

- the probability of each status and of meeting the requirements (over the base sample,
  with a Wilson interval), and the indices of each of those indicators (a status is a
  function of the inputs like any other: its variance is what the inputs decide of it);
- the indices of each output where it exists: computed on the rows of the Saltelli design
  whose every evaluation has a value, i.e. conditional on the design existing over that
  row, with how many rows were kept.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import xarray as xr

from sweep.errors import UserError

#: base samples at most (the kernel runs samples x (inputs + 2) designs)
MAX_SAMPLES = 2 ** 20
#: kernel columns per task
BLOCK = 4096
#: SALib's distributions and what their two or three numbers mean
DISTRIBUTIONS = {"unif": "low, high", "norm": "mean, standard deviation",
                 "lognorm": "mean and standard deviation of the logarithm",
                 "triang": "low, high, mode as a fraction of (high - low)",
                 "truncnorm": "low, high, mean, standard deviation"}
CONFIDENCE = 0.95


def _distribution(name: str, entry, q):
    """(SALib dist name, bounds) of one input, checked: (low, high) or (dist, numbers...)."""
    from sweep.domains import check_value, domain_text

    where = f"inputs.{name}"
    if isinstance(entry, (tuple, list)) and entry and isinstance(entry[0], str):
        dist, numbers = entry[0], list(entry[1:])
    elif isinstance(entry, (tuple, list)):
        dist, numbers = "unif", list(entry)
    else:
        raise UserError(f"{where}: (low, high) or (distribution, numbers...), not {entry!r}")
    if dist not in DISTRIBUTIONS:
        raise UserError(f"{where}: unknown distribution {dist!r}; allowed: "
                        + ", ".join(DISTRIBUTIONS))
    wanted = {"unif": 2, "norm": 2, "lognorm": 2, "triang": 3, "truncnorm": 4}[dist]
    if len(numbers) != wanted or not all(isinstance(v, (int, float)) and not
                                         isinstance(v, bool) and math.isfinite(v)
                                         for v in numbers):
        raise UserError(f"{where}: {dist} takes {wanted} finite numbers "
                        f"({DISTRIBUTIONS[dist]})")
    numbers = [float(v) for v in numbers]
    if dist in ("unif", "triang", "truncnorm"):
        low, high = numbers[0], numbers[1]
        if not low < high:
            raise UserError(f"{where}: low {low:g} must be below high {high:g}")
        for value in (low, high):
            problem = check_value(q, value)
            if problem is not None:
                raise UserError(f"{where}: {value:g} is outside {name}'s domain "
                                f"({problem})")
    elif numbers[1] <= 0:
        raise UserError(f"{where}: the standard deviation must be > 0")
    if q.choices is not None:
        raise UserError(f"{where}: {name} is categorical ({domain_text(q)}); hold it in "
                        "fixed")
    return dist, numbers


def boxes_of_grid(grid: dict) -> dict:
    """A spec's grid axes as the inputs' boxes: a range's start and stop, a list's least
    and greatest values."""
    inputs = {}
    for name, entry in grid.items():
        if name == "from":
            raise UserError("grid.from: a sensitivity study varies parameters, not the "
                            "designs of an atlas")
        if isinstance(entry, dict) and "start" in entry and "stop" in entry:
            low, high = sorted((entry["start"], entry["stop"]))
        elif isinstance(entry, list) and entry and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in entry):
            low, high = min(entry), max(entry)
        else:
            raise UserError(f"grid.{name}: a sensitivity input needs a numeric range or "
                            "list (a categorical axis is held in fixed)")
        inputs[name] = (float(low), float(high))
    return inputs


def study(document: dict, inputs: dict | None = None, outputs=None, samples: int = 1024,
          seed: int = 0, workers: int | None = None) -> xr.Dataset:
    """The sensitivity of ``outputs`` to ``inputs`` (see the module): a Dataset over
    (quantity, input) with S1, ST and their confidence intervals, the probabilities of
    the statuses and of meeting the requirements, and the method recorded."""
    from SALib.analyze import sobol as sobol_analyze
    from SALib.sample import sobol as sobol_sample

    from sweep import engine, registry, spec
    from sweep.requirements import evaluate as evaluate_requirements

    check_sampling(samples, seed, MAX_SAMPLES)
    document = dict(document)
    grid = dict(document.get("grid") or {})
    if inputs is None:
        inputs = boxes_of_grid(grid)
        grid = {}
    if not isinstance(inputs, dict) or len(inputs) < 2:
        raise UserError("inputs: at least two, {name: (low, high) or (distribution, "
                        "numbers...)}")
    name = document.get("mechanism")
    if name not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {name!r}; allowed: "
                        + ", ".join(registry.names()))
    mech = registry.get(name).declaration
    known = {p.name: p for p in mech.parameters}
    problem = {"num_vars": len(inputs), "names": [], "bounds": [], "dists": []}
    for key, entry in inputs.items():
        if key not in known:
            raise UserError(f"inputs.{key}: not a parameter of {name}; allowed: "
                            + ", ".join(known))
        if key in (document.get("fixed") or {}):
            raise UserError(f"inputs.{key}: also in fixed; an input varies, give it once")
        dist, numbers = _distribution(key, entry, known[key])
        problem["names"].append(key)
        problem["bounds"].append(numbers)
        problem["dists"].append(dist)
    for axis in grid:
        if axis not in inputs:
            raise UserError(f"grid.{axis}: a sensitivity study holds every parameter that "
                            "is not an input at one value; put it in fixed or in inputs")
    # the base: every input at a value inside its box, as a one-point grid (the spec's
    # rules and the outputs a requirement needs are checked as for a run)
    document["grid"] = {key: [_inside(b, d)] for key, b, d in
                        zip(problem["names"], problem["bounds"], problem["dists"])}
    base = spec.validate(document)
    scalar = [o for o in base.scalar_outputs if not mech.output(o).is_flag]
    if outputs is not None:
        outputs = [outputs] if isinstance(outputs, str) else list(outputs)
        for o in outputs:
            if o not in scalar:
                raise UserError(f"outputs: {o!r} is not a numeric output of this study; "
                                "allowed: " + ", ".join(scalar))
        scalar = outputs
    n_eval = samples * (len(inputs) + 2)
    if n_eval * (len(mech.outputs) + 2) * 8 > 4 * 1024 ** 3:
        raise UserError(f"samples: {n_eval:,} designs would not fit in memory; take fewer")
    x = sobol_sample.sample(problem, samples, calc_second_order=False, seed=seed)
    params = engine.point_parameters(base, np.zeros(x.shape[0], dtype=np.int64))
    order = [p.name for p in mech.parameters]
    for k, key in enumerate(problem["names"]):
        params[order.index(key)] = x[:, k]  # a numeric parameter's code is its value
    out, status = evaluate(base, params, workers)
    index = mech.output_index
    meets = None
    if base.requirements:
        code, _ = evaluate_requirements({limit.name: out[getattr(index, limit.name)]
                                         for limit in base.requirements}, base.requirements)
        meets = code == 0
    return _analysis(problem, x, out, status, meets, mech, scalar, samples, seed, base,
                     sobol_analyze)


def check_sampling(samples, seed, most: int) -> None:
    """A quasi-random sample's size (a power of two: the Sobol' points keep their
    balance) and seed, or a UserError naming them."""
    if isinstance(samples, bool) or not isinstance(samples, int) or not \
            2 <= samples <= most or samples & (samples - 1):
        raise UserError(f"samples: a power of two from 2 to {most:,} (Sobol' points keep "
                        f"their balance), not {samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise UserError(f"seed: a whole number, not {seed!r}")


def _inside(bounds, dist) -> float:
    if dist in ("unif", "triang", "truncnorm"):
        return 0.5 * (bounds[0] + bounds[1])
    if dist == "lognorm":
        return float(math.exp(bounds[0]))
    return float(bounds[0])


def evaluate(base, params, workers=None):
    """(outputs, status) of the kernel over every column of ``params``, in blocks on
    threads (the kernels release the GIL)."""
    from sweep.compile_ahead import cores

    n = params.shape[1]
    starts = list(range(0, n, BLOCK))

    def one(start):
        block = np.ascontiguousarray(params[:, start:start + BLOCK])
        out, status, _ = base.kernel(block, base.method_record)
        return out, status

    with ThreadPoolExecutor(workers or cores()) as pool:
        parts = list(pool.map(one, starts))
    return (np.concatenate([p[0] for p in parts], axis=1),
            np.concatenate([p[1] for p in parts]))


def wilson(hits: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval of a probability from ``hits`` of ``n``."""
    p = hits / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def _analysis(problem, x, out, status, meets, mech, outputs, samples, seed, base,
              sobol_analyze):
    d = problem["num_vars"]
    step = d + 2  # SALib's rows per base sample: A, AB_1 .. AB_d, B
    codes = mech.status_codes._asdict()  # {word: code}
    quantities, s1, s1c, st, stc, kept, kinds = [], [], [], [], [], [], []

    def indices(y, name, kind):
        groups = y.reshape(samples, step)
        whole = np.all(np.isfinite(groups), axis=1)
        count = int(whole.sum())
        nan = np.full(d, np.nan)
        if count >= 8 and np.nanvar(groups[whole]) > 0:
            result = sobol_analyze.analyze(problem, groups[whole].ravel(),
                                           calc_second_order=False, conf_level=CONFIDENCE,
                                           seed=seed)
            values = (result["S1"], result["S1_conf"], result["ST"], result["ST_conf"])
        else:  # no design, or a constant: nothing to apportion
            values = (nan, nan, nan, nan)
        quantities.append(name)
        for target, value in zip((s1, s1c, st, stc), values):
            target.append(np.asarray(value, dtype=float))
        kept.append(count)
        kinds.append(kind)

    index = mech.output_index
    for name in outputs:
        indices(out[getattr(index, name)], name, "output where it exists")
    base_rows = np.zeros(status.shape[0], dtype=bool)
    base_rows[0::step] = True  # A and B: the independent base samples
    base_rows[step - 1::step] = True
    probability, low, high, what = [], [], [], []
    for word, code in codes.items():
        hits = status == code
        if not hits[base_rows].any():
            continue
        indices(hits.astype(float), f"P(status = {word})", "indicator of a status")
        n_hits = int(hits[base_rows].sum())
        probability.append(n_hits / base_rows.sum())
        interval = wilson(n_hits, int(base_rows.sum()))
        low.append(interval[0])
        high.append(interval[1])
        what.append(f"status = {word}")
    if meets is not None:
        ok = meets & (status == 0)
        indices(ok.astype(float), "P(meets the requirements)", "indicator of the "
                "requirements met by an ok design")
        n_hits = int(ok[base_rows].sum())
        probability.append(n_hits / base_rows.sum())
        interval = wilson(n_hits, int(base_rows.sum()))
        low.append(interval[0])
        high.append(interval[1])
        what.append("meets the requirements")
    units = {name: mech.output(name).units for name in outputs}
    ds = xr.Dataset(
        {"first_order": (("quantity", "input"), np.array(s1)),
         "first_order_conf": (("quantity", "input"), np.array(s1c)),
         "total": (("quantity", "input"), np.array(st)),
         "total_conf": (("quantity", "input"), np.array(stc)),
         "rows_kept": (("quantity",), np.array(kept, dtype=np.int64)),
         "kind": (("quantity",), np.array(kinds, dtype=object)),
         "probability": (("event",), np.array(probability)),
         "probability_low": (("event",), np.array(low)),
         "probability_high": (("event",), np.array(high))},
        coords={"quantity": quantities, "input": problem["names"], "event": what,
                "quantity_units": (("quantity",), np.array(
                    [units.get(q, "1") for q in quantities], dtype=object))})
    half = f"{CONFIDENCE:.0%} bootstrap confidence half-width"
    attrs = {
        "first_order": ("1", "first-order Sobol' index S1 (Saltelli 2010)"),
        "first_order_conf": ("1", f"S1's {half}"),
        "total": ("1", "total Sobol' index ST (Jansen 1999)"),
        "total_conf": ("1", f"ST's {half}"),
        "rows_kept": ("1", "base samples of the Saltelli design whose every evaluation "
                           "has a value (an output's indices are conditional on them)"),
        "kind": ("1", "what the quantity is: an output where it exists, or the indicator "
                      "of a status or of meeting the requirements"),
        "probability": ("1", "probability over the inputs' distributions, from the base "
                             "samples (A and B)"),
        "probability_low": ("1", f"Wilson {CONFIDENCE:.0%} interval's lower end"),
        "probability_high": ("1", f"Wilson {CONFIDENCE:.0%} interval's upper end"),
    }
    for name, (unit, long_name) in attrs.items():
        ds[name].attrs.update(units=unit, long_name=long_name)
    import json

    ds.attrs.update(
        title=f"Sensitivity of {mech.name}: {', '.join(problem['names'])}",
        mechanism=mech.name,
        method="Saltelli design over a scrambled Sobol' sequence (SALib "
               "sample.sobol, calc_second_order=False), indices by SALib analyze.sobol "
               f"with {CONFIDENCE:.0%} bootstrap intervals; failed designs counted "
               "through status indicators; an output's indices over the rows where it "
               "exists",
        samples=samples, evaluations=int(x.shape[0]), seed=seed,
        outputs=" ".join(outputs),
        inputs=json.dumps({n: [dist, *b] for n, dist, b in
                           zip(problem["names"], problem["dists"], problem["bounds"])}),
        spec=json.dumps(base.spec))
    return ds


def figure(ds: xr.Dataset, quantities=None):
    """Bars with intervals: per quantity, S1 and ST of each input."""
    from matplotlib.figure import Figure

    from sweep import labels, palettes

    names = list(ds.quantity.values) if quantities is None else list(quantities)
    names = [q for q in names if np.isfinite(ds.total.sel(quantity=q).values).any()]
    n = max(1, len(names))
    cols = min(3, n)
    rows = -(-n // cols)
    fig = Figure(figsize=(4.4 * cols + 0.6, 3.0 * rows + 1.0), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    inputs = list(ds.input.values)
    position = np.arange(len(inputs))
    for ax, q in zip(axes, names):
        row = ds.sel(quantity=q)
        ax.bar(position - 0.2, row.first_order.values, 0.38, yerr=row.first_order_conf.values,
               color=palettes.OKABE_ITO[0], capsize=2, label="first order $S_1$")
        ax.bar(position + 0.2, row.total.values, 0.38, yerr=row.total_conf.values,
               color=palettes.OKABE_ITO[1], capsize=2, label="total $S_T$")
        ax.set_xticks(position, [labels.wrapped(labels.label(ds, n), 18) for n in inputs],
                      fontsize=8)
        ax.set_ylim(min(0.0, float(np.nanmin(row.first_order.values)) - 0.05), 1.05)
        title = labels.label(ds, str(q)) if str(q) in ds.attrs.get("outputs", "") else str(q)
        ax.set_title(labels.wrapped(title, 40), fontsize=9)
        ax.set_ylabel("Sobol' index", fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
    for unused in axes[len(names):]:
        unused.set_visible(False)
    handles, texts = axes[0].get_legend_handles_labels()
    fig.legend(handles, texts, loc="outside lower center", ncols=2, frameon=False,
               fontsize=8)
    fig.suptitle(f"Sobol' indices of {ds.attrs['mechanism']} over "
                 f"{', '.join(inputs)} ({ds.attrs['samples']:,} base samples, "
                 f"{ds.attrs['evaluations']:,} designs)", fontsize=9)
    return fig
