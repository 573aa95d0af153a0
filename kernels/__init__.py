"""Numba kernels of impact-sweep: pure numerics on plain floats and arrays.

This package must not import xarray, dask, scipy, pint, netCDF4, matplotlib or anything from
``sweep`` (tests/test_boundary.py enforces it). Kernels never raise on a bad grid point: they
write a status code (``kernels.status``) and NaN outputs.
"""

#: compile options of every kernel. error_model="numpy": a float division by zero gives
#: inf/NaN (then a status code) instead of raising ZeroDivisionError, and costs no check.
#: No fastmath: results must be bit-identical whatever the block length.
KERNEL_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")
