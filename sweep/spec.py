"""Sweep specs (atlas.md §1): TOML in, a validated ``Sweep`` out, or a one-line UserError.

Everything is checked here, before any compute: structure (pydantic), parameter names and
domains (the registry), cross-parameter rules (the mechanism), outputs, method and run keys.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, StrictStr
from pydantic import ValidationError

from sweep import registry
from sweep.errors import UserError
from sweep.registry import Mechanism, Parameter

MAX_POINTS = 10**10  # more than this is a typo, not a sweep
MAX_AXIS = 10**8

Number = StrictInt | StrictFloat


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


class RangeAxis(_Strict):
    start: Number
    stop: Number
    num: StrictInt = Field(ge=1, le=MAX_AXIS)
    scale: Literal["linear", "log"] = "linear"


class RunSettings(_Strict):
    chunk: StrictInt = Field(default=131072, ge=1, le=10**8)  # points per task
    workers: StrictInt | None = Field(default=None, ge=1, le=1024)  # threads; None: all cores
    compress_level: StrictInt = Field(default=1, ge=0, le=9)  # zlib level, 0 = off
    scheduler: StrictStr | None = None  # dask.distributed scheduler address


class ChartSettings(_Strict):
    x: StrictStr
    y: StrictStr
    color: StrictStr


class SpecModel(_Strict):
    mechanism: StrictStr
    title: StrictStr | None = None
    outputs: list[StrictStr] | None = None
    grid: dict[str, Any]
    fixed: dict[str, Any] = {}
    method: dict[str, Any] = {}
    run: RunSettings = RunSettings()
    chart: ChartSettings | None = None


@dataclass
class Axis:
    """One grid dimension: its labels (coordinate values) and the kernel codes."""

    parameter: Parameter
    values: np.ndarray  # float64, or str labels for a categorical parameter
    codes: np.ndarray  # float64 as the kernel reads them

    @property
    def name(self) -> str:
        return self.parameter.name


@dataclass
class Sweep:
    mechanism: Mechanism
    axes: list[Axis]
    fixed: dict[str, float]  # kernel codes of the parameters not on the grid (NaN: not given)
    outputs: list[str]
    method: dict[str, float]
    run: RunSettings
    chart: ChartSettings | None
    title: str
    spec: dict = field(default_factory=dict)  # the spec with defaults filled, JSON-able

    @property
    def scalar_outputs(self) -> list[str]:
        names = {o.name for o in self.mechanism.outputs}
        return [n for n in self.outputs if n in names]

    @property
    def profile_outputs(self) -> list[str]:
        names = {o.name for o in self.mechanism.profiles}
        return [n for n in self.outputs if n in names]

    def profile_coordinate(self) -> np.ndarray:
        if not self.profile_outputs:
            return np.empty(0)
        return self.mechanism.profile_coordinate(self.method)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def spec_json(self) -> str:
        return json.dumps(self.spec, sort_keys=False)


def _pydantic_message(err: ValidationError) -> str:
    e = err.errors()[0]
    loc = ".".join(str(x) for x in e["loc"]) or "spec"
    if e["type"] == "extra_forbidden":
        return f"{loc}: unknown key"
    if e["type"] == "missing":
        return f"{loc}: required key is missing"
    return f"{loc}: {e['msg']}"


def _axis_values(name: str, entry: Any, p: Parameter) -> tuple[np.ndarray, list]:
    """Grid entry -> (labels array, python values) with domain checks."""
    where = f"grid.{name}"
    if isinstance(entry, dict):
        if p.choices is not None:
            raise UserError(f"{where}: a categorical parameter takes a list of "
                            f"{p.domain_text()}")
        try:
            rng = RangeAxis.model_validate(entry)
        except ValidationError as err:
            raise UserError(f"{where}." + _pydantic_message(err)) from None
        start, stop = float(rng.start), float(rng.stop)
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise UserError(f"{where}: start and stop must be finite numbers")
        if rng.num == 1 and start != stop:
            raise UserError(f"{where}: num = 1 needs start = stop")
        if rng.num > 1 and start == stop:
            raise UserError(f"{where}: empty range (start = stop with num > 1)")
        if rng.scale == "log":
            if start <= 0 or stop <= 0:
                raise UserError(f"{where}: scale = \"log\" needs start > 0 and stop > 0")
            values = np.geomspace(start, stop, rng.num)
        else:
            values = np.linspace(start, stop, rng.num)
        for v in values:
            if p.check(float(v)) is not None:
                raise UserError(f"{where}: value {v:g} is outside the domain; "
                                f"allowed: {p.domain_text()}")
        return values, [float(v) for v in values]
    if isinstance(entry, list):
        if not entry:
            raise UserError(f"{where}: empty list")
        if len(entry) > MAX_AXIS:
            raise UserError(f"{where}: more than {MAX_AXIS} values")
        for v in entry:
            problem = p.check(v)
            if problem is not None:
                raise UserError(f"{where}: value {v!r} is not allowed; allowed: {problem}")
        if len({(type(v) is str, v) for v in entry}) != len(entry):
            raise UserError(f"{where}: repeated values")
        if p.choices is not None:
            return np.array([str(v) for v in entry], dtype=object), list(entry)
        return np.array([float(v) for v in entry]), [float(v) for v in entry]
    raise UserError(f"{where}: must be a table {{start, stop, num[, scale]}} or a list "
                    "of values")


def parse(text: str, source: str = "spec") -> Sweep:
    """Parse and validate a TOML spec; raise UserError with a one-line message."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise UserError(f"{source}: invalid TOML: {err}") from None
    return validate(raw)


def load(path: str | Path) -> Sweep:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError(f"spec: no such file: {path}") from None
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(f"spec: cannot read {path}: {err}") from None
    return parse(text, source=str(path))


def validate(raw: dict) -> Sweep:
    try:
        model = SpecModel.model_validate(raw)
    except ValidationError as err:
        raise UserError(_pydantic_message(err)) from None
    if model.mechanism not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {model.mechanism!r}; allowed: "
                        + ", ".join(registry.names()))
    mech = registry.get(model.mechanism)
    known = [p.name for p in mech.parameters]

    if not model.grid:
        raise UserError("grid: at least one axis is required")
    for table, entries in (("grid", model.grid), ("fixed", model.fixed)):
        for name in entries:
            if name not in known:
                raise UserError(f"{table}.{name}: unknown parameter of {mech.name}; "
                                f"allowed: {', '.join(known)}")
    for name in model.fixed:
        if name in model.grid:
            raise UserError(f"{name}: given in both [grid] and [fixed]; give it once")

    axes: list[Axis] = []
    given: dict[str, set] = {}
    grid_echo: dict[str, Any] = {}
    for name, entry in model.grid.items():
        p = mech.parameter(name)
        labels, pyvalues = _axis_values(name, entry, p)
        codes = np.array([p.encode(v) for v in pyvalues], dtype=np.float64)
        axes.append(Axis(p, labels, codes))
        given[name] = set(pyvalues)
        grid_echo[name] = entry
    size = math.prod(len(a.values) for a in axes)
    if size > MAX_POINTS:
        raise UserError(f"grid: {size:.3g} points; at most {MAX_POINTS:.0e} are allowed")

    fixed: dict[str, float] = {}
    fixed_echo: dict[str, Any] = {}
    for p in mech.parameters:
        if p.name in model.grid:
            continue
        if p.name in model.fixed:
            v = model.fixed[p.name]
            problem = p.check(v)
            if problem is not None:
                raise UserError(f"fixed.{p.name}: value {v!r} is not allowed; "
                                f"allowed: {problem}")
            given[p.name] = {v}
        elif p.default is not None:
            v = p.default
        else:
            fixed[p.name] = math.nan
            continue
        fixed[p.name] = p.encode(v)
        fixed_echo[p.name] = v
    method: dict[str, float] = {}
    method_echo: dict[str, Any] = {}
    for name in model.method:
        if name not in mech.method:
            allowed = ", ".join(mech.method) or "none"
            raise UserError(f"method.{name}: unknown method key of {mech.name}; "
                            f"allowed: {allowed}")
    for name, p in mech.method.items():
        v = model.method.get(name, p.default)
        problem = p.check(v)
        if problem is not None:
            raise UserError(f"method.{name}: value {v!r} is not allowed; allowed: {problem}")
        method[name] = p.encode(v)
        method_echo[name] = v
        if name in model.method:
            given["method." + name] = {v}
    if mech.check is not None:
        mech.check(given)  # only what the user set; the rules know the defaults
    profile_names = [o.name for o in mech.profiles]
    profiling = bool(mech.profiles) and method.get("profile_points", 0) > 0

    all_outputs = [o.name for o in mech.outputs] + profile_names
    if model.outputs is None:
        outputs = [o.name for o in mech.outputs] + (profile_names if profiling else [])
    else:
        if not model.outputs:
            raise UserError("outputs: empty list; omit the key for all outputs")
        for name in model.outputs:
            if name not in all_outputs:
                raise UserError(f"outputs: unknown output {name!r} of {mech.name}; "
                                f"allowed: {', '.join(all_outputs)}")
        if len(set(model.outputs)) != len(model.outputs):
            raise UserError("outputs: repeated names")
        for name in model.outputs:
            if name in profile_names and not profiling:
                raise UserError(f"outputs: {name} is a profile; set method.profile_points "
                                "to a number of crank angles > 0")
        outputs = list(model.outputs)

    if model.chart is not None:
        names = set(model.grid) | set(outputs)
        if mech.profile_dim is not None and profiling:
            names.add(mech.profile_dim.name)
        for axis in ("x", "y", "color"):
            v = getattr(model.chart, axis)
            if v not in names:
                raise UserError(f"chart.{axis}: {v!r} is neither a grid axis nor an output "
                                "of this sweep")

    spec = {
        "mechanism": mech.name,
        "title": model.title or mech.title,
        "outputs": outputs,
        "grid": grid_echo,
        "fixed": fixed_echo,
        "method": method_echo,
        "run": model.run.model_dump(),
    }
    if model.chart is not None:
        spec["chart"] = model.chart.model_dump()
    return Sweep(mech, axes, fixed, outputs, method, model.run, model.chart,
                 spec["title"], spec)
