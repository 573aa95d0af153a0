"""How a mechanism is declared: the one place its names are written.

A ``Mechanism`` declaration lists a mechanism's parameters (name, paper symbol, units,
long_name, domain, default), its outputs and profiles, its method keys (with their allowed
words), the status flags its kernel can emit, and the rules between parameters. Everything
else is derived from it:

- the kernel's index constants (``parameter_index``, ``output_index``, ``profile_index``) and
  status codes (``status_codes``), as namedtuples of ints that numba freezes as constants;
- the method record (``method_record``): the kernel receives its options by name;
- spec validation, CF attributes, ``sweep examples`` and ``sweep parameters`` (in ``sweep/``).

This module is plain Python: no numba, no ``sweep`` imports, so that both sides can use it.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np

from kernels.status import CODES


@dataclass(frozen=True)
class Quantity:
    """A parameter of the grid or a method key.

    ``choices`` maps the allowed words (or numbers) of a categorical quantity to the codes the
    kernel reads; ``aliases`` are words that stand for a numeric code of a numeric quantity
    (``harmonics = "auto"``). ``used_when`` restricts where the quantity means something:
    ``{"type": ("b", "general")}`` says it is used only when ``type`` takes one of those values
    (a quantity given where it is not used is an error, not silently ignored).
    ``replaces``: the parameter this one stands in for (the kernel derives it).
    """

    name: str
    units: str
    long_name: str
    symbol: str = ""
    default: object = None  # None: no default (required where the rules say so)
    minimum: float = -math.inf
    maximum: float = math.inf
    min_inclusive: bool = True
    max_inclusive: bool = True
    nonzero: bool = False
    integer: bool = False
    choices: dict | None = None
    aliases: dict | None = None
    used_when: dict = field(default_factory=dict)
    #: another parameter this one is given instead of (envelope for crank_length): where
    #: this one is given, the other's default is not used (its code is NaN, not recorded)
    replaces: str | None = None
    #: the short label a chart shows beside the units, never the long_name: a symbol and a
    #: few words, in matplotlib's mathtext (``r"crank speed $\omega_1$"``)
    label: str = ""
    #: each value of this categorical quantity runs code of its own (an entry point
    #: compiled apart): a first run compiles the values on a grid in parallel processes
    compiles_apart: bool = False

    def encode(self, value) -> float:
        """The kernel's code for a value (a word, a number or None for "not given": NaN)."""
        if value is None:
            return math.nan
        if self.aliases and isinstance(value, str) and value in self.aliases:
            return float(self.aliases[value])
        if self.choices is not None:
            for word, code in self.choices.items():
                if value == word and type(value) is type(word):
                    return float(code)
        return float(value)

    def decode(self, code: float):
        """The word (or number) a kernel code stands for; inverse of ``encode``."""
        for table in (self.choices, self.aliases):
            for word, c in (table or {}).items():
                if float(c) == code:
                    return word
        if math.isnan(code):
            return None
        return int(code) if self.integer else float(code)

    @property
    def categorical(self) -> bool:
        return self.choices is not None


#: the common positive-number domain
POSITIVE = dict(minimum=0.0, min_inclusive=False)


@dataclass(frozen=True)
class Output:
    """An output of the kernel (or a profile along an extra dimension).

    A flag output (``flags``: meaning -> integer code) is stored as a small integer with CF
    ``flag_values``/``flag_meanings``; where the kernel writes NaN it gets the code of the
    meaning ``undetermined``. ``echoes`` names a parameter this output only repeats when that
    parameter is given (a grid axis then carries it: no data variable collides with it).
    ``marks``: (value, meaning) pairs a design chart draws as labelled lines, the levels a
    designer reads the output against (K = 1, where a balancer stops helping).
    ``diagnostic``: the output describes the computation (steps, harmonics, an error
    estimate), so a jump in it across a boundary says nothing about the design.
    ``everywhere``: a value of the inputs alone or of the whole computation (the synthesized
    proportions, a threshold, a classification, a count over starts), kept at every status.
    Every other output is a design value only where the status is usable (``ok`` or one of
    the mechanism's ``usable``) and NaN elsewhere (``Mechanism.values_by_status``);
    diagnostics and echoes count as everywhere.
    """

    name: str
    units: str
    long_name: str
    symbol: str = ""
    description: str = ""
    flags: dict | None = None
    undetermined: str | None = None
    echoes: str | None = None
    marks: tuple = ()
    diagnostic: bool = False  # a count or estimate of the computation, not a design value
    everywhere: bool = False
    #: computed only when a spec lists it in ``outputs`` (it costs work the others do not)
    on_request: bool = False
    #: a whole-number count: a chart draws it as categories where it takes few values
    count: bool = False
    #: (units, factor) a chart shows the output in instead of its own: ("turn", 1/(2 pi))
    #: for a rotor angle of many turns
    chart_units: tuple | None = None
    #: the short label a chart shows beside the units (see Quantity.label)
    label: str = ""

    @property
    def is_flag(self) -> bool:
        return self.flags is not None

    @property
    def at_every_status(self) -> bool:
        """Kept at every status (see ``everywhere``), not only at the usable ones."""
        return self.everywhere or self.diagnostic or self.echoes is not None

    def flag_code_of_nan(self) -> int:
        return int(self.flags[self.undetermined])


@dataclass(frozen=True)
class Boundary:
    """What explains a boundary between two flag meanings (of ``status`` or of a flag
    output), for ``sweep boundaries``: a sentence, and the continuous output whose value at
    the crossing says where the limit is (the indicator; dimensionless), if there is one."""

    sides: frozenset
    explains: str
    indicator: str | None = None


@dataclass(frozen=True)
class Mechanism:
    """Everything the engine, the atlas and the command line need to know of a mechanism.

    ``status``: the status meanings the kernel emits (``ok`` first), a subset of the global
    table ``kernels.status.CODES`` whose codes are stable across mechanisms.
    ``usable``: statuses besides ``ok`` whose outputs are still design values.
    ``rules``: a function of {name: set of given values} (method keys as ``method.NAME``)
    returning a one-line message for a combination that is not allowed, else None; the
    ``used_when`` restrictions are checked before it.
    ``whole_axes``: grid axes the kernel rescales instead of solving again (kept whole in
    every block). ``profile_coordinate``: method record -> the profile dimension's values.
    ``boundaries``: what explains the boundaries between flag meanings that have a known
    cause (``Boundary``); the others are labelled by what the outputs do across them.
    """

    name: str
    title: str
    summary: str
    references: str
    parameters: tuple[Quantity, ...]
    outputs: tuple[Output, ...]
    status: tuple[str, ...]
    method: tuple[Quantity, ...] = ()
    usable: tuple[str, ...] = ()
    profiles: tuple[Output, ...] = ()
    profile_dim: Quantity | None = None
    profile_coordinate: Callable | None = None
    whole_axes: tuple[str, ...] = ()
    rules: Callable[[dict], str | None] | None = None
    boundaries: tuple[Boundary, ...] = ()

    def __post_init__(self):
        for kind, items in (("parameter", self.parameters), ("output", self.outputs),
                            ("profile", self.profiles), ("method key", self.method)):
            names = [q.name for q in items]
            if len(set(names)) != len(names):
                raise ValueError(f"{self.name}: repeated {kind} names")
        if not self.status or self.status[0] != "ok":
            raise ValueError(f"{self.name}: status must list 'ok' first")
        unknown = set(self.status) - set(CODES)
        if unknown:
            raise ValueError(f"{self.name}: status {sorted(unknown)} not in kernels.status")
        if not set(self.usable) <= set(self.status):
            raise ValueError(f"{self.name}: usable statuses must be declared statuses")
        if bool(self.profiles) != (self.profile_dim is not None):
            raise ValueError(f"{self.name}: profiles need a profile dimension")
        names = {p.name for p in self.parameters}
        for q in self.parameters + self.method:
            pool = names if q in self.parameters else {m.name for m in self.method}
            for other in q.used_when:
                if other not in pool:
                    raise ValueError(f"{self.name}: {q.name} used_when {other}: unknown")
        for o in self.outputs:
            if o.echoes is not None and o.echoes not in names:
                raise ValueError(f"{self.name}: {o.name} echoes an unknown parameter")
        meanings = set(self.status).union(*(o.flags for o in self.outputs if o.is_flag))
        for b in self.boundaries:
            if len(b.sides) != 2 or not b.sides <= meanings:
                raise ValueError(f"{self.name}: boundary {sorted(b.sides)} is not two meanings")
            if b.indicator is not None and self.output(b.indicator).units != "1":
                raise ValueError(f"{self.name}: indicator {b.indicator} is not dimensionless")

    def boundary(self, a: str, b: str) -> Boundary | None:
        """The declared explanation of a boundary between meanings a and b, if any."""
        for item in self.boundaries:
            if item.sides == frozenset((a, b)):
                return item
        return None

    # ---------------------------------------------------------------- lookups

    def parameter(self, name: str) -> Quantity:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    def output(self, name: str) -> Output:
        for o in self.outputs + self.profiles:
            if o.name == name:
                return o
        raise KeyError(name)

    def method_key(self, name: str) -> Quantity:
        for m in self.method:
            if m.name == name:
                return m
        raise KeyError(name)

    # ---------------------------------------------------------------- derived for the kernel

    @cached_property
    def parameter_index(self):
        """Row of each parameter in the kernel's parameter matrix: ``P.omega1``."""
        return _index("Parameters", [p.name for p in self.parameters])

    @cached_property
    def output_index(self):
        """Row of each output in the kernel's output matrix: ``O.impact_speed``."""
        return _index("Outputs", [o.name for o in self.outputs])

    @cached_property
    def profile_index(self):
        return _index("Profiles", [o.name for o in self.profiles])

    @cached_property
    def status_codes(self):
        """The global code of each declared status: ``S.not_assemblable``."""
        return namedtuple("Status", self.status)(*[CODES[s] for s in self.status])

    @cached_property
    def method_type(self):
        return namedtuple("Method", [m.name for m in self.method] + ["outputs"])

    @cached_property
    def usable_codes(self) -> np.ndarray:
        """Status codes whose points carry design values: ``ok`` and ``usable``."""
        return np.array([CODES[s] for s in ("ok",) + tuple(self.usable)], dtype=np.int8)

    def values_by_status(self, out: np.ndarray, status: np.ndarray) -> np.ndarray:
        """The one rule of what a status carries, applied to a kernel's (n_outputs, n)
        output matrix in place: outputs that are design values (not ``at_every_status``)
        become NaN wherever the status is not usable. Returns ``out``."""
        unusable = ~np.isin(status, self.usable_codes)
        if unusable.any():
            rows = [i for i, o in enumerate(self.outputs) if not o.at_every_status]
            out[np.ix_(rows, np.flatnonzero(unusable))] = np.nan
        return out

    @property
    def default_outputs(self) -> tuple[str, ...]:
        """The scalar outputs an atlas has when its spec does not list them."""
        return tuple(o.name for o in self.outputs if not o.on_request)

    def method_record(self, outputs=None, **given):
        """The kernel's method options by name: codes of the given values, defaults
        elsewhere (int for whole-number and categorical keys, float otherwise), and
        ``outputs``, the names the sweep asks for (the kernel computes no more)."""
        unknown = set(given) - {m.name for m in self.method}
        if unknown:
            raise KeyError(f"{self.name}: unknown method keys {sorted(unknown)}")
        values = []
        for m in self.method:
            code = m.encode(given.get(m.name, m.default))
            values.append(int(code) if (m.integer or m.categorical) else code)
        asked = self.default_outputs if outputs is None else tuple(outputs)
        return self.method_type(*values, asked)


# ---------------------------------------------------------------- shared declarations

#: the code of sigma = "impact" in every kernel that takes an assembly branch
SIGMA_IMPACT = 0.0
#: assembly_branch outputs: sigma itself, 0 where no branch was determined
BRANCH_FLAGS = {"minus": -1, "undetermined": 0, "plus": 1}


def assembly_branch() -> Quantity:
    """sigma: +1, -1 or the branch that makes the special position an impact."""
    return Quantity("sigma", "1", "assembly branch (sigma): +1, -1, or the impact branch",
                    symbol="σ", default="impact", label=r"branch $\sigma$",
                    choices={"impact": SIGMA_IMPACT, 1: 1, -1: -1})


def geometry_tol(what: str) -> Quantity:
    """The relative tolerance of the change-point identities (and of ``what``)."""
    return Quantity("geometry_tol", "1", "relative tolerance of the change-point identities "
                    f"and {what}; such linkages are modelled as exact change points",
                    default=1e-9, minimum=0.0, maximum=1e-3)


def path(what: str) -> Quantity:
    """The method's path through the special positions (kernels.fourbar.path_branch)."""
    return Quantity("path", "1", f"the path through the special positions for {what}: "
                    "impact (the stop reverses the rocker: one crank turn) or free (no "
                    "stop: the linkage passes each node on its smooth curve and switches "
                    "branch, the cycle two crank turns)", default="impact",
                    choices={"impact": 0, "free": 1})


def profile_points(description: str) -> Quantity:
    """The method's number of crank angles of the profiles (0: none, the default)."""
    return Quantity("profile_points", "1", description, default=0, minimum=0,
                    maximum=100000, integer=True)


def peak_samples(name: str, description: str, default: int, minimum: int) -> Quantity:
    """The method's number of crank angles sampled before each peak is refined."""
    return Quantity(name, "1", description, default=default, minimum=minimum,
                    maximum=10**6, integer=True)


def _index(kind: str, names: list[str]):
    return namedtuple(kind, names)(*range(len(names)))


def used_when_text(q: Quantity) -> str:
    """``type = "b" or "general"``: where a restricted quantity is used, in words."""
    return " and ".join(f"{other} = " + " or ".join(_word(v) for v in values)
                        for other, values in q.used_when.items())


def _word(v) -> str:
    return f'"{v}"' if isinstance(v, str) else repr(v)
