"""Lazy grid -> dask blocks -> numba kernel -> xarray Dataset (atlas.md §2).

The cartesian product is never built in the client: each dask task receives only its block's
index ranges, broadcasts the axis slices of that block into the kernel's parameter matrix,
runs the kernel and returns the selected outputs plus status. Every grid point is computed
independently, so results are bit-identical whatever the chunk size or thread count.
"""

from __future__ import annotations

import math

import dask.array as da
import numpy as np
import xarray as xr

from sweep.atlas import annotate
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


def block_parameters(sweep: Sweep, location: list[tuple[int, int]]) -> np.ndarray:
    """The kernel's parameter matrix (n_parameters, n_points) for one block of the grid."""
    bshape = tuple(stop - start for start, stop in location)
    n = math.prod(bshape)
    params = np.empty((len(sweep.mechanism.parameters), n))
    axis_of = {axis.name: j for j, axis in enumerate(sweep.axes)}
    for k, p in enumerate(sweep.mechanism.parameters):
        j = axis_of.get(p.name)
        if j is None:
            params[k] = sweep.fixed[p.name]
            continue
        start, stop = location[j]
        view = [1] * len(bshape)
        view[j] = stop - start
        params[k] = np.broadcast_to(sweep.axes[j].codes[start:stop].reshape(view),
                                    bshape).ravel()
    return params


def run_block(sweep: Sweep, location: list[tuple[int, int]]) -> np.ndarray:
    """Selected outputs, status and profiles of one block, stacked as
    (n_scalar + 1 + n_profile * n_angle, *block_shape)."""
    bshape = tuple(stop - start for start, stop in location)
    method = np.array(list(sweep.method.values()), dtype=np.float64)
    out, status, prof = sweep.mechanism.run(block_parameters(sweep, location), method)
    names = [o.name for o in sweep.mechanism.outputs]
    rows = [names.index(name) for name in sweep.scalar_outputs]
    pnames = [o.name for o in sweep.mechanism.profiles]
    prows = [pnames.index(name) for name in sweep.profile_outputs]
    n_ang = prof.shape[2]
    result = np.empty((len(rows) + 1 + len(prows) * n_ang,) + bshape)
    result[:len(rows)] = out[rows].reshape((len(rows),) + bshape)
    result[len(rows)] = status.reshape(bshape)
    for k, row in enumerate(prows):
        start = len(rows) + 1 + k * n_ang
        result[start:start + n_ang] = prof[row].T.reshape((n_ang,) + bshape)
    return result


class Plan:
    """How a sweep is cut into blocks and where each kernel row goes in the atlas."""

    def __init__(self, sweep: Sweep, chunk: int | None = None):
        self.sweep = sweep
        self.requested = chunk
        self.shape = sweep.shape
        self.angles = sweep.profile_coordinate()
        self.n_out = len(sweep.scalar_outputs)
        self.n_prof = len(sweep.profile_outputs)
        n_ang = self.angles.shape[0]
        # a block's memory grows with the profile length: keep it near the requested size
        per_point = self.n_out + 1 + self.n_prof * n_ang
        target = max(1, (chunk or sweep.run.chunk) * (self.n_out + 1) // per_point)
        if chunk is None and "chunk" not in sweep.run.model_fields_set:
            # at least MIN_BLOCKS blocks, so that a small grid of an expensive mechanism
            # (an integrated pendulum: ~1 ms a point) still keeps every core busy
            target = min(target, max(1, -(-math.prod(self.shape) // MIN_BLOCKS)))
        whole = tuple(d for d, axis in enumerate(sweep.axes)
                      if axis.parameter.name in sweep.mechanism.whole_axes)
        self.chunk_shape = choose_chunks(self.shape, target, whole)
        self.chunks = da.core.normalize_chunks(self.chunk_shape, self.shape)
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
        """A stacked block result -> {variable: array over grid dims (+ profile dim last)}."""
        out = {name: result[k] for k, name in enumerate(self.sweep.scalar_outputs)}
        out["status"] = result[self.n_out].astype(np.int8)
        n_ang = self.angles.shape[0]
        for k, name in enumerate(self.sweep.profile_outputs):
            start = self.n_out + 1 + k * n_ang
            out[name] = np.moveaxis(result[start:start + n_ang], 0, -1)
        return out


def kernel_array(plan: Plan) -> da.Array:
    """All kernel rows of the sweep as one lazy dask array (rows, *grid)."""
    sweep = plan.sweep

    def block(block_info=None):
        return run_block(sweep, block_info[None]["array-location"][1:])

    return da.map_blocks(block, chunks=((plan.rows,),) + plan.chunks, dtype=np.float64,
                         meta=np.empty((0,) * (len(plan.shape) + 1)), name="kernel")


def build(sweep: Sweep, chunk: int | None = None) -> xr.Dataset:
    """The atlas as a lazy (dask-backed) Dataset; nothing is computed here."""
    plan = Plan(sweep, chunk)
    stacked = kernel_array(plan)
    n_out, n_ang = plan.n_out, plan.angles.shape[0]
    dims = [axis.name for axis in sweep.axes]
    coords = {axis.name: (axis.name, axis.values) for axis in sweep.axes}
    data = {name: (dims, stacked[k]) for k, name in enumerate(sweep.scalar_outputs)}
    data["status"] = (dims, stacked[n_out].astype(np.int8))
    if plan.n_prof:
        pdim = sweep.mechanism.profile_dim.name
        coords[pdim] = (pdim, plan.angles)
        for k, name in enumerate(sweep.profile_outputs):
            start = n_out + 1 + k * n_ang
            data[name] = (dims + [pdim], da.moveaxis(stacked[start:start + n_ang], 0, -1))
    ds = xr.Dataset(data, coords=coords)
    return annotate(ds, sweep, plan.chunk_shape)
