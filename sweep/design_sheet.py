"""``sweep sheet``: one page for one design, to hand on to a review or the workshop.

Its parameters and every output with unit and meaning, the requirement margins, its place
on the front (a front's atlas, or the front ``sweep pareto --sheet`` has just found), its
profiles over the cycle where the mechanism has them, and the provenance (spec, code
version, package versions, date). HTML from a template (jinja2), figures inlined; a PDF of
it printed by the distribution's headless Chromium where one is installed (never a
downloaded browser)."""

from __future__ import annotations

import base64
import io
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from sweep.errors import UserError

CHROMIUM = ("chromium", "chromium-browser")
#: how long a PDF may take to print [s]
PDF_TIMEOUT = 120


def point_of(ds: xr.Dataset, design: int | None = None, where: str | None = None) -> dict:
    """The grid point a sheet is of, {dim: index}: ``design``, its flat (C-order) index in
    the grid (as ``sweep query`` lists it), or the first that matches ``where``."""
    from sweep.selection import first_point

    dims = list(ds["status"].dims)
    shape = ds["status"].shape
    size = int(np.prod(shape))
    if (design is None) == (where is None):
        raise UserError("design: give one of design (a grid point's index) or where")
    if where is not None:
        return first_point(ds, where)
    if isinstance(design, bool) or not isinstance(design, (int, np.integer)) \
            or not 0 <= design < size:
        raise UserError(f"design: a grid point's index from 0 to {size - 1}, not "
                        f"{design!r}")
    flat = int(design)
    return dict(zip(dims, (int(i) for i in np.unravel_index(flat, shape))))


def page(ds: xr.Dataset, at: dict, front_png: bytes | None = None, source: str = "") -> str:
    """The sheet of the design at grid point ``at`` as one HTML document."""
    import jinja2

    from sweep import labels, requirements
    from sweep.charts import design_text

    dims = list(ds["status"].dims)
    point = ds.isel(at)
    flat = int(np.ravel_multi_index(tuple(at[d] for d in dims), ds["status"].shape))
    mech = _declaration(ds)
    parameter_names = {p.name for p in mech.parameters} if mech is not None else set()
    spec = json.loads(ds.attrs.get("spec", "{}") or "{}")
    parameters, outputs = [], []
    for name in [*(d for d in dims if d in ds.variables),
                 *(str(n) for n in ds.variables if str(n) not in dims)]:
        var = ds[name]
        if not set(var.dims) <= set(dims) or name.startswith("_"):
            continue  # a profile
        row = _row(ds, point, name)
        (parameters if name in parameter_names else outputs).append(row)
    shown = {row["name"] for row in parameters}
    for name, value in (spec.get("fixed") or {}).items():
        if name not in shown and mech is not None and name in parameter_names:
            q = mech.parameter(name)
            parameters.append({"name": name, "label": labels.plain(q.label or name),
                               "value": _number(value) if isinstance(value, (int, float))
                               and not isinstance(value, bool) else str(value),
                               "units": labels.pretty_units(q.units),
                               "meaning": q.long_name + " (fixed)"})
    limits = requirements.of_dataset(ds) if "status" in ds else ()
    margins = []
    for limit in limits:
        if limit.name not in point.variables:
            continue
        value = float(point[limit.name].values)
        holds = bool(limit.holds(np.array(value))) if np.isfinite(value) else False
        margins.append({"limit": limit.text, "value": _number(value, ds, limit.name),
                        "margin": f"{float(limit.slack(np.array(value))):+.3%}"
                        if np.isfinite(value) else "no value",
                        "holds": holds, "verdict": "met" if holds else "fails"})
    status = _word(point["status"])
    profiles = _profiles(ds, at)
    history = str(ds.attrs.get("history", "")).strip().splitlines()
    provenance = [("atlas", source or str(ds.encoding.get("source", "(in memory)"))),
                  ("grid point", str(flat)),
                  ("code version", str(ds.attrs.get("code_version", ""))),
                  ("package versions", ", ".join(
                      f"{k} {v}" for k, v in json.loads(
                          ds.attrs.get("package_versions", "{}") or "{}").items())),
                  ("method", _method_text(ds)),
                  ("history", history[-1] if history else ""),
                  ("notes", "; ".join(json.loads(ds.attrs.get("notes", "[]") or "[]")))]
    if "source_atlas" in ds.attrs:
        origin = json.loads(ds.attrs["source_atlas"])
        provenance.append(("source atlas", f"{origin.get('atlas', '')} "
                                           f"({origin.get('mechanism', '')})"))
    environment = jinja2.Environment(
        loader=jinja2.PackageLoader("sweep", "templates"), autoescape=True)
    where = design_text(point, dims, True, plain=True)
    return environment.get_template("sheet.html").render(
        title=f"Design sheet: {ds.attrs.get('title', ds.attrs.get('mechanism', ''))}",
        mechanism=ds.attrs.get("mechanism", ""), where=where, status=status,
        date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        parameters=parameters, outputs=outputs, requirements=margins,
        front=_png64(front_png) if front_png else _front(ds, flat),
        profiles=profiles, provenance=[(k, v) for k, v in provenance if v],
        spec=json.dumps(spec, indent=1))


def _declaration(ds):
    from sweep import registry

    name = ds.attrs.get("mechanism", "")
    return registry.get(name).declaration if name in registry.names() else None


def _word(var) -> str:
    from sweep.selection import flag_names

    names = flag_names(var)
    value = var.values.item() if hasattr(var.values, "item") else var.values
    if names is not None:
        return names.get(int(value), str(value))
    return value.decode() if isinstance(value, bytes) else str(value)


def _number(value, ds=None, name=None) -> str:
    if ds is not None and name is not None and ds[name].attrs.get("units") == "rad":
        value = np.degrees(value)
    value = float(value)
    return f"{value:.6g}" if np.isfinite(value) else "no value"


def _row(ds, point, name) -> dict:
    from sweep import labels

    var = point[name]
    attrs = ds[name].attrs
    if "flag_meanings" in attrs or var.dtype.kind in "OSU":
        value, units = _word(var), ""
    else:
        value = _number(labels.shown_values(var, True, ds).item())
        units = labels.pretty_units(labels.units(ds, name, True))
    return {"name": name, "label": labels.plain(labels.label(ds, name)), "value": value,
            "units": units, "meaning": attrs.get("long_name", "")}


def _method_text(ds) -> str:
    method = json.loads(ds.attrs.get("method", "{}") or "{}")
    return str(method.get("model", "")) if isinstance(method, dict) else ""


def _png64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def figure_png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def _profiles(ds, at) -> str | None:
    """The design's profiles over the mechanism's profile axis, one panel per unit."""
    from sweep.charts import profile_figure

    mech = _declaration(ds)
    if mech is None or mech.profile_dim is None:
        return None
    axis = mech.profile_dim.name
    names = [str(n) for n, v in ds.data_vars.items() if axis in v.dims
             and np.isfinite(np.asarray(v.isel(at).values, dtype=float)).any()]
    if not names:
        return None
    fig, _ = profile_figure(ds, names, None, True, at=at)
    return _png64(figure_png(fig))


def _front(ds, flat) -> str | None:
    """A front's atlas: its first two objectives over its designs, this one marked."""
    from matplotlib.figure import Figure

    from sweep import labels

    pareto = json.loads(ds.attrs.get("pareto", "{}") or "{}")
    objectives = [o.split(" ", 1) for o in pareto.get("objectives", [])]
    if len(objectives) < 2 or any(name not in ds for _, name in objectives[:2]):
        return None
    (sense_x, x), (sense_y, y) = objectives[:2]
    fig = Figure(figsize=(6.0, 3.6), layout="constrained")
    ax = fig.subplots()
    xs = labels.shown_values(ds[x], True, ds).ravel()
    ys = labels.shown_values(ds[y], True, ds).ravel()
    ax.plot(xs, ys, "o", ms=4, color="#0072B2", label="front")
    ax.plot(xs[flat], ys[flat], "*", ms=16, color="#D55E00", mec="black",
            label="this design")
    ax.set_xlabel(f"{labels.axis_label(ds, x)}, {sense_x}imised")
    ax.set_ylabel(f"{labels.axis_label(ds, y)}, {sense_y}imised")
    ax.legend(loc="best", frameon=False)
    return _png64(figure_png(fig))


def chromium() -> str | None:
    """The distribution's Chromium, or None."""
    for name in CHROMIUM:
        path = shutil.which(name)
        if path:
            return path
    return None


def print_pdf(html: Path, pdf: Path) -> bool:
    """The page printed to ``pdf`` by headless Chromium (written under a temporary name,
    renamed when whole); False where no Chromium is installed."""
    from sweep.store import atomic

    browser = chromium()
    if browser is None:
        return False
    with tempfile.TemporaryDirectory() as profile, atomic(pdf) as tmp:
        done = subprocess.run(
            [browser, "--headless=new", "--no-sandbox", "--disable-gpu",
             "--no-pdf-header-footer", f"--user-data-dir={profile}",
             f"--print-to-pdf={tmp}", html.resolve().as_uri()],
            capture_output=True, timeout=PDF_TIMEOUT)
        if done.returncode != 0 or not Path(tmp).is_file():
            raise UserError(f"pdf: Chromium could not print {html} (exit {done.returncode})")
    return True
