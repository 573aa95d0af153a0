"""The block loop every linkage and machine kernel shares: the designs of a block one at a
time, each design's parameters copied into a contiguous vector, its point function writing
its outputs and profiles by name, its status into the block's arrays.

A kernel makes its block once, at import, as a module-level function of its own module
(cached on disk): ``block = design_block(design, "name_block", globals(), KERNEL_OPTIONS)``.
The loop is written once, here, and defined in the kernel's module around its point
function: a point function passed to a cached loop as an argument is a dynamic global to
numba's cache (compiled again in every process), and a loop compiled as a closure of its
own under a module-level wrapper is one more function to compile on every first run. The
point functions are declared with ``INLINE_OPTIONS``: inlined into the loop, they are not a
compile unit of their own either (benchmarks/compile_events.py).
"""

import numba
import numpy as np

#: the loop: for each design (column) i of ``params`` (n_parameters, n),
#: ``status[i] = point(i, pr, settings, out_i, prof_i)`` with pr the design's parameters
#: (the rows of its declaration), out_i its outputs and prof_i its profiles [profile,
#: angle], views of the block's arrays, NaN until the point writes them. ``settings``: the
#: method's options and block-wide data, by name. Scalar loops and views only: a temporary
#: per design and the slice assignments that fill it were half of a small kernel's first
#: compile (benchmarks/compile_events.py)
LOOP = """
def {name}(params, settings, out, status, prof):
    for i in range(params.shape[1]):
        for k in range(out.shape[0]):
            out[k, i] = _np.nan
        for k in range(prof.shape[0]):
            for j in range(prof.shape[2]):
                prof[k, i, j] = _np.nan
        status[i] = {point}(i, params[:, i], settings, out[:, i], prof[:, i, :])
"""


def design_block(point, name: str, namespace: dict, options: dict):
    """The block function ``name(params, settings, out, status, prof)`` of the point
    function ``point`` (see LOOP), defined in the module whose globals are ``namespace``
    and compiled with ``options``. ``name`` must say everything that makes the block what
    it is (numba caches it by its name and file)."""
    import numpy

    namespace.setdefault("_np", numpy)
    namespace[f"_{name}_point"] = point
    exec(compile(LOOP.format(name=name, point=f"_{name}_point"), namespace["__file__"],
                 "exec"), namespace)
    namespace[name] = numba.njit(**options)(namespace[name])
    return namespace[name]


def block_arrays(declaration, n: int, angles):
    """A block's result arrays for the loop: outputs (n_outputs, n), status (n,) and
    profiles (n_profiles, n, angles), to be filled by name."""
    return (np.empty((len(declaration.outputs), n)), np.empty(n, dtype=np.int8),
            np.empty((len(declaration.profiles), n, len(angles))))
