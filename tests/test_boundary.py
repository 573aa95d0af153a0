"""kernels/ holds numba numerics only: no xarray, dask, scipy, pint, I/O or sweep imports."""

import ast
import json
import subprocess
import sys
from pathlib import Path

KERNELS = Path(__file__).resolve().parent.parent / "kernels"
FORBIDDEN = {"xarray", "dask", "distributed", "scipy", "pint", "netCDF4", "h5py",
             "matplotlib", "pandas", "sweep", "click", "pydantic", "zarr"}


def _imported_roots(path: Path):
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0], node.lineno
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module.split(".")[0], node.lineno
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "__import__":
            yield "__import__", node.lineno


def test_kernels_source_imports_nothing_forbidden():
    files = sorted(KERNELS.rglob("*.py"))
    assert files, "no kernel modules found"
    bad = [f"{f.name}:{line} imports {root}" for f in files
           for root, line in _imported_roots(f) if root in FORBIDDEN | {"__import__"}]
    assert not bad, bad


def test_importing_kernels_loads_no_forbidden_module():
    names = [f"kernels.{f.stem}" for f in sorted(KERNELS.glob("*.py")) if f.stem != "__init__"]
    # numba itself imports scipy when it is installed: compare with numba alone
    code = ("import importlib, json, sys\n"
            "import numba, numpy\n"
            "base = set(sys.modules)\n"
            f"for n in {names!r}: importlib.import_module(n)\n"
            "print(json.dumps(sorted(set(sys.modules) - base)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=KERNELS.parent)
    loaded = {m.split(".")[0] for m in json.loads(out.stdout)}
    assert "kernels" in loaded
    assert not loaded & FORBIDDEN, loaded & FORBIDDEN


def test_boundary_check_catches_a_violation(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import numpy\nfrom scipy.optimize import brentq\n")
    assert ("scipy", 2) in list(_imported_roots(bad))


def test_numba_cache_is_keyed_on_every_kernel_source():
    """numba reuses cached code after checking only the decorated function's own file; a
    kernel calling into a changed module ran stale code until the cache directory was named
    by a hash of all kernel sources."""
    import hashlib

    import numba

    import kernels
    here = Path(kernels.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    assert numba.config.CACHE_DIR.endswith("numba-" + digest.hexdigest()[:16])
