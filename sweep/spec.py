"""Sweep specs: TOML in, a validated ``Sweep`` out, or a one-line UserError.

Everything is checked here, before any compute, as a sequence of named checks (``validate``):
the structure (pydantic), the mechanism, parameter names, grid axes and fixed values against
their declared domains, method keys, where each quantity is used, the mechanism's own rules
between parameters, the outputs, and the chart.
"""

from __future__ import annotations

import json
import math
import stat
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, StrictStr
from pydantic import ValidationError

from kernels.declaration import Mechanism, Quantity, used_when_text
from sweep import registry
from sweep.domains import check_value, domain_text
from sweep.errors import UserError

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
    at: dict[str, float] = {}  # other grid axes taken at one value (nearest)
    boundaries: StrictStr | None = None  # a flag variable whose boundaries are refined, drawn
    overlay: StrictStr | None = None  # a numeric output drawn as contour lines on top

    def at_values(self) -> dict[str, tuple[float, str]]:
        return {name: (value, "") for name, value in self.at.items()}


class SpecModel(_Strict):
    mechanism: StrictStr
    title: StrictStr | None = None
    outputs: list[StrictStr] | None = None
    grid: dict[str, Any]
    fixed: dict[str, Any] = {}
    method: dict[str, Any] = {}
    run: RunSettings = RunSettings()
    chart: ChartSettings | None = None
    requirements: dict[str, Any] = {}


@dataclass
class Axis:
    """One grid dimension: its labels (coordinate values) and the kernel codes; or the
    designs of another atlas (a chained sweep), each setting several parameters."""

    parameter: Quantity
    values: np.ndarray  # float64, or str labels for a categorical parameter
    codes: np.ndarray  # float64 as the kernel reads them
    #: a design axis: {parameter: kernel codes per design}, and its coordinates
    #: {name: (values per design, attrs)}
    columns: dict = field(default_factory=dict)
    coordinates: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.parameter.name

    @property
    def is_design(self) -> bool:
        return bool(self.columns)

    def parameters(self) -> dict[str, np.ndarray]:
        """{parameter: kernel codes along the axis}: the axis's own, or its designs'."""
        return self.columns if self.columns else {self.name: self.codes}


#: the design axis of a chained sweep: which design of the source's selection
DESIGN_AXIS = Quantity("design", "1", "design of the source atlas's selection (its place "
                       "in the source's grid order)", integer=True)


@dataclass
class Sweep:
    """A validated sweep: what the engine computes and the atlas records."""

    mechanism: Mechanism
    kernel: Callable  # the kernel entry point run(params, method)
    axes: list[Axis]
    fixed: dict[str, float]  # kernel codes of the parameters not on the grid (NaN: not given)
    outputs: list[str]  # the atlas's output variables (scalars, then profiles)
    method: dict[str, Any]  # method options as the user reads them (words, numbers)
    method_record: Any  # the same options as the kernel reads them (by name)
    run: RunSettings
    chart: ChartSettings | None
    title: str
    spec: dict = field(default_factory=dict)  # the spec with defaults filled, JSON-able
    source: dict = field(default_factory=dict)  # the document as given (+ run overrides)
    requirements: tuple = ()  # the limits a design must meet (sweep.requirements.Limit)
    designs: Any = None  # a chained sweep's resolved source (sweep.chains.Designs)
    #: what the run does that the spec did not say in so many words, one line each: said
    #: at the start of a run and recorded in the atlas (``notes``)
    notes: tuple = ()

    def __reduce__(self):
        # rebuilt from the document it came from (deterministic), e.g. on a cluster worker;
        # a chained sweep's designs travel with it (the worker may not see the source)
        return validate, (self.source, self.designs)

    @classmethod
    def from_toml(cls, path: str | Path) -> Sweep:
        """A spec file (TOML), validated: ``Sweep.from_toml("cr.toml")``."""
        return load(path)

    @classmethod
    def from_dict(cls, document) -> Sweep:
        """A spec document as a dict (the TOML's tables as dicts), validated:
        ``Sweep.from_dict({"mechanism": "crank_rocker", "grid": {"R": [0.2, 0.3]}})``.
        Python's own sequences stand for TOML's arrays: a grid axis may be a list, a
        tuple, a range or a numpy array (``np.linspace(0.1, 0.4, 7)``), and numpy's
        numbers are numbers."""
        if not isinstance(document, dict):
            try:
                document = dict(document)
            except (TypeError, ValueError):
                raise UserError("spec: a dict of the spec's tables") from None
        return validate(plain(document))

    @classmethod
    def from_text(cls, text: str) -> Sweep:
        """A spec as TOML text, validated."""
        return parse(text)

    def to_dict(self) -> dict:
        """The spec with its defaults filled in, as the atlas records it."""
        return json.loads(self.spec_json())

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
        return self.mechanism.profile_coordinate(self.method_record)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def spec_json(self) -> str:
        return json.dumps(self.spec, sort_keys=False)

    def with_run(self, **changes) -> Sweep:
        """The same sweep with run settings changed (command-line overrides), recorded in
        the spec; a value of None leaves a setting as it is."""
        changes = {k: v for k, v in changes.items() if v is not None}
        if not changes:
            return self
        try:
            run = RunSettings.model_validate(self.run.model_dump() | changes)
        except ValidationError as err:
            raise UserError("run." + _pydantic_message(err)) from None
        run = RunSettings.model_construct(_fields_set=self.run.model_fields_set | set(changes),
                                          **run.model_dump())
        source = self.source | {"run": self.source.get("run", {}) | changes}
        return replace(self, run=run, spec=self.spec | {"run": run.model_dump()},
                       source=source)


# ---------------------------------------------------------------- reading a spec

#: a spec file larger than this is not a spec (a grid of values belongs in ranges)
MAX_SPEC_BYTES = 10 * 1024**2


def parse(text: str, source: str = "spec") -> Sweep:
    """Parse and validate a TOML spec; raise UserError with a one-line message."""
    text = text.removeprefix("\ufeff")  # a byte-order mark, as Windows editors write it
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise UserError(f"{source}: invalid TOML: {err}") from None
    except RecursionError:
        raise UserError(f"{source}: tables or arrays nested too deeply") from None
    return validate(raw)


def load(path: str | Path) -> Sweep:
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise UserError(f"spec: no such file: {path}") from None
    except OSError as err:
        raise UserError(f"spec: cannot read {path}: {err.strerror or err}") from None
    if stat.S_ISDIR(info.st_mode):
        raise UserError(f"spec: {path} is a directory, not a spec file")
    if not stat.S_ISREG(info.st_mode):  # a FIFO or a device would block or never end
        raise UserError(f"spec: {path} is not a regular file")
    if info.st_size > MAX_SPEC_BYTES:
        raise UserError(f"spec: {path} is {info.st_size:,} bytes; a spec is at most "
                        f"{MAX_SPEC_BYTES:,}")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(f"spec: cannot read {path}: {err}") from None
    return parse(text, source=str(path))


def plain(value):
    """A spec document from Python with TOML's types: tuples, ranges and numpy arrays as
    lists, numpy's scalars as Python's, tables as dicts (recursively)."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (list, tuple, range)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def validate(raw: dict, designs=None) -> Sweep:
    """A spec document (as read from TOML) -> a Sweep, or a one-line UserError.
    ``designs``: a chained sweep's source already resolved (sweep.chains.Designs)."""
    try:
        return _validate(raw, designs)
    except RecursionError:
        raise UserError("spec: tables or arrays nested too deeply") from None


def _validate(raw: dict, designs=None) -> Sweep:
    model = _structure(raw)
    kernel = _mechanism(model)
    mech = kernel.declaration
    _known_names(model, mech)
    designs = _source(model, mech, designs)
    axes = _grid(model, mech, designs)
    fixed, fixed_echo = _fixed(model, mech, designs)
    method, record = _method(model, mech)
    given = _given(model, mech, axes, method)
    _where_used(mech, given, method)
    outputs = _outputs(model, mech, axes, record)
    outputs, notes = _with_required_outputs(model, mech, outputs)
    if designs is not None:
        from sweep import chains

        notes += chains.notes(designs, mech, {*model.grid, *model.fixed})
    given["outputs"] = set(outputs)
    _mechanism_rules(mech, given)
    record = record._replace(outputs=tuple(outputs))
    limits = _requirements(model, mech, record)
    _chart(model, mech, axes, outputs)
    fixed_echo, method = _in_use(mech, given, fixed_echo, method)
    spec = {
        "mechanism": mech.name,
        "title": model.title or mech.title,
        "outputs": outputs,
        "grid": ({"from": designs.record} if designs else {})
        | {k: v for k, v in model.grid.items() if k != "from"},
        "fixed": fixed_echo,
        "method": method,
        "run": model.run.model_dump(),
    }
    if model.chart is not None:
        spec["chart"] = model.chart.model_dump()
    if limits:
        spec["requirements"] = dict(model.requirements)
    return Sweep(mech, kernel.run, axes, fixed, outputs, method, record, model.run,
                 model.chart, spec["title"], spec, raw, limits, designs, notes)


def _pydantic_message(err: ValidationError) -> str:
    e = err.errors()[0]
    loc = ".".join(str(x) for x in e["loc"]) or "spec"
    if e["type"] == "extra_forbidden":
        return f"{loc}: unknown key"
    if e["type"] == "missing":
        return f"{loc}: required key is missing"
    return f"{loc}: {e['msg']}"


def _structure(raw: dict) -> SpecModel:
    """Keys, tables and their types."""
    try:
        return SpecModel.model_validate(raw)
    except ValidationError as err:
        raise UserError(_pydantic_message(err)) from None


def _mechanism(model: SpecModel) -> registry.Kernel:
    if model.mechanism not in registry.names():
        raise UserError(f"mechanism: unknown mechanism {model.mechanism!r}; allowed: "
                        + ", ".join(registry.names()))
    return registry.get(model.mechanism)


def _known_names(model: SpecModel, mech: Mechanism) -> None:
    """Every grid and fixed name is a parameter, given once; every method key is known."""
    known = [p.name for p in mech.parameters]
    if not model.grid:
        raise UserError("grid: at least one axis is required")
    for table, entries in (("grid", model.grid), ("fixed", model.fixed)):
        for name in entries:
            if name not in known and (table, name) != ("grid", "from"):
                raise UserError(f"{table}.{name}: unknown parameter of {mech.name}; "
                                f"allowed: {', '.join(known)}")
    for name in model.fixed:
        if name in model.grid:
            raise UserError(f"{name}: given in both [grid] and [fixed]; give it once")
    keys = [m.name for m in mech.method]
    for name in model.method:
        if name not in keys:
            raise UserError(f"method.{name}: unknown method key of {mech.name}; "
                            f"allowed: {', '.join(keys) or 'none'}")


def _source(model: SpecModel, mech: Mechanism, designs=None):
    """A chained sweep's designs (``grid.from``), resolved from the source atlas unless
    given; their parameters are set by them alone."""
    if "from" not in model.grid:
        return None
    from sweep import chains

    if designs is None:
        designs = chains.resolve(model.grid["from"], mech)
    for name in designs.columns:
        replaced = mech.parameter(name).replaces
        for table, entries in (("grid", model.grid), ("fixed", model.fixed)):
            if name in entries:
                raise UserError(f"{table}.{name}: set by the source designs (grid.from); "
                                "give it once")
            if replaced in entries:  # e.g. the source's crank speed sets the idle speed
                raise UserError(f"{table}.{replaced}: follows from {name}, which the "
                                "source designs set (grid.from); leave it out")
    return designs


def _grid(model: SpecModel, mech: Mechanism, designs=None) -> list[Axis]:
    """The grid axes with their values and kernel codes, once the grid's size, counted from
    the axis specifications, is known to be allowed (nothing is built before); a chained
    sweep's designs first."""
    size = math.prod(designs.count if name == "from" else axis_length(f"grid.{name}", entry)
                     for name, entry in model.grid.items())
    if size > MAX_POINTS:
        raise UserError(f"grid: {size:.3g} points; at most {MAX_POINTS:.0e} are allowed")
    axes = []
    if designs is not None:
        axes.append(Axis(DESIGN_AXIS, np.arange(designs.count, dtype=np.int64),
                         np.arange(designs.count, dtype=float), designs.columns,
                         designs.coordinates))
    for name, entry in model.grid.items():
        if name == "from":
            continue
        p = mech.parameter(name)
        labels, values = _axis_values(name, entry, p)
        axes.append(Axis(p, labels, np.array([p.encode(v) for v in values])))
    return axes


def axis_length(where: str, entry: Any) -> int:
    """How many values a grid entry gives, from its specification alone (a range's num, a
    list's length); its structure is checked, its values are not."""
    if isinstance(entry, dict):
        try:
            return RangeAxis.model_validate(entry).num
        except ValidationError as err:
            raise UserError(f"{where}." + _pydantic_message(err)) from None
    if isinstance(entry, list):
        if len(entry) > MAX_AXIS:
            raise UserError(f"{where}: more than {MAX_AXIS} values")
        return len(entry)
    raise UserError(f"{where}: must be a table {{start, stop, num[, scale]}} or a list "
                    "of values")


def grid_shape(document: dict) -> tuple[int, ...] | None:
    """The grid's shape a spec document asks for, from its axis specifications alone (an
    atlas's recorded spec is compared with the atlas before it is run again); None where
    the document has no readable grid."""
    from sweep.chains import declared_count

    grid = document.get("grid") if isinstance(document, dict) else None
    if not isinstance(grid, dict):
        return None
    try:
        return tuple(declared_count(entry) if name == "from"
                     else axis_length(f"grid.{name}", entry) for name, entry in grid.items())
    except UserError:
        return None


def _axis_values(name: str, entry: Any, p: Quantity) -> tuple[np.ndarray, list]:
    """Grid entry -> (labels array, python values) with domain checks."""
    where = f"grid.{name}"
    if isinstance(entry, dict):
        if p.choices is not None:
            raise UserError(f"{where}: a categorical parameter takes a list of "
                            f"{domain_text(p)}")
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
        # a range is monotonic: its ends bound it, and only 0 can fall inside a hole
        zero = values[values == 0.0][:1] if p.nonzero else values[:0]
        for v in [values[0], values[-1], *zero]:
            if check_value(p, int(v) if p.integer and float(v).is_integer() else float(v)):
                raise UserError(f"{where}: value {v:g} is outside the domain; "
                                f"allowed: {domain_text(p)}")
        return values, [float(v) for v in values]
    if isinstance(entry, list):
        if not entry:
            raise UserError(f"{where}: empty list")
        if len(entry) > MAX_AXIS:
            raise UserError(f"{where}: more than {MAX_AXIS} values")
        for v in entry:
            problem = check_value(p, v)
            if problem is not None:
                raise UserError(f"{where}: value {v!r} is not allowed; allowed: {problem}")
        if len({(type(v) is str, v) for v in entry}) != len(entry):
            raise UserError(f"{where}: repeated values")
        if p.choices is not None:
            return np.array([str(v) for v in entry], dtype=object), list(entry)
        # an axis increases whatever the list's order: a chart's cells and a refined
        # boundary lie between neighbouring values
        numbers = sorted(float(v) for v in entry)
        return np.array(numbers), numbers
    raise UserError(f"{where}: must be a table {{start, stop, num[, scale]}} or a list "
                    "of values")


def _fixed(model: SpecModel, mech: Mechanism,
           designs=None) -> tuple[dict[str, float], dict[str, Any]]:
    """Kernel codes of every parameter not on the grid (given, default or NaN = not given),
    and the values as the atlas records them."""
    codes, echo = {}, {}
    given = set(model.grid) | set(model.fixed) | set(designs.columns if designs else ())
    replaced = {p.replaces for p in mech.parameters if p.replaces and p.name in given}
    for p in mech.parameters:
        if p.name in model.grid or (designs is not None and p.name in designs.columns):
            continue
        if p.name in replaced and p.name not in model.fixed:
            value = None  # derived by the kernel from what stands in for it
        elif p.name in model.fixed:
            value = model.fixed[p.name]
            problem = check_value(p, value)
            if problem is not None:
                raise UserError(f"fixed.{p.name}: value {value!r} is not allowed; "
                                f"allowed: {problem}")
        else:
            value = p.default
        codes[p.name] = p.encode(value)
        if value is not None:
            echo[p.name] = value
    return codes, echo


def _method(model: SpecModel, mech: Mechanism) -> tuple[dict[str, Any], Any]:
    """Method options (given or default) in words, and the kernel's record of them."""
    words = {}
    for m in mech.method:
        value = model.method.get(m.name, m.default)
        problem = check_value(m, value)
        if problem is not None:
            raise UserError(f"method.{m.name}: value {value!r} is not allowed; "
                            f"allowed: {problem}")
        words[m.name] = value
    return words, mech.method_record(**words)


def _given(model: SpecModel, mech: Mechanism, axes: list[Axis],
           method: dict) -> dict[str, set]:
    """What the user set: {parameter: its values}, {"method.KEY": {value}}."""
    given = {}
    for axis in axes:
        if not axis.is_design:
            given[axis.name] = set(_python_values(axis))
        for name, codes in axis.columns.items():  # the words or numbers the designs set
            given[name] = {mech.parameter(name).decode(c) for c in np.unique(codes).tolist()}
    for name, value in model.fixed.items():
        given[name] = {value}
    for name, value in model.method.items():
        given["method." + name] = {value}
    return given


def _python_values(axis: Axis) -> list:
    if axis.parameter.choices is not None:
        return [axis.parameter.decode(c) for c in axis.codes]
    return [float(v) for v in axis.values]


def is_used(mech: Mechanism, q: Quantity, prefix: str, given: dict[str, set]) -> bool:
    """Whether a quantity means something for the values given (defaults elsewhere);
    ``prefix`` is "method." for a method key."""
    pool = mech.parameters if not prefix else mech.method
    for other, values in q.used_when.items():
        default = next(o.default for o in pool if o.name == other)
        if not given.get(prefix + other, {default}) & set(values):
            return False
    return True


def _where_used(mech: Mechanism, given: dict[str, set], method: dict) -> None:
    """A quantity given where the declaration says it means nothing is an error."""
    for q, key, prefix in ([(p, p.name, "") for p in mech.parameters]
                           + [(m, "method." + m.name, "method.") for m in mech.method]):
        if key in given and not is_used(mech, q, prefix, given):
            raise UserError(f"{key}: used only with {used_when_text(q)}")


def _in_use(mech: Mechanism, given: dict[str, set], fixed: dict, method: dict) -> tuple:
    """The fixed values and method options that mean something for this sweep: what the
    atlas records (a recorded spec runs again as it is, and says only what was used)."""
    return ({k: v for k, v in fixed.items()
             if is_used(mech, mech.parameter(k), "", given)},
            {k: v for k, v in method.items()
             if is_used(mech, mech.method_key(k), "method.", given)})


def _mechanism_rules(mech: Mechanism, given: dict[str, set]) -> None:
    if mech.rules is not None:
        problem = mech.rules(given)
        if problem:
            raise UserError(problem)


def _outputs(model: SpecModel, mech: Mechanism, axes: list[Axis], record) -> list[str]:
    """The atlas's output variables: the ones asked for (default all scalars, and the
    profiles when the method asks for them), without outputs that only echo a grid axis
    (the axis's coordinate carries them)."""
    scalars = [o.name for o in mech.outputs]
    defaults = list(mech.default_outputs)
    profiles = [o.name for o in mech.profiles]
    profiling = bool(profiles) and len(mech.profile_coordinate(record)) > 0
    on_grid = {name for axis in axes for name in axis.parameters()}
    echoes = {o.name for o in mech.outputs if o.echoes in on_grid}
    if model.outputs is None:
        wanted = defaults + ([o.name for o in mech.profiles if not o.on_request]
                             if profiling else [])
    else:
        if not model.outputs:
            raise UserError("outputs: empty list; omit the key for all outputs")
        for name in model.outputs:
            if name not in scalars + profiles:
                raise UserError(f"outputs: unknown output {name!r} of {mech.name}; "
                                f"allowed: {', '.join(scalars + profiles)}")
            if name in profiles and not profiling:
                raise UserError(f"outputs: {name} is a profile; set method.profile_points "
                                "to a number of crank angles > 0")
        if len(set(model.outputs)) != len(model.outputs):
            raise UserError("outputs: repeated names")
        wanted = list(model.outputs)
    return [name for name in wanted if name not in echoes]


def _with_required_outputs(model: SpecModel, mech: Mechanism,
                           outputs: list[str]) -> tuple[list[str], tuple]:
    """The outputs with each one a requirement names added where the spec's ``outputs``
    leave it out (the atlas then holds what its requirements read), and a note of it."""
    from sweep import requirements

    numeric = requirements.numeric_outputs(mech)
    missing = [name for name in dict.fromkeys(model.requirements)
               if name in numeric and name not in outputs]
    if not missing:
        return outputs, ()
    them = "it" if len(missing) == 1 else "them"
    return outputs + missing, (f"outputs: {', '.join(missing)} added to the atlas (a "
                               f"requirement reads {them})",)


def _requirements(model: SpecModel, mech: Mechanism, record) -> tuple:
    """The spec's limits, each on a numeric output the kernel computes (an output on
    request must be asked for)."""
    from sweep import requirements

    limits = requirements.from_table(model.requirements,
                                     requirements.numeric_outputs(mech))
    for limit in limits:
        if mech.output(limit.name).on_request and limit.name not in record.outputs:
            raise UserError(f"requirements.{limit.name}: computed only on request; add it to "
                            "outputs")
    return limits


def _chart(model: SpecModel, mech: Mechanism, axes: list[Axis], outputs: list[str]) -> None:
    if model.chart is None:
        return
    names = {axis.name for axis in axes} | set(outputs) | {"status"}
    if model.requirements:
        names |= {"requirements", "requirement_margin"}
    profiles = {p.name for p in mech.profiles}
    for axis in ("x", "y", "color"):
        v = getattr(model.chart, axis)
        if v not in names:
            raise UserError(f"chart.{axis}: {v!r} is neither a grid axis nor an output "
                            "of this sweep (nor status)")
        if v in profiles:
            raise UserError(f"chart.{axis}: {v!r} is a profile; pick an output with one "
                            "value per design")
    numeric_axes = [a.name for a in axes if not a.parameter.categorical and not a.is_design]
    for axis in ("x", "y"):
        if getattr(model.chart, axis) not in numeric_axes:
            raise UserError(f"chart.{axis}: {getattr(model.chart, axis)!r} is not a numeric "
                            "grid axis; a design chart is drawn over two of them ("
                            + ", ".join(numeric_axes) + ")")
    if model.chart.x == model.chart.y:
        raise UserError(f"chart.y: {model.chart.y!r} is also the x axis; pick two different "
                        "variables")
    for axis in ("x", "y"):
        if getattr(model.chart, axis) in model.chart.at:
            raise UserError(f"chart.at: {getattr(model.chart, axis)!r} is the chart's {axis} "
                            "axis; take another axis at one value")
    by_name = {axis.name: axis for axis in axes}
    for name, value in model.chart.at.items():
        axis = by_name.get(name)
        if axis is None or axis.parameter.categorical or axis.is_design:
            raise UserError(f"chart.at: {name!r} is not a numeric grid axis; allowed: "
                            + ", ".join(numeric_axes))
        lo, hi = float(np.min(axis.values)), float(np.max(axis.values))
        if not lo <= value <= hi:
            raise UserError(f"chart.at.{name}: {value:g} is outside the grid, {lo:g} to {hi:g}")
    flags = (["status"] + (["requirements"] if model.requirements else [])
             + [name for name in outputs if mech.output(name).is_flag])
    if model.chart.boundaries is not None and model.chart.boundaries not in flags:
        raise UserError(f"chart.boundaries: {model.chart.boundaries!r} is not a flag variable "
                        "of this sweep; allowed: " + ", ".join(flags))
    numeric = [name for name in outputs if not mech.output(name).is_flag
               and name not in {p.name for p in mech.profiles}]
    if model.chart.overlay is not None and model.chart.overlay not in numeric:
        raise UserError(f"chart.overlay: {model.chart.overlay!r} is not a numeric output of "
                        "this sweep; allowed: " + ", ".join(numeric))
    others = [a.name for a in axes if a.name not in (model.chart.x, model.chart.y)
              and a.name not in model.chart.at and len(a.values) > 1]
    if len(others) > 1:
        raise UserError(f"chart: more than one other axis to panel over ({', '.join(others)});"
                        " take all but one at a value with chart.at")
