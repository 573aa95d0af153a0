"""A small, safe expression language over atlas variables and coordinates.

``restitution_kinematic > -0.32 and lambda2 <= 3 and type == "a" and status == "ok"``

The text is parsed with Python's ``ast`` (parsing runs no code) and only a whitelist of node
types is evaluated by the interpreter below: names of atlas variables and coordinates, number
and string literals, arithmetic, comparisons, and/or/not, and a few numeric functions. No
attribute access, subscripts, calls to anything else, or ``eval``: the language cannot reach
Python builtins, objects or files.
"""

from __future__ import annotations

import ast
import operator

import numpy as np
import xarray as xr

from sweep.errors import UserError

MAX_LENGTH = 2000
MAX_NODES = 500

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow, ast.Mod: operator.mod}
_COMPARE = {ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt,
            ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge}
_FUNCTIONS = {"abs": np.abs, "sqrt": np.sqrt, "log": np.log, "log10": np.log10,
              "exp": np.exp, "isnan": np.isnan, "isfinite": np.isfinite,
              "degrees": np.degrees, "radians": np.radians}


def _flag_code(var: xr.DataArray, label: str):
    meanings = var.attrs["flag_meanings"].split()
    if label not in meanings:
        raise UserError(f"where: {var.name} has no flag {label!r}; allowed: "
                        + ", ".join(meanings))
    return np.atleast_1d(var.attrs["flag_values"])[meanings.index(label)]


class _Evaluator:
    def __init__(self, ds: xr.Dataset):
        self.ds = ds

    def value(self, node):
        if isinstance(node, ast.Expression):
            return self.value(node.body)
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                raise UserError(f"where: literal {v!r} is not allowed; use numbers or "
                                "quoted strings")
            return v if isinstance(v, str) else np.float64(v)
        if isinstance(node, ast.Name):
            if node.id in ("requirements", "requirement_margin") \
                    and node.id not in self.ds.variables:
                raise UserError("where: this atlas has no requirements; give them with "
                                "--require 'NAME <= NUMBER' (or a spec's [requirements])")
            if node.id not in self.ds.variables:
                raise UserError(f"where: unknown name {node.id!r}; allowed: "
                                + ", ".join(sorted(map(str, self.ds.variables))))
            return self.ds[node.id]
        if isinstance(node, ast.BoolOp):
            parts = [self._boolean(self.value(v)) for v in node.values]
            out = parts[0]
            for p in parts[1:]:
                out = (out & p) if isinstance(node.op, ast.And) else (out | p)
            return out
        if isinstance(node, ast.UnaryOp):
            operand = self.value(node.operand)
            if isinstance(node.op, ast.Not):
                return ~self._boolean(operand)
            if isinstance(node.op, ast.USub):
                return -self._number(operand)
            if isinstance(node.op, ast.UAdd):
                return self._number(operand)
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            left, right = self._number(self.value(node.left)), self._number(self.value(node.right))
            with np.errstate(all="ignore"):
                return _BINARY[type(node.op)](left, right)
        if isinstance(node, ast.Compare):
            left = self.value(node.left)
            result = None
            for op, right_node in zip(node.ops, node.comparators):
                if type(op) not in _COMPARE:
                    raise UserError("where: only ==, !=, <, <=, >, >= compare")
                right = self.value(right_node)
                a, b = self._comparable(left, right)
                part = _COMPARE[type(op)](a, b)
                result = part if result is None else (result & part)
                left = right
            return result
        if isinstance(node, ast.Call):
            allowed = ", ".join(_FUNCTIONS)
            if not isinstance(node.func, ast.Name) or node.func.id not in _FUNCTIONS:
                name = ast.unparse(node.func)
                raise UserError(f"where: function {name!r} is not allowed; allowed: {allowed}")
            if node.keywords or len(node.args) != 1:
                raise UserError(f"where: {node.func.id} takes one argument")
            with np.errstate(all="ignore"):
                return _FUNCTIONS[node.func.id](self._number(self.value(node.args[0])))
        raise UserError(f"where: {type(node).__name__} is not allowed in a query")

    def _comparable(self, a, b):
        # a string compared with a flag variable means its flag meaning: status == "ok"
        for x, y, swap in ((a, b, False), (b, a, True)):
            if isinstance(x, xr.DataArray) and "flag_meanings" in x.attrs and isinstance(y, str):
                code = _flag_code(x, y)
                return (code, x) if swap else (x, code)
        for x, y in ((a, b), (b, a)):  # a word a categorical variable never takes: a typo
            if isinstance(x, xr.DataArray) and x.dtype.kind in "OUS" and isinstance(y, str):
                words = sorted({v.decode() if isinstance(v, bytes) else str(v)
                                for v in np.unique(x.values)})
                if y not in words:
                    raise UserError(f"where: {x.name} has no value {y!r}; allowed: "
                                    + ", ".join(f'"{w}"' for w in words))
        for x, y in ((a, b), (b, a)):
            text = isinstance(x, str) or (isinstance(x, xr.DataArray) and x.dtype.kind in "OUS")
            other_text = isinstance(y, str) or (isinstance(y, xr.DataArray)
                                                 and y.dtype.kind in "OUS")
            if text and not other_text:
                name = repr(x) if isinstance(x, str) else x.name
                raise UserError(f"where: {name} is text and is compared with a number; "
                                "compare it with a quoted string")
        return a, b

    @staticmethod
    def _number(v):
        if isinstance(v, str):
            raise UserError(f"where: string {v!r} used as a number")
        if isinstance(v, xr.DataArray) and v.dtype.kind in "OUS":
            raise UserError(f"where: {v.name} is categorical; compare it with == \"...\"")
        return v

    @staticmethod
    def _boolean(v):
        if isinstance(v, xr.DataArray) and v.dtype == bool:
            return v
        if isinstance(v, (bool, np.bool_)):
            return v
        raise UserError("where: and/or/not need comparisons on both sides")


def parse(expr: str) -> ast.Expression:
    if len(expr) > MAX_LENGTH:
        raise UserError(f"where: expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(expr, mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as err:
        msg = getattr(err, "msg", None) or type(err).__name__
        raise UserError(f"where: not a valid expression ({msg})") from None
    if sum(1 for _ in ast.walk(tree)) > MAX_NODES:
        raise UserError(f"where: expression has more than {MAX_NODES} parts")
    return tree


def value_of(ds: xr.Dataset, tree: ast.Expression):
    """The value of a parsed expression over the atlas: a DataArray, a number or a word."""
    try:
        return _Evaluator(ds).value(tree)
    except RecursionError:
        raise UserError("where: expression nested too deeply") from None


def evaluate(ds: xr.Dataset, expr: str) -> xr.DataArray:
    """Boolean mask over the atlas grid (broadcast to all grid dims)."""
    tree = parse(expr)
    mask = value_of(ds, tree)
    if not (isinstance(mask, xr.DataArray) and mask.dtype == bool):
        raise UserError("where: the expression must be a condition, e.g. \"x > 1\"")
    dims = [d for d in ds["status"].dims]
    extra = [d for d in mask.dims if d not in dims]
    if extra:
        profiles = sorted(name for name in tree_names(tree) if name in ds.data_vars
                          and extra[0] in ds[name].dims)
        raise UserError(f"where: {', '.join(profiles) or 'the condition'} is a profile over "
                        f"{extra[0]}; a condition picks grid points: compare a value with "
                        f"one value per design, or take the profile at one {extra[0]} "
                        f"(--at {extra[0]}=VALUE with --columns)")
    return mask.broadcast_like(ds["status"]).transpose(*dims)


def at_values(at) -> dict[str, tuple[float, str]]:
    """Axes taken at one value, as {axis: (number, "" or "deg")}, from {axis: number or
    "90deg"} (the Python API) or ["axis=90deg", ...] (the command line's --at)."""
    if at is None:
        return {}
    if isinstance(at, dict):
        pairs = [(str(name), value) for name, value in at.items()]
    else:
        pairs = []
        for pair in at:
            dim, sep, value = str(pair).partition("=")
            if not sep:
                raise UserError(f"at: {pair!r} must be AXIS=NUMBER in the axis's units, or "
                                "NUMBERdeg for an angle, e.g. crank_angle=90deg")
            pairs.append((dim.strip(), value.strip()))
    out = {}
    for dim, value in pairs:
        if isinstance(value, bool):
            number = None
        elif isinstance(value, (int, float, np.integer, np.floating)):
            number, unit = float(value), ""
        else:
            text = str(value).strip()
            unit = "deg" if text.endswith(("deg", "°")) else ""
            try:
                number = float(text.removesuffix("deg").removesuffix("°"))
            except ValueError:
                number = None
        if number is None or not np.isfinite(number):
            raise UserError(f"at: {dim}={value!r} must be a number in the axis's units, or "
                            "NUMBERdeg for an angle, e.g. crank_angle=90deg")
        out[dim] = (number, unit)
    return out


def tree_names(tree: ast.AST) -> set[str]:
    """The variable names a parsed expression reads."""
    return {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}


def grid_variables(ds: xr.Dataset) -> list[str]:
    """The variables with one value per grid point (not profiles over an extra axis)."""
    dims = set(ds["status"].dims)
    return [str(v) for v in ds.data_vars if set(ds[v].dims) <= dims]


def take_at(ds: xr.Dataset, at: dict | None, grid: bool = False) -> tuple[xr.Dataset, str]:
    """The atlas with each axis in ``at`` ({axis: (value, "" or "deg")}) taken at its nearest
    value, and a caption of the values taken. Profile axes by default; ``grid``: grid axes
    (kept as a dimension of length 1, for a chart)."""
    allowed = (list(ds["status"].dims) if grid
               else sorted(set(ds.dims) - set(ds["status"].dims)))
    chosen = []
    for dim, (value, unit) in (at or {}).items():
        if dim not in allowed:
            kind = "grid axis" if grid else "profile axis"
            raise UserError(f"at: {dim!r} is not a {kind} of this atlas; allowed: "
                            + (", ".join(map(str, allowed)) or "none (the atlas has no "
                                                                "profiles)"))
        axis = ds[dim]
        if axis.dtype.kind not in "fiu":
            raise UserError(f"at: {dim} is categorical; its values are drawn as panels")
        units = axis.attrs.get("units", "")
        if unit == "deg":
            if units != "rad":
                raise UserError(f"at: {dim} is in {units or 'no units'}, not an angle in rad")
            value = np.radians(value)
        lo, hi = float(axis.min()), float(axis.max())
        step = (hi - lo) / max(axis.size - 1, 1)
        if not lo - step <= value <= hi + step:
            shown = (f"{np.degrees(lo):.4g}-{np.degrees(hi):.4g} deg" if units == "rad"
                     else f"{lo:.4g}-{hi:.4g} {units}")
            raise UserError(f"at: {dim} = {value:.6g} {units} is outside the "
                            f"{'grid' if grid else 'profile'}'s range, {lo:.4g}-{hi:.4g} "
                            f"{units}"
                            + (f" ({shown}; write e.g. {dim}=90deg)" if units == "rad" else ""))
        ds = ds.sel({dim: value}, method="nearest")
        chosen.append(f"{dim} = {float(ds[dim].values):.6g}"
                      + ("" if units in ("", "1") else f" {units}"))
        if grid:
            ds = ds.expand_dims(dim)
    return ds, ", ".join(chosen)


def first_point(ds: xr.Dataset, where: str | None) -> dict:
    """The first grid point (C order) matching ``where`` (the first of all without one),
    as {dim: index}; a UserError where none does."""
    return _points(ds, _hits(ds, where)[:1])[0]


def matching_points(ds: xr.Dataset, where: str | None) -> list[dict]:
    """Every grid point (C order) matching ``where`` (all without one), each as
    {dim: index}; a UserError where none does."""
    return _points(ds, _hits(ds, where))


def _hits(ds: xr.Dataset, where: str | None) -> np.ndarray:
    """Flat (C order) indices of the grid points matching ``where``; none is an error."""
    dims = list(ds["status"].dims)
    mask = np.asarray(evaluate(ds, where).broadcast_like(ds["status"]).transpose(*dims)
                      .values) if where else np.ones(ds["status"].shape, bool)
    hits = np.flatnonzero(mask)
    if not hits.size:
        raise UserError("where: no grid point matches")
    return hits


def _points(ds: xr.Dataset, hits: np.ndarray) -> list[dict]:
    dims = list(ds["status"].dims)
    return [dict(zip(dims, (int(i) for i in np.unravel_index(int(hit), ds["status"].shape))))
            for hit in hits]


def flag_names(var: xr.DataArray) -> dict[int, str] | None:
    """Code -> meaning of a flag variable, or None."""
    if "flag_meanings" not in var.attrs:
        return None
    codes = np.atleast_1d(var.attrs["flag_values"]).astype(int)
    return dict(zip(codes, var.attrs["flag_meanings"].split()))


def select(ds: xr.Dataset, where: str | None, sort: str | None = None,
           limit: int | None = None, columns: list[str] | None = None,
           descending: bool = False, at: dict[str, float] | None = None,
           rank_all: bool = False):
    """Rows (a pandas DataFrame) of the grid points that satisfy ``where``, sorted by
    ``sort`` (ascending, or descending: the best designs first), flags as their meanings.
    Where the atlas has requirements, a design that fails one is never ranked above one
    that meets them all, unless ``rank_all``. Profiles (variables over an extra axis such
    as crank_angle) are shown only where asked, at the value of their axis given in
    ``at``."""
    import pandas as pd

    ds, _ = take_at(ds, at)
    if sort is not None and sort not in ds.variables:
        raise UserError(f"sort: unknown variable {sort!r}")
    dims = list(ds["status"].dims)
    columns = columns or grid_variables(ds)
    for c in columns:
        if c not in ds.variables:
            raise UserError(f"columns: unknown variable {c!r}")
        extra = [d for d in ds[c].dims if d not in dims]
        if extra:
            raise UserError(f"columns: {c} is a profile over {', '.join(extra)}; pick a "
                            f"value with --at {extra[0]}=VALUE")
    if sort is not None and sort not in columns and sort not in dims:
        columns = columns + [sort]
    if where:
        mask = np.asarray(evaluate(ds, where).values)
    else:
        mask = np.ones(ds["status"].shape, dtype=bool)
    index = np.nonzero(mask)
    data = {}
    for j, dim in enumerate(dims):
        data[dim] = np.asarray(ds[dim].values)[index[j]]
    for c in columns:
        if c in dims:
            continue
        v = ds[c].broadcast_like(ds["status"]).transpose(*dims).values
        data[c] = np.asarray(v)[index]
    frame = pd.DataFrame(data)
    if sort is not None:  # by code, before codes become words; NaN last either way
        frame = frame.sort_values(sort, kind="stable", ascending=not descending,
                                  na_position="last")
        if "requirements" in ds.variables and not rank_all:  # the ones that meet them first
            met = np.asarray(ds["requirements"].transpose(*dims).values)[index] == 0
            frame = frame.iloc[np.argsort(~met[frame.index.to_numpy()], kind="stable")]
    for c in frame.columns:
        names = flag_names(ds[c]) if c in ds.variables else None
        if names is not None:
            frame[c] = frame[c].map(lambda v: names.get(int(v), str(v)) if v == v else "")
    matched = len(frame)
    if limit is not None:
        frame = frame.head(limit)
    frame.attrs["matched"] = matched  # before --limit: what the table's footer reports
    return frame


def units_of(ds: xr.Dataset, columns, degrees: bool = False) -> list[str]:
    """The units of each column, as printed under a table's header ("" for words)."""
    out = []
    for c in columns:
        var = ds[c] if c in ds.variables else None
        if var is None or "flag_meanings" in var.attrs or var.dtype.kind in "OUS":
            out.append("")
        else:
            units = var.attrs.get("units", "")
            out.append("deg" if degrees and units == "rad" else units)
    return out


def in_degrees(ds: xr.Dataset, frame):
    """The selected rows with every column in rad shown in degrees (the atlas keeps rad)."""
    frame = frame.copy()
    for c in frame.columns:
        if c in ds.variables and ds[c].attrs.get("units") == "rad" \
                and "flag_meanings" not in ds[c].attrs:
            frame[c] = np.degrees(frame[c].astype(float))
    return frame
