"""Lazy grid -> blocks -> numba kernel -> rows of the atlas.

The cartesian product is never built: each block receives only its index ranges, broadcasts
the axis slices of that block into the kernel's parameter matrix (one row per declared
parameter), runs the kernel with the method options by name, and returns the selected
outputs plus status. Every grid point is computed independently, so results are
bit-identical whatever the chunk size or thread count.
"""

from __future__ import annotations

import itertools
import math
import sys
from contextlib import contextmanager

import numpy as np

from sweep.metadata import annotate, flag_codes
from sweep.requirements import evaluate as evaluate_requirements
from sweep.spec import Sweep

MIN_BLOCKS = 8


def choose_chunks(shape: tuple[int, ...], target: int,
                  whole: tuple[int, ...] = ()) -> tuple[int, ...]:
    """Balanced chunk shape with about ``target`` points: the ``whole`` axes and small axes
    whole, the budget left spread evenly over the large ones, so slices along any axis read
    few chunks."""
    chunk = [1] * len(shape)
    budget = max(1, target)
    for dim in whole:
        chunk[dim] = shape[dim]
        budget = max(1, budget // shape[dim])
    order = [i for i in sorted(range(len(shape)), key=lambda i: shape[i]) if i not in whole]
    for rank, dim in enumerate(order):
        share = budget ** (1.0 / (len(order) - rank))
        c = max(1, min(shape[dim], int(math.floor(share + 1e-9))))
        chunk[dim] = c
        budget = max(1, budget // c)
    return tuple(chunk)


def normalize_chunks(chunk_shape: tuple[int, ...], shape: tuple[int, ...]) -> tuple:
    """Block lengths along each axis: whole chunks, then the remainder."""
    return tuple(tuple([c] * (n // c) + ([n % c] if n % c else [])) for c, n in
                 zip(chunk_shape, shape))


def sample_parameters(sweep: Sweep) -> np.ndarray:
    """A few points that take every code path of a sweep: each combination of the values of
    its categorical axes (model, tool, type ...), the other axes at their first value. Run
    once before the blocks, it compiles what the sweep needs, and only that."""
    codes_of = {name: codes for axis in sweep.axes
                for name, codes in axis.parameters().items()}
    values = []
    for p in sweep.mechanism.parameters:
        codes = codes_of.get(p.name)
        if codes is None:
            values.append([sweep.fixed[p.name]])
        elif p.choices is not None:
            values.append(list(dict.fromkeys(codes.tolist())))
        else:
            values.append([codes[0]])
    return np.array(list(itertools.product(*values)), dtype=float).T


def compile_groups(sweep: Sweep, params: np.ndarray) -> list[list[int]]:
    """The sample points (columns of ``params``) by the values of the parameters whose
    values run code of their own (``compiles_apart``): each group compiles its own entry
    points, so the groups can be compiled side by side."""
    rows = [row for row, p in enumerate(sweep.mechanism.parameters) if p.compiles_apart]
    groups: dict[tuple, list[int]] = {}
    for column in range(params.shape[1]):
        groups.setdefault(tuple(params[rows, column]), []).append(column)
    return list(groups.values())


def warm_up(sweep: Sweep, columns: list[int] | None = None) -> None:
    """Run the kernel on the sample points, or on those columns of them (compiling it on
    a first run)."""
    params = sample_parameters(sweep)
    with numba_without_blas():
        sweep.kernel(params if columns is None else params[:, columns], sweep.method_record)


#: the module numba imports, on its first compile or cache load, to learn whether np.dot
#: and np.linalg may call BLAS
BLAS_PROBE = "scipy.linalg.cython_blas"


@contextmanager
def numba_without_blas():
    """numba's first compile or cache load in a process imports scipy.linalg (a sizeable
    share of a cheap sweep's time beyond the import floor) only to learn whether BLAS is
    there; no kernel calls BLAS (np.dot, np.linalg, @). While numba has not looked yet and
    scipy.linalg is not loaded, the probe's import fails for that moment: numba records
    "no BLAS", and scipy imports normally afterwards."""
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        yield
        return
    sys.modules[BLAS_PROBE] = None  # an import of a None entry raises ImportError
    try:
        yield
    finally:
        if BLAS_PROBE in sys.modules and sys.modules[BLAS_PROBE] is None:
            del sys.modules[BLAS_PROBE]


def _parameter_matrix(sweep: Sweep, n: int, positions) -> np.ndarray:
    """The kernel's parameter matrix (n_parameters, n): a fixed parameter's code in its row;
    a grid axis's parameter (or each parameter a design sets) at ``positions(j)``, the n
    points' places along axis j."""
    params = np.empty((len(sweep.mechanism.parameters), n))
    source = {name: (j, codes) for j, axis in enumerate(sweep.axes)
              for name, codes in axis.parameters().items()}
    for row, p in enumerate(sweep.mechanism.parameters):
        if p.name in source:
            j, codes = source[p.name]
            params[row] = codes[positions(j)]
        else:
            params[row] = sweep.fixed[p.name]
    return params


def block_parameters(sweep: Sweep, location: list[tuple[int, int]]) -> np.ndarray:
    """The kernel's parameter matrix (n_parameters, n_points) for one block of the grid."""
    bshape = tuple(stop - start for start, stop in location)

    def positions(j):
        start, stop = location[j]
        view = [1] * len(bshape)
        view[j] = stop - start
        return np.broadcast_to(np.arange(start, stop).reshape(view), bshape).ravel()

    return _parameter_matrix(sweep, math.prod(bshape), positions)


def point_parameters(sweep: Sweep, points: np.ndarray) -> np.ndarray:
    """The kernel's parameter matrix (n_parameters, n) at grid points given by their flat
    (C-order) indices (``sweep boundaries`` moves one axis's row between them)."""
    index = np.unravel_index(np.asarray(points, dtype=np.int64), sweep.shape)
    return _parameter_matrix(sweep, len(index[0]), lambda j: index[j])


def run_block(sweep: Sweep, location: list[tuple[int, int]]) -> np.ndarray:
    """Selected outputs, status, the requirements' flag and margin (where the sweep has
    requirements) and profiles of one block, stacked as
    (n_scalar + 1 [+ 2] + n_profile * n_angle, *block_shape)."""
    bshape = tuple(stop - start for start, stop in location)
    out, status, prof = sweep.kernel(block_parameters(sweep, location), sweep.method_record)
    index = sweep.mechanism.output_index
    rows = [getattr(index, name) for name in sweep.scalar_outputs]
    pindex = sweep.mechanism.profile_index
    prows = [getattr(pindex, name) for name in sweep.profile_outputs]
    n_ang = prof.shape[2]
    extra = requirement_rows(sweep)
    result = np.empty((len(rows) + 1 + extra + len(prows) * n_ang,) + bshape)
    result[:len(rows)] = out[rows].reshape((len(rows),) + bshape)
    result[len(rows)] = status.reshape(bshape)
    if extra:
        code, margin = evaluate_requirements(
            {limit.name: out[getattr(index, limit.name)] for limit in sweep.requirements},
            sweep.requirements)
        result[len(rows) + 1] = code.reshape(bshape)
        result[len(rows) + 2] = margin.reshape(bshape)
    for k, row in enumerate(prows):
        start = len(rows) + 1 + extra + k * n_ang
        result[start:start + n_ang] = prof[row].T.reshape((n_ang,) + bshape)
    return result


def requirement_rows(sweep: Sweep) -> int:
    """Rows a block carries for the requirements: their flag and margin, or none."""
    return 2 if sweep.requirements else 0


class Plan:
    """How a sweep is cut into blocks and where each kernel row goes in the atlas."""

    def __init__(self, sweep: Sweep):
        self.sweep = sweep
        self.shape = sweep.shape
        self.angles = sweep.profile_coordinate()
        self.n_out = len(sweep.scalar_outputs)
        self.n_prof = len(sweep.profile_outputs)
        self.n_req = requirement_rows(sweep)
        n_ang = self.angles.shape[0]
        # a block's memory grows with the profile length: keep it near the requested size
        per_point = self.n_out + 1 + self.n_req + self.n_prof * n_ang
        target = max(1, sweep.run.chunk * (self.n_out + 1) // per_point)
        if "chunk" not in sweep.run.model_fields_set:
            # at least MIN_BLOCKS blocks, so that a small grid of an expensive mechanism
            # (an integrated pendulum: ~1 ms a point) still keeps every core busy
            target = min(target, max(1, -(-math.prod(self.shape) // MIN_BLOCKS)))
        whole = tuple(d for d, axis in enumerate(sweep.axes)
                      if axis.name in sweep.mechanism.whole_axes)
        self.chunk_shape = choose_chunks(self.shape, target, whole)
        self.chunks = normalize_chunks(self.chunk_shape, self.shape)
        self.rows = per_point

    def locations(self):
        """Block index and [(start, stop) per grid dim] of every block, in C order."""
        starts = [np.cumsum((0,) + c[:-1]) for c in self.chunks]
        for index in np.ndindex(*[len(c) for c in self.chunks]):
            yield index, [(int(starts[d][i]), int(starts[d][i] + self.chunks[d][i]))
                          for d, i in enumerate(index)]

    @property
    def n_blocks(self) -> int:
        return math.prod(len(c) for c in self.chunks)

    def split(self, result: np.ndarray) -> dict[str, np.ndarray]:
        """A stacked block result -> {variable: array over grid dims (+ profile dim last)},
        flag outputs as their int8 codes."""
        mech = self.sweep.mechanism
        out = {}
        for k, name in enumerate(self.sweep.scalar_outputs):
            o = mech.output(name)
            out[name] = flag_codes(result[k], o) if o.is_flag else result[k]
        out["status"] = result[self.n_out].astype(np.int8)
        if self.n_req:
            out["requirements"] = result[self.n_out + 1].astype(np.int8)
            out["requirement_margin"] = result[self.n_out + 2]
        n_ang = self.angles.shape[0]
        for k, name in enumerate(self.sweep.profile_outputs):
            start = self.n_out + 1 + self.n_req + k * n_ang
            out[name] = np.moveaxis(result[start:start + n_ang], 0, -1)
        return out


class _Definition:
    """One variable of a Template: dimensions, placeholder values, attributes, encoding."""

    def __init__(self, dims, values):
        self.dims = (dims,) if isinstance(dims, str) else tuple(dims)
        self.values = np.asarray(values)
        self.dtype, self.shape = self.values.dtype, self.values.shape
        self.attrs, self.encoding = {}, {}


class Template:
    """What the atlas writer needs of an atlas (the names, dimensions, dtypes, attributes
    and encodings of ``build``'s Dataset, in the same order) without xarray's data model:
    building an xarray Dataset imports dask to check for dask arrays (a good part of a
    small run). ``metadata.annotate`` fills it as it fills a Dataset."""

    def __init__(self, coords: dict, data: dict):
        self.coords = {name: _Definition(*item) for name, item in coords.items()}
        self.data_vars = {name: _Definition(*item) for name, item in data.items()}
        self.sizes = {dim: n for v in self.coords.values() for dim, n in zip(v.dims, v.shape)}
        self.attrs = {}

    def __getitem__(self, name):
        return self.coords[name] if name in self.coords else self.data_vars[name]


def build(sweep: Sweep, lazy: bool = True):
    """The atlas as a lazy (dask-backed) xarray Dataset; nothing is computed here. With
    ``lazy=False``, a Template: the same variables, dimensions, attributes and encodings
    over placeholder values (zero-strided, no memory), what the atlas writer needs,
    without importing xarray's data model or dask."""
    plan = Plan(sweep)
    n_out, n_ang = plan.n_out, plan.angles.shape[0]
    dims = [axis.name for axis in sweep.axes]
    coords = {axis.name: (axis.name, axis.values) for axis in sweep.axes}
    for axis in sweep.axes:  # a chained sweep: what each design sets, and where it came from
        coords.update({name: (axis.name, values)
                       for name, (values, _) in axis.coordinates.items()})
    if plan.n_prof:
        pdim = sweep.mechanism.profile_dim.name
        coords[pdim] = (pdim, plan.angles)
    data = {}
    if not lazy:
        def placeholder(dtype, shape):
            return np.broadcast_to(np.zeros((), dtype), shape)
        for name in sweep.scalar_outputs:
            flag = sweep.mechanism.output(name).is_flag
            data[name] = (dims, placeholder(np.int8 if flag else np.float64, plan.shape))
        data["status"] = (dims, placeholder(np.int8, plan.shape))
        if plan.n_req:
            data["requirements"] = (dims, placeholder(np.int8, plan.shape))
            data["requirement_margin"] = (dims, placeholder(np.float64, plan.shape))
        for name in sweep.profile_outputs:
            data[name] = (dims + [pdim], placeholder(np.float64, plan.shape + (n_ang,)))
        return annotate(Template(coords, data), sweep, plan.chunk_shape)
    import dask.array as da
    import xarray as xr

    stacked = da.map_blocks(lambda block_info=None: run_block(
        sweep, block_info[None]["array-location"][1:]),
        chunks=((plan.rows,),) + plan.chunks, dtype=np.float64,
        meta=np.empty((0,) * (len(plan.shape) + 1)), name="kernel")
    for k, name in enumerate(sweep.scalar_outputs):
        o = sweep.mechanism.output(name)
        rows = stacked[k]
        if o.is_flag:
            rows = rows.map_blocks(flag_codes, o, dtype=np.int8)
        data[name] = (dims, rows)
    data["status"] = (dims, stacked[n_out].astype(np.int8))
    if plan.n_req:
        data["requirements"] = (dims, stacked[n_out + 1].astype(np.int8))
        data["requirement_margin"] = (dims, stacked[n_out + 2])
    for k, name in enumerate(sweep.profile_outputs):
        start = n_out + 1 + plan.n_req + k * n_ang
        data[name] = (dims + [pdim], da.moveaxis(stacked[start:start + n_ang], 0, -1))
    ds = xr.Dataset(data, coords=coords)
    return annotate(ds, sweep, plan.chunk_shape)
