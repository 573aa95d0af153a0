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


def choose_chunks(shape: tuple[int, ...], target: int) -> tuple[int, ...]:
    """Balanced chunk shape with about ``target`` points: small axes whole, the budget left
    spread evenly over the large ones, so slices along any axis read few chunks."""
    chunk = [1] * len(shape)
    budget = max(1, target)
    order = sorted(range(len(shape)), key=lambda i: shape[i])
    for rank, dim in enumerate(order):
        share = budget ** (1.0 / (len(shape) - rank))
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


def build(sweep: Sweep, chunk: int | None = None) -> xr.Dataset:
    """The atlas as a lazy (dask-backed) Dataset; nothing is computed here."""
    shape = sweep.shape
    angles = sweep.profile_coordinate()
    n_ang = angles.shape[0]
    n_out = len(sweep.scalar_outputs)
    n_prof = len(sweep.profile_outputs)
    # a block's memory grows with the profile length: keep it near the requested size
    target = max(1, (chunk or sweep.run.chunk) * (n_out + 1) // (n_out + 1 + n_prof * n_ang))
    chunk_shape = choose_chunks(shape, target)
    chunks = da.core.normalize_chunks(chunk_shape, shape)

    def block(block_info=None):
        location = block_info[None]["array-location"][1:]
        return run_block(sweep, location)

    rows = n_out + 1 + n_prof * n_ang
    stacked = da.map_blocks(block, chunks=((rows,),) + chunks, dtype=np.float64,
                            meta=np.empty((0,) * (len(shape) + 1)), name="kernel")
    dims = [axis.name for axis in sweep.axes]
    coords = {axis.name: (axis.name, axis.values) for axis in sweep.axes}
    data = {name: (dims, stacked[k]) for k, name in enumerate(sweep.scalar_outputs)}
    data["status"] = (dims, stacked[n_out].astype(np.int8))
    if n_prof:
        pdim = sweep.mechanism.profile_dim.name
        coords[pdim] = (pdim, angles)
        for k, name in enumerate(sweep.profile_outputs):
            start = n_out + 1 + k * n_ang
            data[name] = (dims + [pdim], da.moveaxis(stacked[start:start + n_ang], 0, -1))
    ds = xr.Dataset(data, coords=coords)
    return annotate(ds, sweep, chunk_shape)
