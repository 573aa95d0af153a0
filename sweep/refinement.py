"""Design limits as curves: every boundary of a flag variable of an atlas, refined.

A grid says which designs work only to its spacing. For every pair of neighbouring grid
points whose flag (``status``, ``regime`` ...) differs along a numeric axis, the crossing on
that edge is bisected, the other axes held at the edge's grid values, until its bracket is
at most 2 tol max(1, |x|) wide: the crossing x is then known to tol max(1, |x|) in the
axis's own units. A midpoint with a third meaning splits the bracket in two, and both
crossings are followed. Every round evaluates the midpoints of all open brackets at once,
in blocks of ``[run] chunk`` points on a thread pool, through the same kernel entry point
and method record as the sweep: the cost is (crossings) x (rounds), not the volume of a
refined grid, and each point is computed on its own, so the result does not depend on the
chunk size or the thread count. After each round the brackets are kept in a folder beside
the target, so an interrupted run resumes from its last round.

The crossings are written as a companion netCDF (one row per crossing, CF-annotated, with
the source atlas's spec and code version). Each row says what explains it: the
mechanism's declared reason with the value of its indicator output where the cause is
known (``kernels.declaration.Boundary``: the crank-rocker's gamma bound, the pendulum's
R_crit, a balancer resonance), and always what the outputs do across the final bracket:
continuous, a jump (the model's map is discontinuous there: a border collision, the onset
of chatter), or values that exist on one side only.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import json
import math
import os
import shutil
import sys
from pathlib import Path

import numpy as np

from sweep import engine
from sweep.errors import UserError
from sweep.metadata import (CONVENTIONS, code_version, flag_codes, history_line,
                            package_versions)
from sweep.selection import flag_names
from sweep.store import atomic, check_target, open_partial, partial_dir

#: a relative change of the outputs across the final bracket above this is a jump
JUMP = 1e-3
#: what the outputs do across a crossing, as a flag of the companion file
CONTINUITY = {"continuous": 0, "outputs_jump": 1, "values_on_one_side_only": 2,
              "no_values": 3}
CONTINUITY_TEXT = {
    0: "the outputs are continuous across it (a threshold or bifurcation)",
    1: "the outputs jump across it: the model's map is discontinuous there (a border "
       "collision or the onset of chatter)",
    2: "design values exist on one side only",
    3: "neither side has design values",
}
#: bisection rounds at most (a float64 bracket cannot halve more often than this)
MAX_ROUNDS = 1100
#: crossings followed per grid edge: where the flag alternates faster than any grid (the
#: blade's regimes at R > 0), following every split would never end
MAX_PER_EDGE = 4


class Request:
    """What to refine: the atlas's sweep rebuilt from its recorded spec, the flag variable,
    its grid values and the tolerance; every check runs before any compute."""

    def __init__(self, ds, var: str, tol: float):
        from sweep import registry, spec

        flags = [name for name in ds.data_vars if "flag_meanings" in ds[name].attrs]
        if var not in ds.data_vars:
            raise UserError(f"var: {var!r} is not a variable of this atlas; flag variables: "
                            + ", ".join(flags))
        if var not in flags:
            raise UserError(f"var: {var!r} is not a flag variable (it has values, not "
                            "meanings); allowed: " + ", ".join(flags))
        if not (isinstance(tol, (int, float)) and math.isfinite(tol) and 0 < tol < 1):
            raise UserError(f"tol: must be a number > 0 and < 1, got {tol}")
        if ds.attrs.get("mechanism") not in registry.names() or "spec" not in ds.attrs:
            raise UserError("atlas: no recorded spec of a known mechanism to run again")
        try:
            document = json.loads(ds.attrs["spec"])
        except ValueError:
            raise UserError("atlas: its recorded spec is not readable JSON") from None
        # the recorded grid against the atlas's own, from the axis specifications alone:
        # a spec changed after the run must not make a grid of another size
        shape = spec.grid_shape(document)
        if shape != tuple(ds[var].shape[:len(shape or ())]) or shape is None:
            raise UserError(f"atlas: its recorded spec's grid {shape} is not the grid of its "
                            f"variables {tuple(ds['status'].shape)}: the file was changed "
                            "after the run")
        try:
            self.sweep = spec.validate(document)
        except (UserError, ValueError) as err:
            raise UserError(f"atlas: its recorded spec does not validate here ({err})") \
                from None
        self.mechanism = self.sweep.mechanism
        # only the flags and scalar outputs are read: no profiles (the scalars do not
        # depend on them; tested), so a block's memory does not grow with their length
        self.method = self.sweep.method_record
        if "profile_points" in self.method._fields:
            self.method = self.method._replace(profile_points=0)
        self.var = var
        self.tol = float(tol)
        dims = [axis.name for axis in self.sweep.axes]
        if list(ds[var].dims) != dims:
            raise UserError(f"var: {var!r} is not over the grid axes ({', '.join(dims)})")
        self.flags = np.asarray(ds[var].values, dtype=np.int8)
        self.flag_attrs = {k: ds[var].attrs[k] for k in ("flag_values", "flag_meanings")}
        self.meaning = flag_names(ds[var])
        self.axes = [d for d, axis in enumerate(self.sweep.axes)
                     if not axis.parameter.categorical and not axis.is_design
                     and axis.values.size > 1]
        if not self.axes:
            raise UserError("atlas: no numeric grid axis with two or more values, so no "
                            "edge to refine")
        # axes the kernel only rescales (the pendulum's omega1, l2): where the flag is the
        # same at each of their values, the boundaries are too; refined once, then repeated
        self.scale_axes = [d for d in self.axes
                           if self.sweep.axes[d].name in self.mechanism.whole_axes
                           and bool(np.all(self.flags == np.take(self.flags, [0], axis=d)))]
        self.source = {"title": ds.attrs.get("title", ""), "spec": ds.attrs["spec"],
                       "code_version": ds.attrs.get("code_version", "")}

    def flag_of(self, out: np.ndarray, status: np.ndarray) -> np.ndarray:
        """The variable's int8 codes from a kernel result, as the atlas stores them."""
        if self.var == "status":
            return status.astype(np.int8)
        if self.var == "requirements":  # from the outputs, as the run evaluated them
            from sweep.requirements import evaluate

            index = self.mechanism.output_index
            limits = self.sweep.requirements
            return evaluate({limit.name: out[getattr(index, limit.name)] for limit in limits},
                            limits)[0]
        return flag_codes(out[getattr(self.mechanism.output_index, self.var)],
                          self.mechanism.output(self.var))


def grid_edges(request: Request) -> dict[str, np.ndarray]:
    """The brackets of every grid edge whose flag differs: the axis, the flat index of the
    edge's lower-index grid point, the two values (ascending) and the flags at them."""
    flags, shape = request.flags, request.flags.shape
    strides = np.cumprod((1,) + shape[::-1])[::-1][1:]
    parts = []
    for d in request.axes:
        n = shape[d]
        a = np.take(flags, np.arange(n - 1), axis=d)
        b = np.take(flags, np.arange(1, n), axis=d)
        lower = np.ravel_multi_index(np.nonzero(a != b), shape).astype(np.int64)
        i = (lower // strides[d]) % n
        values = request.sweep.axes[d].values.astype(float)
        x0, x1 = values[i], values[i + 1]
        f0, f1 = flags.ravel()[lower], flags.ravel()[lower + strides[d]]
        swap = x0 > x1  # a descending axis: brackets run from the smaller value
        parts.append(dict(axis=np.full(lower.size, d, np.int16), point=lower,
                          lo=np.where(swap, x1, x0), hi=np.where(swap, x0, x1),
                          below=np.where(swap, f1, f0).astype(np.int8),
                          above=np.where(swap, f0, f1).astype(np.int8)))
    edges = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    for d in request.scale_axes:  # refined at the axis's first value only (_replicate)
        edges = {k: v[(edges["point"] // strides[d]) % shape[d] == 0] for k, v in edges.items()}
    edges["edge"] = np.arange(edges["point"].size)
    edges["done"] = np.zeros(edges["point"].size, bool)
    edges["more"] = np.zeros(edges["point"].size, bool)  # a crossing was left unfollowed
    return edges


def evaluate(sweep, params: np.ndarray, workers: int, method=None):
    """The kernel at the columns of ``params`` (with ``method``, default the sweep's), in
    blocks of ``[run] chunk`` points on ``workers`` threads (the kernels release the GIL):
    (outputs, status)."""
    method = sweep.method_record if method is None else method
    n = params.shape[1]
    # small batches of an expensive kernel still use every thread (as a sweep's blocks do)
    step = max(1, min(sweep.run.chunk, -(-n // engine.MIN_BLOCKS)))
    spans = [(a, min(n, a + step)) for a in range(0, n, step)]
    n_out = len(sweep.mechanism.outputs)
    if not spans:
        return np.empty((n_out, 0)), np.empty(0, np.int8)

    def one(span):
        out, status, _ = sweep.kernel(np.ascontiguousarray(params[:, span[0]:span[1]]),
                                      method)
        return out, status

    with cf.ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        results = list(pool.map(one, spans))
    return (np.concatenate([r[0] for r in results], axis=1),
            np.concatenate([r[1] for r in results]))


def _parameters(request: Request, edges: dict, which: np.ndarray, x: np.ndarray):
    """Parameter matrix of the brackets ``which`` with their edge axis at ``x``."""
    params = engine.point_parameters(request.sweep, edges["point"][which])
    row_of_axis = np.array([-1 if axis.is_design  # never an edge's axis
                            else request.mechanism.parameters.index(axis.parameter)
                            for axis in request.sweep.axes])
    params[row_of_axis[edges["axis"][which]], np.arange(which.size)] = x
    return params


def closed(edges: dict, tol: float) -> np.ndarray:
    """Brackets narrow enough (or that float64 cannot halve again)."""
    lo, hi = edges["lo"], edges["hi"]
    mid = lo + 0.5 * (hi - lo)
    scale = np.maximum(1.0, np.maximum(np.abs(lo), np.abs(hi)))
    return (hi - lo <= 2.0 * tol * scale) | (mid <= lo) | (mid >= hi)


def bisect_round(request: Request, edges: dict, workers: int) -> tuple[dict, int]:
    """One round: every open bracket's midpoint evaluated, each bracket halved; a midpoint
    with a third meaning splits its bracket into two (up to MAX_PER_EDGE crossings an edge;
    beyond, the bracket follows its lower side's crossing and the edge is marked as having
    more). Returns (edges, evaluations)."""
    edges["done"] |= closed(edges, request.tol)
    open_ = np.flatnonzero(~edges["done"])
    if not open_.size:
        return edges, 0
    lo, hi = edges["lo"][open_], edges["hi"][open_]
    mid = lo + 0.5 * (hi - lo)
    flag = request.flag_of(*evaluate(request.sweep, _parameters(request, edges, open_, mid),
                                     workers, request.method))
    below, above = edges["below"][open_], edges["above"][open_]
    to_lo = flag == below
    to_hi = ~to_lo & (flag == above)
    third = ~to_lo & ~to_hi
    count = np.bincount(edges["edge"], minlength=edges["edge"].max() + 1)
    capped = []
    for j in np.flatnonzero(third):  # in bracket order: the same splits at any chunk size
        e = edges["edge"][open_[j]]
        if count[e] < MAX_PER_EDGE:
            count[e] += 1
        else:
            third[j] = False
            capped.append(e)
    edges["more"] |= np.isin(edges["edge"], capped)
    split = open_[third]
    new = {k: v[split].copy() for k, v in edges.items()}  # [mid, hi] of the split brackets
    new["lo"], new["below"] = mid[third], flag[third]
    edges["lo"][open_[to_lo]] = mid[to_lo]
    edges["hi"][open_[~to_lo]] = mid[~to_lo]
    edges["above"][open_[~to_lo]] = flag[~to_lo]  # the flag at hi, a third one included
    edges = {k: np.concatenate([edges[k], new[k]]) for k in edges}
    return edges, open_.size


class _State:
    """The brackets between rounds, kept beside the target so that a killed run resumes."""

    def __init__(self, request: Request, target: Path, resume: bool, force: bool):
        self.folder = partial_dir(target)
        manifest = {"spec": request.source["spec"], "var": request.var, "tol": request.tol,
                    "code_version": code_version()}
        open_partial(self.folder, manifest, {"spec": "spec", "var": "variable",
                                             "tol": "tolerance",
                                             "code_version": "code version"},
                     resume, force)

    def load(self):
        path = self.folder / "brackets.npz"
        if not path.exists():
            return None
        with np.load(path) as data:
            counters = data["counters"]
            return ({k: data[k] for k in data.files if k != "counters"}, int(counters[0]),
                    int(counters[1]))

    def save(self, edges: dict, rounds: int, evaluations: int) -> None:
        with atomic(self.folder / "brackets.npz") as tmp, open(tmp, "wb") as fh:
            np.savez(fh, counters=np.array([rounds, evaluations]), **edges)

    def discard(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def refine(ds, var: str = "status", tol: float = 1e-8, target: Path | None = None,
           workers: int | None = None, chunk: int | None = None, resume: bool = False,
           force: bool = False, progress: bool = False, history: str | None = None):
    """Refine every boundary of ``var`` in the atlas ``ds``; write the crossings to
    ``target`` (atomically) when given. Returns the crossings as an xarray Dataset."""
    from sweep import resources

    request = Request(ds, var, tol)
    if target is not None:
        check_target(target, force or resume)
    lock = resources.target_lock(target) if target is not None else contextlib.nullcontext()
    with lock:
        return _refine(request, var, target, workers, chunk, resume, force, progress, history)


def _refine(request, var, target, workers, chunk, resume, force, progress, history):
    """``refine`` once its target is locked: the rounds of bisection, each kept for a
    resume, then the crossings."""
    from sweep import resources
    from sweep.runner import compile_first, terminal_bar_size

    if chunk is not None:
        request.sweep = request.sweep.with_run(chunk=chunk)
    workers = workers or request.sweep.run.workers or os.cpu_count() or 1
    state = None
    if target is not None:
        resources.remove_stale_temporaries(target)
        state = _State(request, target, resume, force)
    saved = state.load() if state is not None else None
    edges, rounds, evaluations = saved if saved else (grid_edges(request), 0, 0)
    if progress:
        print(f"refining {edges['point'].size:,} grid edges where {var} changes "
              f"(to {request.tol:g}) ...", file=sys.stderr, flush=True)
    if (~edges["done"]).any():
        compile_first(request.sweep, announce=progress)
    from tqdm import tqdm

    bar = tqdm(total=rounds + expected_rounds(edges, request.tol), initial=rounds,
               unit="round", delay=1.5, disable=not progress, file=sys.stderr,
               desc="boundaries", **terminal_bar_size())
    try:
        while rounds < MAX_ROUNDS:
            edges, count = bisect_round(request, edges, workers)
            if not count:
                break
            rounds += 1
            evaluations += count
            bar.update(1)
            if state is not None:
                state.save(edges, rounds, evaluations)
    except KeyboardInterrupt:
        if state is None:
            raise
        raise resources.RunInterrupted(
            f"interrupted; {rounds} finished rounds are kept in {state.folder}; "
            f"`sweep boundaries ATLAS --var {var} -o {target} --resume` continues") from None
    finally:
        bar.close()
    result = crossings(request, edges, workers)
    evaluations += 2 * edges["point"].size
    result.attrs.update(rounds=rounds, kernel_evaluations=evaluations,
                        history=history or history_line())
    if request.scale_axes:
        result.attrs["repeated_along"] = (
            " ".join(request.sweep.axes[d].name for d in request.scale_axes)
            + ": axes the kernel only rescales; refined at their first value, repeated")
    if target is not None:
        write(result, target)
        state.discard()
    return result


def expected_rounds(edges: dict, tol: float) -> int:
    """Rounds the widest open bracket still needs (for the progress bar)."""
    open_ = ~edges["done"]
    if not open_.any():
        return 0
    lo, hi = edges["lo"][open_], edges["hi"][open_]
    scale = np.maximum(1.0, np.maximum(np.abs(lo), np.abs(hi)))
    return int(np.ceil(np.log2(np.max((hi - lo) / (2.0 * tol * scale))).clip(0)))


def crossings(request: Request, edges: dict, workers: int):
    """The companion dataset: one row per crossing, sorted by axis, edge and position."""
    import xarray as xr

    e = dict(edges)
    n = e["point"].size
    ends = np.concatenate([e["lo"], e["hi"]])
    out, status = evaluate(request.sweep, _parameters(request, {k: np.concatenate([v, v])
                                                                for k, v in e.items()},
                                                      np.arange(2 * n), ends), workers,
                           request.method)
    x = e["lo"] + 0.5 * (e["hi"] - e["lo"])
    accuracy = 0.5 * (e["hi"] - e["lo"]) / np.maximum(1.0, np.abs(x))
    mech = request.mechanism
    values = [k for k, o in enumerate(mech.outputs) if not (o.is_flag or o.diagnostic)]
    a, b = out[values][:, :n], out[values][:, n:]
    both = np.isfinite(a) & np.isfinite(b)
    one = np.isfinite(a) ^ np.isfinite(b)
    size = np.maximum(np.abs(a), np.abs(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(both & (size > 0), np.abs(a - b) / np.where(size > 0, size, 1.0), 0.0)
    jump = np.where(both.any(axis=0), np.where(both, rel, 0.0).max(axis=0), np.nan)
    continuity = np.where(one.any(axis=0), CONTINUITY["values_on_one_side_only"],
                          np.where(~both.any(axis=0), CONTINUITY["no_values"],
                                   np.where(jump > JUMP, CONTINUITY["outputs_jump"],
                                            CONTINUITY["continuous"]))).astype(np.int8)
    explanation, indicator, indicator_value = [], [], np.full(n, np.nan)
    for i in range(n):
        declared = mech.boundary(request.meaning.get(int(e["below"][i]), ""),
                                 request.meaning.get(int(e["above"][i]), ""))
        if declared is None:
            explanation.append(CONTINUITY_TEXT[int(continuity[i])])
            indicator.append("")
            continue
        explanation.append(declared.explains)
        indicator.append(declared.indicator or "")
        if declared.indicator:
            row = out[getattr(mech.output_index, declared.indicator)]
            pair = np.array([row[i], row[n + i]])
            if np.isfinite(pair).any():
                indicator_value[i] = float(np.nanmean(pair))
    e.update(x=x, accuracy=accuracy, jump=jump, continuity=continuity,
             explanation=np.array(explanation, dtype=object),
             indicator=np.array(indicator, dtype=object), indicator_value=indicator_value)
    e = _replicate(request, e)
    order = np.lexsort((e["lo"], e["point"], e["axis"]))
    e = {k: v[order] for k, v in e.items()}
    x = e["x"]
    index = np.unravel_index(e["point"], request.sweep.shape)
    data = {}
    for d, axis in enumerate(request.sweep.axes):
        p = axis.parameter
        if p.categorical:
            column = np.array([str(v) for v in axis.values[index[d]]], dtype=object)
            data[axis.name] = ("crossing", column, {"long_name": p.long_name,
                                                    "units": p.units})
            continue
        column = axis.values.astype(float)[index[d]]
        column = np.where(e["axis"] == d, x, column)
        data[axis.name] = ("crossing", column, {
            "long_name": p.long_name, "units": p.units,
            "comment": f"the crossing where edge_axis is {axis.name}, else the edge's grid "
                       "value"})
    names = [a.name for a in request.sweep.axes]
    flag_of = dict(request.flag_attrs)
    data.update({
        "edge_axis": ("crossing", np.array([names[d] for d in e["axis"]], dtype=object),
                      {"long_name": "grid axis along which the edge runs and the crossing "
                                    "was bisected", "units": "1"}),
        "grid_point": ("crossing", e["point"], {
            "long_name": "flat (C-order) index in the atlas's grid of the edge's first "
                         "point; the edge runs to its next neighbour along edge_axis",
            "units": "1"}),
        "side_below": ("crossing", e["below"], {
            "long_name": f"{request.var} on the side of smaller edge_axis values",
            "units": "1", **flag_of}),
        "side_above": ("crossing", e["above"], {
            "long_name": f"{request.var} on the side of larger edge_axis values",
            "units": "1", **flag_of}),
        "edge_crossings": ("crossing", e["more"].astype(np.int8), {
            "long_name": f"whether every crossing of {request.var} on this edge was "
                         f"followed (at most {MAX_PER_EDGE} are)", "units": "1",
            "flag_values": np.array([0, 1], np.int8),
            "flag_meanings": "all_followed more_not_followed"}),
        "accuracy": ("crossing", e["accuracy"], {
            "long_name": "half-width of the final bracket over max(1, |crossing|): the "
                         "crossing is known to accuracy max(1, |x|) in its axis's units",
            "units": "1"}),
        "continuity": ("crossing", e["continuity"], {
            "long_name": "what the outputs do across the final bracket",
            "units": "1", "flag_values": np.array(list(CONTINUITY.values()), np.int8),
            "flag_meanings": " ".join(CONTINUITY)}),
        "output_jump": ("crossing", e["jump"], {
            "long_name": "largest relative change of a design output across the final "
                         f"bracket (a jump above {JUMP:g})", "units": "1"}),
        "explanation": ("crossing", e["explanation"], {
            "long_name": "what explains the boundary", "units": "1"}),
        "indicator": ("crossing", e["indicator"], {
            "long_name": "output whose value at the crossing says where the limit is "
                         "(empty: none known)", "units": "1"}),
        "indicator_value": ("crossing", e["indicator_value"], {
            "long_name": "the indicator output at the crossing (mean of the two sides' "
                         "finite values)", "units": "1"}),
    })
    result = xr.Dataset({k: (dims, v, attrs) for k, (dims, v, attrs) in data.items()})
    result.attrs.update(
        Conventions=CONVENTIONS,
        title=f"Boundaries of {request.var}: {request.source['title']}",
        institution="impact-sweep",
        source=f"impact-sweep sweep boundaries, mechanism {request.mechanism.name}",
        references=request.mechanism.references,
        mechanism=request.mechanism.name,
        variable=request.var,
        tolerance=request.tol,
        method=("bisection on every grid edge where the variable changes, the other axes "
                "at the edge's grid values; a midpoint with a third meaning splits the "
                "bracket; the crossing is the final bracket's midpoint"),
        spec=request.source["spec"],
        source_code_version=request.source["code_version"],
        code_version=code_version(),
        package_versions=json.dumps(package_versions()),
    )
    return result


def _replicate(request: Request, rows: dict) -> dict:
    """The crossings refined at the first value of each scale-only axis, repeated at its
    other values (the same bits: the kernel solves the scaled case once)."""
    shape = request.flags.shape
    strides = np.cumprod((1,) + shape[::-1])[::-1][1:]
    for d in request.scale_axes:
        copies = [{**rows, "point": rows["point"] + j * strides[d]} for j in range(shape[d])]
        rows = {k: np.concatenate([c[k] for c in copies]) for k in rows}
    return rows


def write(result, target: Path) -> None:
    """The companion file, written under a temporary name and renamed (never half)."""
    encoding = {name: {"dtype": "S1"} for name in result.variables
                if result[name].dtype == object}
    encoding.update({name: {"_FillValue": None} for name in result.variables
                     if name not in encoding and result[name].dtype.kind in "iu"})
    with atomic(target) as tmp:
        result.to_netcdf(tmp, engine="netcdf4", encoding=encoding)
