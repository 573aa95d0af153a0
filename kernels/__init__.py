"""Numba kernels of impact-sweep: pure numerics on plain floats and arrays.

This package must not import xarray, dask, scipy, pint, netCDF4, matplotlib or anything from
``sweep`` (tests/test_boundary.py enforces it). Kernels never raise on a bad grid point: they
write a status code (``kernels.status``) and NaN outputs.
"""

#: compile options of every kernel. error_model="numpy": a float division by zero gives
#: inf/NaN (then a status code) instead of raising ZeroDivisionError, and costs no check.
#: No fastmath: results must be bit-identical whatever the block length.
KERNEL_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")


def _use_source_keyed_cache() -> None:
    """Point numba's on-disk cache at a directory named by a hash of every kernel source.

    numba checks only the decorated function's own file before reusing cached machine code,
    so a kernel that calls into a changed module would silently run the old callee. A new
    source hash means a fresh cache; stale siblings are pruned. Must run before any kernel
    module is imported (the cache locator is fixed at decoration time).
    """
    import hashlib
    import os
    import shutil
    from pathlib import Path

    import numba

    here = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    base = Path(os.environ.get("NUMBA_CACHE_DIR") or here / "__pycache__")
    target = base / f"numba-{digest.hexdigest()[:16]}"
    if not target.exists():
        for old in base.glob("numba-*"):
            shutil.rmtree(old, ignore_errors=True)
    numba.config.CACHE_DIR = str(target)


_use_source_keyed_cache()
