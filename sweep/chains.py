"""Chained sweeps: a spec's grid made of the designs of another atlas.

    mechanism = "linkage_forces"
    [grid]
    from = {atlas = "cr.nc", where = 'type == "a"', carry = ["blow_energy"]}
    m2 = [2.0, 3.0]                # other axes as usual, after the designs

The source's feasible designs (status ok, its requirements met) that satisfy ``where``
become one grid axis, ``design``, in the source's grid order; each of them sets the target
mechanism's parameters through a mapping of names, declared once per pair of mechanisms
below (``MAPPINGS``; between two atlases of one mechanism, the parameters that vary per
design) and extended or overridden by the spec's ``map``: target parameter =
an expression over the source's variables in the query language (``lambda0 *
crank_length``), a quoted word for a categorical parameter (``'"general"'``), or a
source's categorical variable by name. A front written by ``sweep pareto -o`` is a source
too. The source's grid axes at each design, and the variables named in ``carry``, become
coordinates ``source_NAME`` along ``design`` (a front of the two atlases' outputs together).

The resolved selection is pinned in the recorded spec (``designs``: how many, ``sha256``:
a hash of the parameter values they set), so a resumed run or a refinement that finds the
source changed refuses to mix two sources; the source's path, title, spec and code version
are recorded in the atlas (``source_atlas``).
"""

from __future__ import annotations

import ast
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sweep.errors import UserError

DESIGN = "design"
SOURCE_PREFIX = "source_"


@dataclass(frozen=True)
class Mapping:
    """How one mechanism's designs set another's parameters: {target parameter:
    expression over the source's variables}, and a condition every design must meet.
    ``optional``: entries that apply where the source has every variable they name (an
    input the source may not have been given); where it does not, the target keeps its own
    value, and the run says so. ``own``: the target's parameters the source design does not
    give (a quantity its model has not), said at the start of a run where the spec leaves
    them at the target's defaults, ``own_why`` saying why."""

    columns: dict
    requires: str | None = None
    why: str = ""
    optional: dict = field(default_factory=dict)
    own: tuple = ()
    own_why: str = ""


#: the declared mappings: (source mechanism, target mechanism) -> Mapping
MAPPINGS = {
    ("crank_rocker", "linkage_forces"): Mapping(
        {"l0": "lambda0 * crank_length", "l1": "crank_length",
         "l2": "lambda2 * crank_length", "l3": "lambda3 * crank_length",
         "omega1": "omega1"},
        # the rocker's inertia about D where the source has one, all of it as J3 with no
        # mass (the source knows no centroid: the rocker's weight is not in it)
        optional={"J3": "rocker_inertia", "m3": "0 * rocker_inertia"},
        own=("m1", "m2", "J1", "J2"), own_why="the source models no crank or coupler mass"),
    ("crank_rocker", "impact_machine"): Mapping(
        # the linkage, the material it was synthesised for and the crank speed it was
        # designed at (the machine's motor is sized for it: its idle speed solved); the
        # rocker's inertia about D where the source has one (all of it as J3, no mass)
        {"type": '"general"', "lambda0": "lambda0", "lambda2": "lambda2",
         "lambda3": "lambda3", "crank_length": "crank_length", "R": "R",
         "omega1": "abs(omega1)"},
        optional={"J3": "rocker_inertia", "m3": "0 * rocker_inertia"}),
    ("crank_rocker", "six_link"): Mapping(
        {"mu4": "lambda2", "mu5": "lambda3"}, requires='type == "b"',
        why="six_link's second stage is a type b four-bar (largest rocker): mu4 = lambda2, "
            "mu5 = lambda3, its base 1 - mu4 + mu5 = lambda0",
        optional={"rocker_inertia": "rocker_inertia"},
        own=("crank_length", "omega1"),
        own_why="the source's crank length and speed are its second stage's; these are the "
                "first stage's, whose ratio to the second's varies over the cycle"),
    ("crank_rocker", "six_link_forces"): Mapping(
        # the source's striker linkage as stage 2, its rocker's inertia about the pivot as
        # J5 with no mass (as for linkage_forces); the single four-bar the outputs compare
        # with is then the source's linkage at the same mean energy per blow
        {"mu4": "lambda2", "mu5": "lambda3"}, requires='type == "b"',
        why="six_link_forces' second stage is a type b four-bar (largest rocker): mu4 = "
            "lambda2, mu5 = lambda3, its base 1 - mu4 + mu5 = lambda0",
        optional={"J5": "rocker_inertia", "m5": "0 * rocker_inertia"},
        own=("crank_length", "omega1", "m1", "m2", "m3", "m4", "J1", "J2", "J3", "J4"),
        own_why="the source's crank is the second stage's and it models no link mass but "
                "the rocker's"),
    ("six_link", "crank_rocker"): Mapping(
        # the reverse: the six-link's second stage alone, its crank (link 3) driven directly
        # at the speed of the same mean energy per blow
        {"type": '"general"', "lambda0": "1 - mu4 + mu5", "lambda2": "mu4", "lambda3": "mu5",
         "crank_length": "lambda3 * crank_length",
         "omega1": "omega1 * sqrt((transfer_stage1_impact_1 ** 2 "
                   "+ transfer_stage1_impact_2 ** 2) / 2)"},
        optional={"rocker_inertia": "rocker_inertia"}),
}


@dataclass
class Designs:
    """A resolved source: the design axis's parameter codes, its coordinates and what the
    atlas records of where they came from."""

    columns: dict  # target parameter -> kernel codes per design (float64)
    coordinates: dict  # name -> (values per design, attrs)
    record: dict  # the recorded spec's from-table (atlas, where, map, designs, sha256)
    provenance: dict = field(default_factory=dict)  # the source's title, spec, code version
    lacking: tuple = ()  # (source variables missing, target parameters kept) per optional
    own: tuple = ()  # the target's parameters the source's model has not (Mapping.own)
    own_why: str = ""

    @property
    def count(self) -> int:
        return len(next(iter(self.columns.values())))


def _table(entry: Any) -> dict:
    from pydantic import BaseModel, ConfigDict, StrictInt, StrictStr, ValidationError

    class Source(BaseModel):
        model_config = ConfigDict(extra="forbid", strict=True)
        atlas: StrictStr
        where: StrictStr | None = None
        map: dict[str, StrictStr] = {}
        carry: list[StrictStr] = []
        designs: StrictInt | None = None
        sha256: StrictStr | None = None

    if not isinstance(entry, dict):
        raise UserError("grid.from: must be a table {atlas = \"SOURCE.nc\", where = "
                        "\"...\", map = {PARAMETER = \"EXPRESSION\"}}")
    try:
        return Source.model_validate(entry).model_dump()
    except ValidationError as err:
        e = err.errors()[0]
        loc = ".".join(str(x) for x in e["loc"])
        what = "unknown key" if e["type"] == "extra_forbidden" else \
            "required key is missing" if e["type"] == "missing" else e["msg"]
        raise UserError(f"grid.from.{loc}: {what}") from None


def declared_count(entry: Any) -> int | None:
    """How many designs a recorded from-table pins (None where it pins none)."""
    return entry.get("designs") if isinstance(entry, dict) else None


def resolve(entry: Any, mech) -> Designs:
    """A spec's ``grid.from`` table -> the designs it selects, checked (a one-line
    UserError before any compute)."""
    table = _table(entry)
    path = Path(table["atlas"]).expanduser()
    ds = _open(path)
    with ds:
        designs = _designs(ds, table, mech, path)
    pinned = table["designs"], table["sha256"]
    if pinned[0] is not None and pinned[0] != designs.count or \
            pinned[1] is not None and pinned[1] != designs.record["sha256"]:
        raise UserError(f"grid.from: {path} no longer gives the designs this spec was run "
                        f"on ({pinned[0]} designs, sha256 {str(pinned[1])[:12]}...; now "
                        f"{designs.count}, {designs.record['sha256'][:12]}...): the source "
                        "changed; run again with --force, or restore it")
    return designs


def _open(path: Path):
    import xarray as xr

    if not path.is_file():
        raise UserError(f"grid.from.atlas: no such file: {path}")
    try:
        ds = xr.open_dataset(path, engine="netcdf4")
    except Exception as err:  # noqa: BLE001  (any reason a file is not a netCDF atlas)
        raise UserError(f"grid.from.atlas: {path} is not a readable netCDF atlas "
                        f"({type(err).__name__})") from None
    if "status" not in ds.variables or "mechanism" not in ds.attrs:
        ds.close()
        raise UserError(f"grid.from.atlas: {path} is not an atlas of this tool (no status "
                        "or mechanism)")
    return ds


def _designs(ds, table: dict, mech, path: Path) -> Designs:
    from sweep import selection
    from sweep.metadata import usable_mask

    source = ds.attrs["mechanism"]
    declared = MAPPINGS.get((source, mech.name))
    known = {p.name: p for p in mech.parameters}
    for name in table["map"]:
        if name not in known:
            raise UserError(f"grid.from.map.{name}: not a parameter of {mech.name}; allowed: "
                            + ", ".join(known))
    dims = list(ds["status"].dims)
    if declared is None and source == mech.name:  # the same designs again: what varies
        declared = Mapping({name: name for name in known if name in ds.coords
                            and ds[name].ndim and set(ds[name].dims) <= set(dims)})
    if declared is None and not table["map"]:
        raise UserError(f"grid.from.map: no declared mapping from {source} to {mech.name}; "
                        "give map = {PARAMETER = \"EXPRESSION over the source's variables\"}")
    ds = _with_fixed(ds)
    optional, kept = {}, {}
    for name, expression in (declared.optional if declared else {}).items():
        if name in table["map"]:
            continue
        missing = tuple(sorted(_names_in(expression) - set(map(str, ds.variables))))
        if missing:
            kept.setdefault(missing, []).append(name)
        else:
            optional[name] = expression
    lacking = tuple((missing, tuple(names)) for missing, names in kept.items())
    columns = {**(declared.columns if declared else {}), **optional, **table["map"]}
    if not columns:
        raise UserError(f"grid.from.map: the source's designs set no parameter of "
                        f"{mech.name}; give map = {{PARAMETER = \"EXPRESSION\"}}")
    shape = ds["status"].shape
    mask = np.asarray(usable_mask(ds).transpose(*dims).values)
    if "requirements" in ds.variables:
        mask &= np.asarray(ds["requirements"].transpose(*dims).values) == 0
    if table["where"]:
        mask &= np.asarray(_checked(selection.evaluate, ds, table["where"], "where").values)
    points = np.flatnonzero(mask)
    if points.size == 0:
        raise UserError(f"grid.from: no design of {path} is ok, meets its requirements"
                        + (" and satisfies where" if table["where"] else ""))
    if declared is not None and declared.requires:
        meets = np.asarray(_checked(selection.evaluate, ds, declared.requires, "where")
                           .values).ravel()[points]
        if not meets.all():
            raise UserError(f"grid.from.where: {int((~meets).sum())} selected designs fail "
                            f"{declared.requires!r} ({declared.why}); add it to where")
    codes, shown = {}, {}
    for name, expression in columns.items():
        q = known[name]
        codes[name], shown[name] = _column(ds, expression, q, points, dims, shape)
    digest = hashlib.sha256()
    for name in sorted(codes):
        digest.update(name.encode())
        digest.update(np.ascontiguousarray(codes[name]).tobytes())
    coordinates = {name: (shown[name], {"units": known[name].units,
                                        "long_name": known[name].long_name
                                        + " (set by the source design)"})
                   for name in columns}
    carried = list(ds.coords) + table["carry"]
    for name in table["carry"]:
        if name not in ds.data_vars:
            raise UserError(f"grid.from.carry: {name!r} is not a variable of {path}; allowed: "
                            + ", ".join(v for v in map(str, ds.data_vars)
                                        if set(ds[v].dims) <= set(dims)))
        if not set(ds[name].dims) <= set(dims):
            raise UserError(f"grid.from.carry: {name} is a profile; carry values with one "
                            "per design")
    for name in carried:  # the source's grid axes (or a front's), and what was asked
        var = ds[name]
        if not var.ndim or not set(var.dims) <= set(dims):
            continue  # a profile axis
        values = np.asarray(var.broadcast_like(ds["status"]).transpose(*dims).values)
        values = values.ravel()[points]
        if values.dtype.kind in "OSU":
            values = np.array([v.decode() if isinstance(v, bytes) else str(v)
                               for v in values], dtype=object)
        attrs = {k: v for k, v in var.attrs.items() if k not in ("ancillary_variables",
                                                                    "coordinates")}
        attrs.update(units=var.attrs.get("units", "1"),
                     long_name="the source design's " + var.attrs.get("long_name", str(name)))
        coordinates[SOURCE_PREFIX + str(name)] = (values, attrs)
    record = {"atlas": str(path.resolve()), "where": table["where"], "map": table["map"],
              "carry": table["carry"], "designs": int(points.size), "sha256": digest.hexdigest()}
    provenance = {"atlas": str(path.resolve()), "mechanism": source,
                  "title": ds.attrs.get("title", ""), "spec": ds.attrs.get("spec", ""),
                  "code_version": ds.attrs.get("code_version", "")}
    coordinates[SOURCE_PREFIX + "index"] = (points.astype(np.int64), {
        "units": "1", "long_name": "flat (C-order) index of the design in the source's grid "
                                   "(a front's: its place on the front)"})
    own = tuple(n for n in (declared.own if declared else ()) if n not in columns)
    return Designs(codes, coordinates, record, provenance, lacking,
                   own, declared.own_why if declared else "")


def _value_text(q) -> str:
    """A parameter's default as a note gives it: ``J3 = 0.17 kg m2``."""
    if q.default is None:
        return f"{q.name} unset"
    value = f"{q.default:.4g}" if isinstance(q.default, float) else repr(q.default)
    return f"{q.name} = {value} {q.units if q.units != '1' else ''}".rstrip()


def notes(designs: Designs, mech, given) -> tuple:
    """One line for each thing the target takes from its own defaults because the source
    design does not give it, where the spec (``given``: its grid and fixed names) leaves it
    so: an optional entry whose source variable is missing, and the parameters the source's
    model has not (``Mapping.own``)."""
    lines = []
    for missing, names in designs.lacking:
        left = [mech.parameter(n) for n in names if n not in given]
        if left:
            lines.append(f"grid.from: the source has no {', '.join(missing)}: "
                         + ", ".join(q.name for q in left)
                         + (" keeps" if len(left) == 1 else " keep") + " the target's "
                         + ", ".join(_value_text(q) for q in left))
    left = [mech.parameter(n) for n in designs.own if n not in given]
    if left:
        lines.append(f"grid.from: {designs.provenance.get('mechanism', 'the source')} "
                     f"designs give no {', '.join(q.name for q in left)} ({designs.own_why}): "
                     f"{mech.name}'s own " + ", ".join(_value_text(q) for q in left))
    return tuple(lines)


def _names_in(expression: str) -> set[str]:
    """The variable names an expression of the query language reads."""
    from sweep import selection

    tree = selection.parse(expression)
    called = {id(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    return {node.id for node in ast.walk(tree)
            if isinstance(node, ast.Name) and id(node) not in called}


def _with_fixed(ds):
    """The source with its recorded fixed parameters as scalar variables, so that a
    mapping or a condition may name a parameter the source held fixed (an atlas made before
    it echoed crank_length as an output; ``type == "b"`` of an atlas of type b alone)."""
    try:
        fixed = json.loads(ds.attrs.get("spec", "{}")).get("fixed", {})
    except ValueError:
        fixed = {}
    extra = {name: (value if isinstance(value, str) else float(value))
             for name, value in fixed.items()
             if name not in ds.variables and isinstance(value, (int, float, str))
             and not isinstance(value, bool)}
    return ds.assign(extra) if extra else ds


def _checked(function, ds, expression: str, key: str):
    try:
        return function(ds, expression)
    except UserError as err:
        message = str(err)
        message = message.split(": ", 1)[1] if message.startswith("where: ") else message
        raise UserError(f"grid.from.{key}: {message}") from None


def _column(ds, expression: str, q, points, dims, shape):
    """One target parameter's kernel codes and shown values at the selected designs."""
    from sweep import selection
    from sweep.domains import check_value, domain_text

    where = f"grid.from.map.{q.name}"
    if not expression.strip():
        raise UserError(f"{where}: empty expression")
    tree = _checked(lambda _, text: selection.parse(text), ds, expression, f"map.{q.name}")
    body = tree.body
    if isinstance(body, ast.Constant) and isinstance(body.value, str):
        labels = np.array([body.value] * points.size, dtype=object)
    elif isinstance(body, ast.Name) and body.id in ds.variables \
            and ds[body.id].dtype.kind in "OSU":
        values = np.asarray(ds[body.id].broadcast_like(ds["status"]).transpose(*dims).values)
        labels = np.array([v.decode() if isinstance(v, bytes) else str(v)
                           for v in values.ravel()[points]], dtype=object)
    else:
        labels = None
    if labels is not None:
        if q.choices is None:
            raise UserError(f"{where}: {expression!r} gives words; {q.name} takes "
                            f"{domain_text(q)}")
        for word in dict.fromkeys(labels.tolist()):
            if check_value(q, word) is not None:
                raise UserError(f"{where}: {word!r} is not allowed; allowed: "
                                f"{domain_text(q)}")
        return np.array([q.encode(w) for w in labels]), labels
    value = _checked(selection.value_of, ds, tree, f"map.{q.name}")
    if isinstance(value, str) or (hasattr(value, "dtype") and value.dtype == bool):
        raise UserError(f"{where}: {expression!r} must give a number per design")
    if hasattr(value, "dims"):
        extra = [d for d in value.dims if d not in dims]
        if extra:
            raise UserError(f"{where}: {expression!r} is a profile over {extra[0]}; a "
                            "parameter takes one value per design")
        value = value.broadcast_like(ds["status"]).transpose(*dims).values
    numbers = np.broadcast_to(np.asarray(value, dtype=float), shape).ravel()[points]
    if q.choices is not None:
        raise UserError(f"{where}: {q.name} is categorical ({domain_text(q)}); give a quoted "
                        "word or a categorical variable of the source")
    bad = _outside(q, numbers)
    if bad is not None:
        raise UserError(f"{where}: {expression!r} gives {numbers[bad]:g} at source grid point "
                        f"{int(points[bad])}; allowed: {domain_text(q)}")
    return numbers.astype(float), numbers.astype(float)


def _outside(q, numbers: np.ndarray) -> int | None:
    """The first value outside a numeric parameter's domain, or None."""
    lo_bad = numbers < q.minimum if q.min_inclusive else numbers <= q.minimum
    hi_bad = numbers > q.maximum if q.max_inclusive else numbers >= q.maximum
    bad = ~np.isfinite(numbers) | lo_bad | hi_bad
    if q.nonzero:
        bad |= numbers == 0.0
    if q.integer:
        bad |= numbers != np.round(numbers)
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else None
