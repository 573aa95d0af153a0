"""Numba kernels of impact-sweep: pure numerics on plain floats and arrays.

This package must not import xarray, dask, scipy, pint, netCDF4, matplotlib or anything from
``sweep`` (tests/test_boundary.py enforces it). Kernels never raise on a bad grid point: they
write a status code (``kernels.status``) and NaN outputs.
"""
