"""The block loop every linkage and machine kernel shares: the designs of a block one at a
time, each design's parameters copied into a contiguous vector, its point function writing
its outputs and profiles by name, its status into the block's arrays.

A kernel makes its block once, at import, as a module-level function (cached on disk):
``block = module_level(each_design(design), "name_block", globals(), KERNEL_OPTIONS)``.
(A point function passed to a cached loop as an argument is a dynamic global to numba's
cache: it would be compiled again in every process.)
"""

import math

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS


def each_design(point):
    """The block function ``block(params, settings, out, status, prof)`` of a point
    function: for each design (column) i of ``params`` (n_parameters, n),
    ``status[i] = point(i, pr, settings, out_i, prof_i)`` with pr the design's parameters
    (the rows of its declaration), out_i its outputs and prof_i its profiles [profile,
    angle], NaN until the point writes them; out_i into ``out[:, i]`` and prof_i into
    ``prof[:, i, :]``. ``settings``: the method's options and block-wide data, by name."""

    @njit(**INNER_OPTIONS)
    def block(params, settings, out, status, prof):
        pr = np.empty(params.shape[0])
        out_i = np.empty(out.shape[0])
        prof_i = np.empty((prof.shape[0], prof.shape[2]))
        for i in range(params.shape[1]):
            for k in range(params.shape[0]):
                pr[k] = params[k, i]
            out_i[:] = math.nan
            prof_i[:] = math.nan
            status[i] = point(i, pr, settings, out_i, prof_i)
            for k in range(out.shape[0]):
                out[k, i] = out_i[k]
            for k in range(prof.shape[0]):
                for j in range(prof.shape[2]):
                    prof[k, i, j] = prof_i[k, j]

    return block
