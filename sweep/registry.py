"""The mechanism registry: one entry per mechanism, declaring parameters, outputs and kernel.

Adding a mechanism means one kernel module in ``kernels/`` and one ``Mechanism`` entry in
``sweep/mechanisms/``. The kernel reads parameters as rows of a float64 matrix in the order of
``Mechanism.parameters`` (choices as their codes, NaN for "not given") and returns
(outputs[n_outputs, n], status[n]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Parameter:
    """A sweepable parameter. ``choices`` maps labels to kernel codes for categorical ones."""

    name: str
    units: str
    long_name: str
    default: object = None  # None: no default (required where the mechanism says so)
    minimum: float = -math.inf
    maximum: float = math.inf
    min_inclusive: bool = True
    max_inclusive: bool = True
    nonzero: bool = False
    integer: bool = False
    choices: dict | None = None
    aliases: dict | None = None  # words standing for numeric codes, e.g. {"auto": 0}

    def domain_text(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        lo = "[" if self.min_inclusive else "("
        hi = "]" if self.max_inclusive else ")"
        kind = "a whole number" if self.integer else "a finite number"
        text = f"{kind} in {lo}{self.minimum:g}, {self.maximum:g}{hi}"
        if self.aliases:
            text = " or ".join(repr(a) for a in self.aliases) + " or " + text
        return text + (", not 0" if self.nonzero else "")

    def check(self, value) -> str | None:
        """Return None if ``value`` is allowed, else what is allowed."""
        if self.choices is not None:
            ok = any(value == c and type(value) is type(c) for c in self.choices)
            return None if ok else self.domain_text()
        if self.aliases and isinstance(value, str) and value in self.aliases:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return self.domain_text()
        if self.integer and not isinstance(value, int):
            return self.domain_text()
        v = float(value)
        if not math.isfinite(v):
            return self.domain_text()
        if v < self.minimum or (v == self.minimum and not self.min_inclusive):
            return self.domain_text()
        if v > self.maximum or (v == self.maximum and not self.max_inclusive):
            return self.domain_text()
        if self.nonzero and v == 0.0:
            return self.domain_text()
        return None

    def encode(self, value) -> float:
        if self.aliases and isinstance(value, str) and value in self.aliases:
            return float(self.aliases[value])
        if self.choices is not None:
            for label, code in self.choices.items():
                if value == label and type(value) is type(label):
                    return float(code)
        return float(value)


@dataclass(frozen=True)
class Output:
    name: str
    units: str
    long_name: str
    description: str = ""
    flags: tuple[str, ...] = ()  # a categorical output: its codes 0, 1, ... mean these


@dataclass(frozen=True)
class Mechanism:
    name: str
    title: str
    parameters: tuple[Parameter, ...]
    outputs: tuple[Output, ...]
    #: kernel entry point: (params, method) -> (outputs, status, profiles[n_prof, n, n_angle])
    run: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
    flags: tuple[str, ...]  # status meanings this mechanism can produce, "ok" first
    method: dict = field(default_factory=dict)  # method key -> Parameter (domain, default)
    method_text: str = ""
    #: cross-parameter rules: called with {name: set of values (or None if absent)}
    check: Callable[[dict], None] | None = None
    #: flags besides "ok" whose points still carry design values (charts show them)
    usable_flags: tuple[str, ...] = ()
    #: per-point profiles along an extra atlas dimension (e.g. crank_angle), if any
    profiles: tuple[Output, ...] = ()
    profile_dim: Parameter | None = None
    profile_coordinate: Callable[[dict], np.ndarray] | None = None  # method -> coordinate
    #: grid axes kept whole inside every block: the kernel solves once per block for all
    #: their values and rescales (the pendulum's omega1 and l2)
    whole_axes: tuple[str, ...] = ()

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)


REGISTRY: dict[str, Mechanism] = {}


def register(mechanism: Mechanism) -> Mechanism:
    REGISTRY[mechanism.name] = mechanism
    return mechanism


def get(name: str) -> Mechanism:
    import sweep.mechanisms  # noqa: F401  (fills the registry)

    return REGISTRY[name]


def names() -> list[str]:
    import sweep.mechanisms  # noqa: F401

    return sorted(REGISTRY)
