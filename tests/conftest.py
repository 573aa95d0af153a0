import contextlib
import importlib
import math

import numpy as np
import pytest
from numba.core import event as numba_event

from kernels.status import MEANINGS
from sweep import registry

def pytest_addoption(parser):
    parser.addoption("--no-warmup", action="store_true", default=False,
                     help="start the tests without compiling ahead what they need "
                          "(tests/warmup.py)")


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """Compile what the tests need before they start, in parallel processes, each entry
    point once (tests/warmup.py), where the whole suite or its fast loop runs (not a file
    or a test named on the command line): the workers then load it from the cache."""
    config = session.config
    if (hasattr(config, "workerinput") or config.getoption("no_warmup")
            or config.option.collectonly or config.option.keyword
            or config.args_source != pytest.Config.ArgsSource.TESTPATHS):
        return
    from tests import warmup

    reporter = config.pluginmanager.get_plugin("terminalreporter")
    say = reporter.write_line if reporter is not None else print
    warmup.before_tests(slow="not slow" not in (config.option.markexpr or ""), say=say)


class _CachedCompiles(numba_event.Listener):
    """numba's compile events of cached functions in this process: what the warm-up left
    to the tests (each worker reports its list; a kernel compiled on two workers was
    compiled twice), each with the test that compiled it."""

    def __init__(self):
        self.names, self.depth, self.test = {}, 0, "collection"

    def on_start(self, e):
        self.depth += 1
        d = e.data["dispatcher"]
        if self.depth == 1 and d._cache.__class__.__name__ != "NullCache":
            self.names.setdefault(f"{d.py_func.__module__}.{d.py_func.__qualname__}",
                                  self.test)

    def on_end(self, e):
        self.depth -= 1


_COMPILES = _CachedCompiles()
numba_event.register("numba:compile", _COMPILES)


#: the modules that take longest, started first so that the two workers end together
#: (pytest-xdist hands out whole modules in collection order: ./tasks passes
#: --no-loadscope-reorder, whose default order, the most tests first, left the
#: walk-throughs for last, with the other worker idle meanwhile)
LONGEST_FIRST = ("test_docs.py", "test_edges.py", "test_pendulum.py", "test_stability.py",
                 "test_boundary.py", "test_hostile_inputs.py", "test_pendulum_models.py",
                 "test_explorer.py", "test_machine.py", "test_pendulum_table.py")


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: modules whole


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    _COMPILES.test = item.nodeid


def pytest_sessionfinish(session):
    workeroutput = getattr(session.config, "workeroutput", None)
    if workeroutput is not None:
        workeroutput["cached_compiles"] = sorted(_COMPILES.names.items())


def pytest_testnodedown(node, error):
    seen = node.config.stash.setdefault(_COMPILED_BY, {})
    for name, test in getattr(node, "workeroutput", {}).get("cached_compiles", []):
        seen.setdefault(name, []).append(f"{node.gateway.id} {test}")


_COMPILED_BY = pytest.StashKey[dict]()


def pytest_terminal_summary(terminalreporter, config):
    by_worker = config.stash.get(_COMPILED_BY, None)
    if by_worker is None:  # one process: its own list
        by_worker = {name: [f"main {test}"] for name, test in _COMPILES.names.items()}
    twice = sorted(name for name, workers in by_worker.items() if len(workers) > 1)
    if by_worker:
        from kernels.cache import cache_dir

        listing = cache_dir() / "compiled-during-tests.txt"
        listing.parent.mkdir(parents=True, exist_ok=True)
        listing.write_text("".join(f"{name}\t{'; '.join(workers)}\n"
                                   for name, workers in sorted(by_worker.items())))
        terminalreporter.write_line(
            f"cached kernels compiled during the tests: {len(by_worker)} ({listing})"
            + (f"; on more than one worker (add them to tests/warmup.py): {', '.join(twice)}"
               if twice else ""))


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
