"""Numba kernels of impact-sweep: pure numerics on plain floats and arrays.

This package must not import xarray, dask, scipy, pint, netCDF4, matplotlib or anything from
``sweep`` (tests/test_boundary.py enforces it). Kernels never raise on a bad grid point: they
write a status code (``kernels.status``) and NaN outputs.
"""

#: compile options of a kernel called from Python. error_model="numpy": a float division
#: by zero gives inf/NaN (then a status code) instead of raising ZeroDivisionError, and
#: costs no check. No fastmath: results must be bit-identical whatever the block length.
KERNEL_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")
#: functions called only from other kernels: no Python or C wrapper is generated for them
#: (the Python one cost a fifth of the pendulum's compile time), no cache file of their own
#: (their code is in the cache of the kernel that calls them), and no machine code of their
#: own (kernels/linking.py); call them from Python through a kernel
INNER_OPTIONS = dict(KERNEL_OPTIONS, no_cpython_wrapper=True, no_cfunc_wrapper=True,
                     cache=False)
#: numba overloads written for a type (kernels/impact/tuples.py): compiled, like inner
#: kernels, without wrappers, so without machine code of their own
OVERLOAD_OPTIONS = dict(no_cpython_wrapper=True, no_cfunc_wrapper=True)
#: one-line accessors and event functions: inlined into their callers by numba, so that
#: they are not compiled, linked and finalised as functions of their own (half the
#: pendulum's compile units)
INLINE_OPTIONS = dict(INNER_OPTIONS, inline="always")

# Constant arguments between kernels: numba types a literal (0, True, a module's integer
# constant) as its own type, Literal[int](0), and an omitted default as another, and
# compiles the callee, with everything it calls, once for each. So a call between kernels
# passes int(0), bool(True), int(CONSTANT) and every optional argument: the stability
# example had compiled its whole driver twice. A variable first set to a
# literal compiles the callee for the literal too, while numba's typing settles: set it
# with bool(False). tests/test_boundary.py checks that each function compiles once.


from kernels import cache, linking  # noqa: E402  (before any kernel is made)

cache.install()
linking.install()
