"""numba's on-disk cache, keyed by each module's own import closure.

numba reuses cached machine code after checking only the decorated function's own source
file, so a kernel calling into a changed module would silently run the old callee. Here a
function's cache stamp is a hash of its file and of every project module that file imports,
directly or through others (found by reading the imports, lazy ones included): an edit to
kernels/balancer.py recompiles the balancer and nothing else, an edit to the integration
core recompiles every pendulum system, and an edit to kernels/__init__.py everything.

Second, numba names each compiled function ``qualname$uid`` with uid from a counter that
starts at 1 in every process. Two processes that compile closures of one factory in the
same order (the paper and the rigid pendulum on the blade, each in its own sweep) give them
the same symbols, and a later process that loads both cached kernels links one body for
both: measured, a rigid-pendulum sweep run after a paper-pendulum one in the same process
took the paper model's block (15 of 120 random blade designs changed regime). Uids drawn at
random make the symbols distinct across processes and forks (numba issue #10486).

Third, the cache lives outside the source tree (``cache_dir``): in the virtual environment
the package runs in, so that a clean of the tree or a fresh checkout of the same code
installed in the same environment finds it, and its folders are named by each module's
place in the package, not by where the checkout lies on disk.

``install()`` must run before any kernel is decorated (numba picks a function's cache
locator then); kernels/__init__.py calls it.
"""

import hashlib
import inspect
import os
import re
import secrets
import shutil
import sys
from functools import lru_cache
from pathlib import Path

import numba
from numba.core import caching
from numba.core.bytecode import FunctionIdentity

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("kernels", "tests", "benchmarks")  # whose modules count as the project's
# numba 0.68 made these public; earlier releases name them with a leading underscore
_CACHE_IMPL = getattr(caching, "CacheImpl", None) or caching._CacheImpl
_USER_LOCATOR = (getattr(caching, "UserProvidedCacheLocator", None)
                 or caching._UserProvidedCacheLocator)


def _module_file(name: str, root: Path) -> Path | None:
    base = root.joinpath(*name.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


#: an import statement at the start of a line or after a semicolon: ``from M import names`` (names possibly in
#: parentheses or after backslashes over several lines) or ``import M [as N], ...``
_IMPORT = re.compile(r"(?:^|;)[ \t]*(?:from[ \t]+([A-Za-z_][\w.]*)[ \t]+import[ \t]+"
                     r"(\([^)]*\)|(?:\\\n|[^\n;])*)|import[ \t]+((?:\\\n|[^\n;])+))",
                     re.MULTILINE)


@lru_cache(maxsize=None)
def _imports_of(path: Path, mtime_ns: int, size: int) -> frozenset[str]:
    """The project modules a file imports, with their packages (lazy imports included),
    read with a pattern instead of a parse: parsing every kernel file cost a noticeable part
    of each start, the pattern next to nothing (tests/test_boundary.py checks it against the parse on every
    project file). Keyed by the file's mtime and size, so an edit is seen."""
    names = set()
    for match in _IMPORT.finditer(path.read_text(encoding="utf-8")):
        module, imported, plain = match.groups()
        items = re.sub(r"#[^\n]*|[()\\]", " ", imported or plain).split(",")
        words = [item.split()[0] for item in items if item.split()]
        if module is None:
            names.update(words)
        else:
            names.add(module)
            names.update(f"{module}.{word}" for word in words)
    found = set()
    for name in names:
        if name.split(".")[0] in PACKAGES:
            parts = name.split(".")
            found.update(".".join(parts[:i]) for i in range(1, len(parts) + 1))
    return frozenset(found)


def _imported_modules(path: Path) -> frozenset[str]:
    stat = path.stat()
    return _imports_of(path, stat.st_mtime_ns, stat.st_size)


def import_closure(path: Path, root: Path = ROOT) -> list[Path]:
    """The file and every project module it imports, directly or not, sorted."""
    seen, todo = {Path(path).resolve()}, [Path(path).resolve()]
    while todo:
        for name in _imported_modules(todo.pop()):
            found = _module_file(name, root)
            if found is not None and found.resolve() not in seen:
                seen.add(found.resolve())
                todo.append(found.resolve())
    return sorted(seen)


@lru_cache(maxsize=None)
def stamp(path: str, root: Path = ROOT) -> str:
    """A hash of the contents of a file's import closure."""
    digest = hashlib.sha256()
    for member in import_closure(Path(path), root):
        digest.update(str(member.relative_to(root)).encode() + b"\0" + member.read_bytes())
    return digest.hexdigest()


class ImportClosureLocator(_USER_LOCATOR):
    """The user-provided cache directory, stamped by the import closure of the source."""

    def get_source_stamp(self):
        return stamp(str(Path(self._py_file).resolve()))

    @classmethod
    def from_function(cls, py_func, py_file):
        if not Path(py_file).resolve().is_relative_to(ROOT):
            return None
        return super().from_function(py_func, py_file)

    @classmethod
    def get_suitable_cache_subpath(cls, py_file):
        """The module's folder inside the package (``kernels_pendulum``), not a hash of
        where the checkout lies: another checkout of the same code shares the cache (the
        stamp still tells a different file apart)."""
        return "_".join(Path(py_file).resolve().parent.relative_to(ROOT).parts)


class _RandomIds:
    """Function uids for numba's symbol names: random 63-bit numbers, so that code cached by
    different processes never shares a name with a different body (see the module
    docstring); a repeat within a process is as likely as two equal random 63-bit draws."""

    def __iter__(self):
        return self

    def __next__(self) -> int:
        return secrets.randbits(63)


def cache_dir() -> Path:
    """Where compiled kernels are kept: $NUMBA_CACHE_DIR; else inside the virtual
    environment the package runs in (it outlives a clean of the source tree, and every
    checkout installed there shares it); else the user's cache folder."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    if sys.prefix != sys.base_prefix:
        return Path(sys.prefix) / "numba-cache"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / \
        "impact-sweep" / "numba"


def module_level(inner, name: str, namespace: dict, options: dict):
    """A function ``name`` of the module whose globals are ``namespace``, with the
    arguments of the numba function ``inner`` (typically a closure of a factory), that
    calls it: numba caches a module-level function on disk by its name and file, where
    a closure called from Python is compiled again in every process. ``name`` must say
    everything that makes ``inner`` what it is (a system, a method, a variant)."""
    arguments = ", ".join(inspect.signature(getattr(inner, "py_func", inner)).parameters)
    namespace["_" + name] = inner
    exec(compile(f"def {name}({arguments}):\n    return _{name}({arguments})\n",
                 namespace["__file__"], "exec"), namespace)
    namespace[name] = numba.njit(**options)(namespace[name])
    return namespace[name]


def install() -> None:
    """Cache under cache_dir(), with the closure stamp, and with symbol names unique
    across processes."""
    if not isinstance(FunctionIdentity._unique_ids, _RandomIds):
        FunctionIdentity._unique_ids = _RandomIds()
    for old in (Path(__file__).parent / "__pycache__").glob("numba-*"):
        shutil.rmtree(old, ignore_errors=True)  # the caches of a whole-package hash
    numba.config.CACHE_DIR = str(cache_dir())
    if ImportClosureLocator not in _CACHE_IMPL._locator_classes:
        _CACHE_IMPL._locator_classes.insert(0, ImportClosureLocator)
