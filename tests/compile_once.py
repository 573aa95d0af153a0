"""Run in a fresh process with an empty numba cache (tests/test_boundary.py): compile the
kernels of the cheap examples and the rigid pendulum on the blade with the tangent from two
starts, and print, as JSON, every function that numba compiled more than once with its
signatures. numba types a constant argument of a call between kernels as a literal (0,
True) and an omitted default as its own type, and compiles the callee once for each: the
stability example compiled its driver and everything under it twice (66 -> 56 s). A
planted pair of calls (an inner function called with a literal and with a variable) shows
that the check sees such a case."""

import collections
import json
import sys

from numba import njit
from numba.core import event

compiled = collections.defaultdict(list)


class _Compiles(event.Listener):
    def on_start(self, e):
        d = e.data["dispatcher"]
        compiled[id(d)].append((d.py_func.__qualname__, [str(a) for a in e.data["args"]]))

    def on_end(self, e):
        pass


event.register("numba:compile", _Compiles())


@njit(no_cpython_wrapper=True)
def _planted_inner(x, n):
    return x + n


@njit
def _planted(x, n):
    return _planted_inner(x, 0) + _planted_inner(x, n)


def main(examples):
    import numpy as np

    from kernels.impact.runge_kutta import METHOD_DOPRI5
    from kernels.pendulum import systems
    from kernels.pendulum.table import BY_CODES
    from kernels.pendulum.cases import C, N_ROW
    from sweep import engine, spec

    _planted(1.0, 2)
    for path in examples:
        with open(path) as f:
            sw = spec.parse(f.read(), path)
        sw.kernel(engine.sample_parameters(sw), sw.method_record)
    cases = np.zeros((1, len(C)))
    rows, log = np.empty((1, N_ROW)), np.empty((4, 2))
    # one case, two starts: the plain and the tangent-carrying paths of the driver
    system = BY_CODES[1, 1]  # the rigid model on the blade
    systems.entry_point(system, METHOD_DOPRI5, tangent=True)(
        cases, systems.settings_for(system, METHOD_DOPRI5, 1e-6, 1e-9, 0.01, 5, 2), rows,
        np.empty_like(rows), log)
    print(json.dumps([calls for calls in compiled.values() if len(calls) > 1]))


if __name__ == "__main__":
    main(sys.argv[1:])
