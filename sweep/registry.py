"""The mechanisms the engine knows: an explicit table from a mechanism's name to its kernel
module.

A kernel module declares ``DECLARATION`` (a ``kernels.declaration.Mechanism``: parameters,
outputs, method keys, status flags) and an entry point ``run(params, method)`` returning
(outputs[n_outputs, n], status[n], profiles[n_profiles, n, n_angles]). Modules are imported
when first asked for, so a run imports (and numba compiles) only the kernels it uses. The
entry point is wrapped in the declaration's one rule of what a status carries
(``Mechanism.values_by_status``), so no caller sees a design value at an unusable status.
Adding a mechanism is one kernel module and one line here (docs/architecture.md).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

from kernels.declaration import Mechanism

MECHANISMS = {
    "crank_rocker": "kernels.crank_rocker",
    "linkage_forces": "kernels.kinetostatics",
    "six_link": "kernels.six_link",
    "six_link_forces": "kernels.six_link_forces",
    "spring_balancer": "kernels.balancer",
    "rotary_pendulum": "kernels.rotary_pendulum",
    "impact_machine": "kernels.impact_machine",
}


@dataclass(frozen=True)
class Kernel:
    """A mechanism's declaration and the kernel entry point that computes it."""

    declaration: Mechanism
    run: Callable


def get(name: str) -> Kernel:
    """The kernel of a registered mechanism (KeyError for an unknown name)."""
    module = importlib.import_module(MECHANISMS[name])
    declaration = module.DECLARATION
    if declaration.name != name:
        raise RuntimeError(f"{MECHANISMS[name]} declares {declaration.name!r}, not {name!r}")
    return Kernel(declaration, _by_status(declaration, module.run))


def _by_status(declaration: Mechanism, run: Callable) -> Callable:
    def run_by_status(params, method):
        out, status, profiles = run(params, method)
        return declaration.values_by_status(out, status), status, profiles
    run_by_status.__doc__ = run.__doc__
    return run_by_status


def names() -> list[str]:
    return sorted(MECHANISMS)
