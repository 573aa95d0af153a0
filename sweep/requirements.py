"""Requirements as data: the limits a design must meet (``impact_speed <= 10``,
``transmission_angle_working >= 40deg``), given in a spec's ``[requirements]`` table or on
the command line (``--require``), recorded in the atlas and evaluated at every grid point
into a flag variable, ``requirements``, that query, chart, info and boundaries read like
any other flag:

- ``met``: every limit holds;
- ``no_value``: a limit's output has no value at this point (its status has none);
- ``above_NAME`` / ``below_NAME``: the limit the design fails by the most (relative to the
  limit), the binding one.

``requirement_margin`` is the smallest relative slack over the limits: (limit - value)/|limit|
for an upper limit, the other way round for a lower one; negative where one fails. A limit
of 0 is taken relative to 1 in the output's units.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

import numpy as np

from sweep.errors import UserError

MET, NO_VALUE = 0, 1
#: a limit: NAME OP NUMBER, the number optionally in degrees for an angle
_LIMIT = re.compile(r"^\s*([A-Za-z_]\w*)\s*(<=|>=|<|>)\s*([-+0-9.eE]+)\s*(deg|°)?\s*$")
_SIDE = re.compile(r"^\s*(<=|>=|<|>)\s*([-+0-9.eE]+)\s*(deg|°)?\s*$")


@dataclass(frozen=True)
class Limit:
    """One requirement: ``name op value`` with value in the output's own units."""

    name: str
    op: str
    value: float
    text: str

    @property
    def upper(self) -> bool:
        return self.op in ("<=", "<")

    @property
    def meaning(self) -> str:
        """The flag meaning of failing it."""
        return f"{'above' if self.upper else 'below'}_{self.name}"

    def holds(self, values: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return {"<=": values <= self.value, "<": values < self.value,
                    ">=": values >= self.value, ">": values > self.value}[self.op]

    def slack(self, values: np.ndarray) -> np.ndarray:
        """(limit - value)/|limit| for an upper limit, (value - limit)/|limit| for a lower
        one (|limit| of 0 taken as 1): positive where it holds."""
        scale = abs(self.value) or 1.0
        return ((self.value - values) if self.upper else (values - self.value)) / scale


def _number(text: str, degrees: str | None, name: str, units: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise UserError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise UserError(f"{where}: the limit must be a finite number")
    if degrees:
        if units != "rad":
            raise UserError(f"{where}: {name} is in {units or 'no units'}, not an angle in "
                            "rad; drop the deg")
        value = math.radians(value)
    return value


def parse_limit(text: str, units_of: dict[str, str], where: str = "require") -> Limit:
    """A limit ``NAME OP NUMBER[deg]``; NAME must be a numeric output (``units_of``: its
    units by name)."""
    match = _LIMIT.match(str(text))
    if not match:
        raise UserError(f"{where}: {text!r} must be NAME <= NUMBER (or <, >=, >), e.g. "
                        "\"impact_speed <= 10\" or \"transmission_angle_working >= 40deg\"")
    name, op, number, degrees = match.groups()
    return _limit(name, op, number, degrees, text, units_of, where)


def _limit(name, op, number, degrees, text, units_of, where) -> Limit:
    if name not in units_of:
        raise UserError(f"{where}: {name!r} is not a numeric output of this mechanism; "
                        "allowed: " + ", ".join(sorted(units_of)))
    value = _number(number, degrees, name, units_of[name], where)
    return Limit(name, op, value, " ".join(str(text).split()))


def from_table(table: dict, units_of: dict[str, str]) -> tuple[Limit, ...]:
    """A spec's ``[requirements]``: NAME = "<= 10" or NAME = [">= 40deg", "<= 80deg"]."""
    limits = []
    for name, sides in table.items():
        for side in ([sides] if isinstance(sides, str) else sides if isinstance(sides, list)
                     else [None]):
            where = f"requirements.{name}"
            match = _SIDE.match(side) if isinstance(side, str) else None
            if not match:
                raise UserError(f"{where}: must be a string \"<= NUMBER\" (or <, >=, >; "
                                "NUMBERdeg for an angle) or a list of them")
            op, number, degrees = match.groups()
            limits.append(_limit(name, op, number, degrees, f"{name} {side.strip()}",
                                 units_of, where))
    return check(tuple(limits))


def check(limits: tuple[Limit, ...]) -> tuple[Limit, ...]:
    """At most one limit per output and side (their failures are named by it)."""
    seen = set()
    for limit in limits:
        if limit.meaning in seen:
            raise UserError(f"requirements: two {'upper' if limit.upper else 'lower'} limits "
                            f"on {limit.name}; give one")
        seen.add(limit.meaning)
    return limits


def flag_meanings(limits: tuple[Limit, ...]) -> list[str]:
    return ["met", "no_value"] + [limit.meaning for limit in limits]


def evaluate(values: dict[str, np.ndarray], limits: tuple[Limit, ...]):
    """(flag codes, margin) at every point from the limits' outputs: met, no_value, or the
    code of the most violated limit; the margin is the smallest slack."""
    shape = np.shape(next(iter(values.values())))
    missing = np.zeros(shape, bool)
    margin = np.full(shape, np.inf)
    worst = np.full(shape, np.inf)
    code = np.full(shape, MET, np.int8)
    for k, limit in enumerate(limits):
        v = np.asarray(values[limit.name], dtype=float)
        missing |= ~np.isfinite(v)
        slack = limit.slack(v)
        fails = ~limit.holds(v) & np.isfinite(v)
        binding = fails & (slack < worst)
        code = np.where(binding, np.int8(2 + k), code)
        worst = np.where(binding, slack, worst)
        margin = np.minimum(margin, np.where(np.isfinite(slack), slack, np.inf))
    code = np.where(missing & (code == MET), np.int8(NO_VALUE), code)
    margin = np.where(missing, np.nan, margin)
    return code.astype(np.int8), margin


def attributes(limits: tuple[Limit, ...]) -> dict:
    """The flag variable's CF attributes."""
    return {"label": "requirements",
            "long_name": "which requirement the design fails (the most violated one), or "
                         "met", "units": "1",
            "flag_values": np.arange(len(limits) + 2, dtype=np.int8),
            "flag_meanings": " ".join(flag_meanings(limits)),
            "requirements": json.dumps([limit.text for limit in limits])}


MARGIN_ATTRIBUTES = {"label": "requirement margin",
                     "long_name": "smallest relative slack over the requirements "
                                  "((limit - value)/|limit| for an upper limit; negative "
                                  "where one fails)", "units": "1"}


def numeric_outputs(mech) -> dict[str, str]:
    """The outputs a limit may name: numeric, one value per design: {name: units}."""
    return {o.name: o.units for o in mech.outputs if not o.is_flag}


def of_dataset(ds) -> tuple[Limit, ...]:
    """The limits recorded in an atlas (its spec's requirements)."""
    spec = json.loads(ds.attrs.get("spec", "{}"))
    table = spec.get("requirements") or {}
    if not table:
        return ()
    units = {name: ds[name].attrs.get("units", "") for name in table if name in ds}
    return from_table(table, {**units, **{n: ds[n].attrs.get("units", "")
                                          for n in ds.data_vars}})


def with_requirements(ds, limits: tuple[Limit, ...]):
    """The atlas with the flag and margin of ``limits`` (replacing any stored ones),
    evaluated on its outputs as they are stored."""
    import xarray as xr

    for limit in limits:
        if limit.name not in ds.data_vars:
            raise UserError(f"require: {limit.name!r} is not a variable of this atlas")
    grid = list(ds["status"].dims)
    values = {limit.name: ds[limit.name].broadcast_like(ds["status"]).transpose(*grid).values
              for limit in limits}
    code, margin = evaluate(values, limits)
    ds = ds.copy()
    ds["requirements"] = xr.DataArray(code, dims=grid, attrs=attributes(limits))
    ds["requirement_margin"] = xr.DataArray(margin, dims=grid, attrs=MARGIN_ATTRIBUTES)
    return ds
