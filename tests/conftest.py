import contextlib
import importlib
import math

import numpy as np
import pytest

from kernels.status import MEANINGS
from sweep import registry

R03 = 0.3
GAMMA03 = 13.0 / 7.0  # (1 + R)/(1 - R) at R = 0.3


def kernel_points(mechanism, method=None, raw=False, **params):
    """Run a mechanism's kernel on points given by parameter name (scalars, or arrays of one
    length; words for categories); parameters not given take their declared defaults.
    Returns (outputs by name, status meanings, profiles by name [point, angle]). As the
    atlas gets them (the declaration's rule of what a status carries applied), or ``raw``:
    everything the kernel module computed, also at statuses whose outputs are not design
    values."""
    kernel = registry.get(mechanism)
    decl = kernel.declaration
    run = importlib.import_module(registry.MECHANISMS[mechanism]).run if raw else kernel.run
    n = max((np.size(v) for v in params.values() if not isinstance(v, str)), default=1)
    matrix = np.empty((len(decl.parameters), n))
    for row, p in enumerate(decl.parameters):
        value = params.get(p.name, p.default)
        values = [value] * n if np.ndim(value) == 0 else list(value)
        matrix[row] = [p.encode(v.item() if isinstance(v, np.generic) else v) for v in values]
    out, status, prof = run(matrix, decl.method_record(**(method or {})))
    outputs = {o.name: out[row] for row, o in enumerate(decl.outputs)}
    profiles = {o.name: prof[row] for row, o in enumerate(decl.profiles)}
    return outputs, [MEANINGS[s] for s in status], profiles


def kernel_point(mechanism, method=None, raw=False, **params):
    """kernel_points for one point: (outputs by name, status meaning, profiles by name)."""
    outputs, meanings, profiles = kernel_points(mechanism, method, raw, **params)
    return ({k: float(v[0]) for k, v in outputs.items()}, meanings[0],
            {k: v[0] for k, v in profiles.items()})


def crank_rocker_point(geometry_tol=1e-9, raw=False, **given):
    """Run the crank-rocker kernel on one point; returns (outputs dict, status meaning)."""
    out, status, _ = kernel_point("crank_rocker", {"geometry_tol": geometry_tol}, raw, **given)
    return out, status


@pytest.fixture
def point():
    return crank_rocker_point


def flag_words(var) -> np.ndarray:
    """The meanings of a flag variable's values (CF flag_values/flag_meanings)."""
    meaning = dict(zip(np.atleast_1d(var.attrs["flag_values"]).tolist(),
                       var.attrs["flag_meanings"].split()))
    return np.vectorize(lambda v: meaning[int(v)], otypes=[object])(np.asarray(var.values))


@contextlib.contextmanager
def interrupted_after(blocks: int):
    """A run inside stops with KeyboardInterrupt (Ctrl-C) once ``blocks`` blocks finished;
    yields the list of the blocks' locations it was asked for."""
    from sweep import engine

    real, calls = engine.run_block, []

    def stop(sweep, location):
        calls.append(location)
        if len(calls) > blocks:
            raise KeyboardInterrupt
        return real(sweep, location)

    engine.run_block = stop
    try:
        with pytest.raises(KeyboardInterrupt):
            yield calls
    finally:
        engine.run_block = real
