"""kernels/ holds numba numerics only: no xarray, dask, scipy, pint, I/O or sweep imports."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

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
    names = [".".join(f.relative_to(KERNELS.parent).with_suffix("").parts)
             for f in sorted(KERNELS.rglob("*.py")) if f.stem != "__init__"]
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


def _blas_calls(path: Path):
    """np.dot, np.vdot, np.matmul, np.inner, np.outer, np.kron, np.linalg.*, and the @
    operator: what numba compiles to BLAS or LAPACK calls."""
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, (ast.BinOp, ast.AugAssign)) and isinstance(node.op, ast.MatMult):
            yield "@", node.lineno
        elif isinstance(node, ast.Attribute) and node.attr in {
                "dot", "vdot", "matmul", "inner", "outer", "kron", "linalg"}:
            yield node.attr, node.lineno


def test_kernels_call_no_blas():
    """The sweep's warm-up keeps numba from importing scipy.linalg to look for BLAS
    (engine.numba_without_blas, 0.22 s of a cheap sweep): that holds only while no kernel
    calls it."""
    bad = [f"{f.name}:{line} {name}" for f in sorted(KERNELS.rglob("*.py"))
           for name, line in _blas_calls(f)]
    assert not bad, bad


def test_the_warm_up_loads_no_scipy_linalg_and_scipy_still_imports():
    code = ("import sys\n"
            "from sweep import spec, engine\n"
            "sw = spec.parse('mechanism = \"rotary_pendulum\"\\n[grid]\\n"
            "k = {start = 1.0, stop = 2.0, num = 3}', 'test')\n"
            "engine.warm_up(sw)\n"
            "print('scipy.linalg' in sys.modules)\n"
            "import scipy.linalg.cython_blas\n"
            "print('scipy.linalg' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=KERNELS.parent)
    assert out.stdout.split() == ["False", "True"], out.stdout + out.stderr


def test_boundary_check_catches_a_violation(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import numpy\nfrom scipy.optimize import brentq\n"
                   "x = numpy.linalg.solve(a, b) + a @ b\n")
    assert ("scipy", 2) in list(_imported_roots(bad))
    assert {("linalg", 3), ("@", 3)} <= set(_blas_calls(bad))


def test_numba_cache_is_keyed_by_each_modules_import_closure(tmp_path):
    """numba reuses cached code after checking only the decorated function's own file; a
    kernel calling into a changed module ran stale code. The stamp of a kernel's cache is a
    hash of its import closure: an edit to the integration core restamps every pendulum
    system, an edit to the balancer restamps nothing of the pendulum."""
    import shutil

    import numba

    from kernels import cache
    from kernels.impact.runge_kutta import METHOD_DOPRI5
    from kernels.pendulum import distinct, systems
    from kernels.pendulum.table import BY_CODES

    closure = cache.import_closure(KERNELS / "rotary_pendulum.py")
    names = {str(p.relative_to(KERNELS.parent)) for p in closure}
    # the lazily imported systems and, through them, the whole core are in it
    assert {"kernels/pendulum/systems.py", "kernels/impact/events.py",
            "kernels/impact/flight.py", "kernels/extrema.py", "kernels/__init__.py"} <= names
    assert "kernels/balancer.py" not in names and "kernels/crank_rocker.py" not in names
    # an edit changes exactly the stamps of the modules that import the edited one
    copy = tmp_path / "kernels"
    shutil.copytree(KERNELS, copy, ignore=shutil.ignore_patterns("__pycache__"))

    def stamps():
        cache.stamp.cache_clear()
        return {name: cache.stamp(str(copy / name), tmp_path)
                for name in ("rotary_pendulum.py", "pendulum/systems.py", "balancer.py")}
    before = stamps()
    with open(copy / "balancer.py", "a") as f:
        f.write("\n# an edit\n")
    after_balancer = stamps()
    with open(copy / "impact" / "events.py", "a") as f:
        f.write("\n# an edit\n")
    after_core = stamps()
    cache.stamp.cache_clear()
    assert after_balancer["balancer.py"] != before["balancer.py"]
    assert after_balancer["rotary_pendulum.py"] == before["rotary_pendulum.py"]
    assert after_core["rotary_pendulum.py"] != after_balancer["rotary_pendulum.py"]
    assert after_core["pendulum/systems.py"] != after_balancer["pendulum/systems.py"]
    assert after_core["balancer.py"] == after_balancer["balancer.py"]
    # and numba uses it for every cached kernel
    rigid_on_blade = systems.entry_point(BY_CODES[1, 1], METHOD_DOPRI5)
    for kernel in (rigid_on_blade, distinct.row_hashes):
        locator = kernel._cache._impl._locator
        assert isinstance(locator, cache.ImportClosureLocator)
        assert locator.get_source_stamp() == cache.stamp(kernel.py_func.__code__.co_filename)
    assert numba.config.CACHE_DIR


def _project_imports_by_parse(path: Path) -> set[str]:
    """The project modules a file imports, by Python's own parser (the oracle)."""
    from kernels import cache

    names = set()
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return {".".join(name.split(".")[:i]) for name in names
            if name.split(".")[0] in cache.PACKAGES
            for i in range(1, len(name.split(".")) + 1)}


def test_the_cache_stamps_import_scan_agrees_with_the_parser(tmp_path):
    """The cache stamp reads imports with a pattern (a parse of every kernel file cost 0.2
    s at each start): on every file of the project and on a file of awkward forms it finds
    the project modules that Python's parser finds. One it missed would leave a stale
    cache."""
    from kernels import cache

    tricky = tmp_path / "tricky.py"
    tricky.write_text(
        "import numpy; import kernels.balancer as b, kernels.status\n"
        "from kernels.impact import (events,  # a comment\n"
        "    flight as f,\n    tangent)\n"
        "from kernels.pendulum.models import \\\n    MODEL_PAPER\n"
        "def lazy():\n    from kernels.six_link import solve\n"
        "x = 1; from kernels.extrema import peak_search\n"
        "from . import relative_is_not_followed\n")
    files = [tricky] + sorted(p for package in cache.PACKAGES + ("sweep",)
                              for p in (KERNELS.parent / package).rglob("*.py"))
    assert len(files) > 60
    for path in files:
        # never fewer (a stale cache); more only where a string holds an import after a
        # semicolon, as this file's does (a needless recompile), and none in kernels/
        found, parsed = set(cache._imported_modules(path)), _project_imports_by_parse(path)
        assert found >= parsed, (path, parsed - found)
        assert found == parsed or path == Path(__file__), (path, found - parsed)


@pytest.mark.slow
def test_cached_kernels_compiled_apart_run_their_own_closures_side_by_side(tmp_path):
    """numba names a compiled function qualname$uid, uid counted from 1 in each process: two
    kernels whose closures come from one factory, compiled each in its own process, shared
    those names, and a process loading both ran one closure for both (the rigid pendulum
    on the blade ran the paper model's block after a paper sweep: 15 of 120 random designs
    changed regime). kernels.cache draws uids at random. Two kernels of tests/cache_twins.py
    (closures adding 1 and 2), compiled in two processes into one cache, then loaded
    together in either order, must each return their own value."""
    import os

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def run(calls):
        code = f"from tests.cache_twins import plus_one, plus_two\nprint({calls})"
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True, cwd=KERNELS.parent, env=env)
        return out.stdout.split()

    assert run("plus_one(0.0)") == ["2.0"]  # compiled and cached here
    assert run("plus_two(0.0)") == ["4.0"]  # and here, in another process
    assert list(tmp_path.rglob("*plus_one*.nbi")) and list(tmp_path.rglob("*plus_two*.nbi"))
    assert run("plus_one(0.0), plus_two(0.0)") == ["2.0", "4.0"]
    assert run("plus_two(0.0), plus_one(0.0)") == ["4.0", "2.0"]


@pytest.mark.slow
def test_every_kernel_function_compiles_once(tmp_path):
    """A constant argument in a call between kernels (a literal 0, True, or an omitted
    default) makes numba compile the callee once more for that type (kernels/__init__.py):
    the stability example compiled its whole driver twice. In a fresh process and cache,
    the cheap examples and the rigid pendulum on the blade with the tangent and two starts
    (the transient's and the cycle's paths, the attractor starts) compile each function
    once; the planted pair in tests/compile_once.py shows that a duplicate is seen."""
    import os

    examples = KERNELS.parent / "sweep" / "example_specs"
    paths = [str(examples / f"{name}.toml") for name in (
        "crank_rocker", "linkage_forces", "six_link", "spring_balancer", "rotary_pendulum",
        "impact_machine")]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run([sys.executable, "-m", "tests.compile_once", *paths],
                         capture_output=True, text=True, check=True, cwd=KERNELS.parent,
                         env=env)
    twice = json.loads(out.stdout.splitlines()[-1])
    planted = [calls for calls in twice if calls[0][0] == "_planted_inner"]
    assert len(planted) == 1 and len(planted[0]) == 2, twice
    assert [calls for calls in twice if calls[0][0] != "_planted_inner"] == []
