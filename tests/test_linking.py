"""kernels/linking.py: an inner kernel's library hands the JIT engine no code of its own, the
kernel that calls it runs it, and what needs machine code of its own (a kernel called from
Python, a cfunc, a function passed as a value) still has it. That the atlases are unchanged
bit for bit is benchmarks/reference_atlases.py's (docs/performance.md)."""

import math

import numpy as np
from numba import cfunc, njit, types
from numba.core import codegen

from kernels import INNER_OPTIONS, KERNEL_OPTIONS, linking

OPTIONS = dict(KERNEL_OPTIONS, cache=False)


def test_the_patch_is_in_place_on_this_numba():
    """install() finds what it patches (False would leave every compile as slow as before)
    and is idempotent."""
    assert linking.install() and linking.install()


def test_an_inner_kernel_gives_the_engine_no_code_and_its_caller_runs_it(monkeypatch):
    """Two inner kernels, one calling the other, under a kernel called from Python: every
    module handed to the engine that defines either inner function also defines the
    kernel's Python wrapper (the caller's copy, the one that runs); the values are Python's
    to round-off."""
    added = []
    add_module = codegen.JITCPUCodegen._add_module

    def recording(self, module):
        added.append({f.name for f in module.functions if not f.is_declaration})
        return add_module(self, module)
    monkeypatch.setattr(codegen.JITCPUCodegen, "_add_module", recording)

    @njit(**INNER_OPTIONS)
    def leaf(x):
        return x * x + 1.0

    @njit(**INNER_OPTIONS)
    def middle(x):
        return leaf(x) - math.sin(x)

    @njit(**OPTIONS)
    def kernel(xs):
        out = np.empty_like(xs)
        for i in range(xs.size):
            out[i] = middle(xs[i])
        return out

    xs = np.linspace(-3.0, 3.0, 7)
    np.testing.assert_allclose(kernel(xs), [x * x + 1.0 - math.sin(x) for x in xs],
                               rtol=1e-15, atol=1e-15)
    (top,) = kernel.overloads.values()
    wrapper = top.fndesc.llvm_cpython_wrapper_name
    assert any(wrapper in names for names in added)
    for inner in (leaf, middle):
        (result,) = inner.overloads.values()
        assert result.library.lean
        assert all(wrapper in names for names in added
                   if result.fndesc.mangled_name in names), inner


def test_a_cfunc_and_a_function_passed_as_a_value_keep_their_machine_code():
    """A cfunc calling an inner kernel, called through ctypes, and a kernel passed to
    another as a first-class value: both need their own machine code, and run."""
    @njit(**INNER_OPTIONS)
    def twice(x):
        return 2.0 * x

    @cfunc(types.float64(types.float64))
    def plus_one(x):
        return twice(x) + 1.0

    assert plus_one.ctypes(3.0) == 7.0

    @njit(**OPTIONS)
    def call(function, x):
        return function(x)

    @njit(**OPTIONS)
    def half(x):
        return 0.5 * x

    assert call(half, 3.0) == 1.5
