"""Two cached kernels whose inner functions are closures of one factory (the same qualname,
different values), as the pendulum systems are: for the test that cached code compiled in
separate processes still runs its own closures when loaded side by side
(tests/test_boundary.py)."""

import math

from numba import njit

from kernels import INNER_OPTIONS, KERNEL_OPTIONS

# a body too long for LLVM to inline, as the pendulum's closures are: each library then
# keeps it as a function of its own, linked by its name
_BODY = "\n".join(f"    acc = math.sin(acc * {i + 1}) + math.atan2(acc, {i + 2}.0) + math.erf(acc)"
                  for i in range(60))


def _make(value):
    namespace = {"math": math, "value": value}
    exec(f"def shifted(x):\n    acc = x\n{_BODY}\n    return x + value + 0.0 * acc",
         namespace)
    return njit(**INNER_OPTIONS)(namespace["shifted"])


_by_one = _make(1.0)
_by_two = _make(2.0)


@njit(**KERNEL_OPTIONS)
def plus_one(x):
    return _by_one(x) + _by_one(-x) - x


@njit(**KERNEL_OPTIONS)
def plus_two(x):
    return _by_two(x) + _by_two(-x) - x
