"""What an atlas says about itself: CF attributes of every variable, flag meanings, and the
provenance (spec, method, package and code versions, history)."""

from __future__ import annotations

import datetime as _dt
import json
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from kernels.status import CODES

if TYPE_CHECKING:
    import xarray as xr

CONVENTIONS = "CF-1.10"


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for name in ("impact-sweep", "numpy", "numba", "llvmlite", "xarray", "dask", "netCDF4",
                 "h5py", "isal", "pydantic", "click"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def package_version() -> str:
    """impact-sweep's installed version (pyproject.toml's)."""
    try:
        return metadata.version("impact-sweep")
    except metadata.PackageNotFoundError:  # run from a checkout that is not installed
        return "unknown"


def code_version() -> str:
    """Package version, plus the git commit (and '-dirty') when run from a checkout."""
    here = Path(__file__).resolve().parent.parent
    try:
        rev = subprocess.run(["git", "-C", str(here), "describe", "--always", "--dirty",
                              "--abbrev=12"], capture_output=True, text=True, timeout=5)
        if rev.returncode == 0 and rev.stdout.strip():
            return f"{package_version()}+git.{rev.stdout.strip()}"
    except (OSError, subprocess.SubprocessError):
        pass
    return package_version()


def status_attributes(mech) -> dict:
    """CF flag attributes of ``status``: the codes of the statuses this mechanism emits."""
    values = np.array([CODES[f] for f in mech.status], dtype=np.int8)
    return {"long_name": "status of the grid point", "units": "1", "label": "status",
            "flag_values": values, "flag_meanings": " ".join(mech.status),
            "usable_flags": " ".join(("ok",) + tuple(mech.usable)),
            "comment": "usable_flags: statuses whose outputs are design values"}


def flag_attributes(output) -> dict:
    """CF flag attributes of a flag output, its meanings in the order of their codes."""
    pairs = sorted(output.flags.items(), key=lambda item: item[1])
    return {"flag_values": np.array([code for _, code in pairs], dtype=np.int8),
            "flag_meanings": " ".join(meaning for meaning, _ in pairs)}


def flag_codes(values: np.ndarray, output) -> np.ndarray:
    """A kernel's float row of a flag output as its int8 codes (NaN: undetermined)."""
    if output.undetermined is None:
        return values.astype(np.int8)
    return np.where(np.isnan(values), output.flag_code_of_nan(), values).astype(np.int8)


def usable_mask(ds: xr.Dataset) -> xr.DataArray:
    """True where a point's outputs are design values (status in usable_flags)."""
    status = ds["status"]
    meanings = status.attrs["flag_meanings"].split()
    values = np.atleast_1d(status.attrs["flag_values"])
    usable = status.attrs.get("usable_flags", "ok").split()
    codes = [int(values[meanings.index(m)]) for m in usable if m in meanings]
    return status.isin(codes)


def annotate(ds: xr.Dataset, sweep, chunk_shape: tuple[int, ...]) -> xr.Dataset:
    """Attach CF attributes, provenance and netCDF encodings to a (lazy) atlas."""
    mech = sweep.mechanism
    level = sweep.run.compress_level
    for axis in sweep.axes:
        p = axis.parameter
        ds[axis.name].attrs.update(units=p.units, long_name=p.long_name,
                                   **({"label": p.label} if p.label else {}))
        ds[axis.name].encoding["_FillValue"] = None
        if p.categorical:
            # fixed-width chars, not HDF5 variable-length strings: reopening a file with
            # vlen strings after closing another handle on it segfaults (xarray #8289)
            ds[axis.name].encoding["dtype"] = "S1"
        for name, (values, attrs) in axis.coordinates.items():
            ds[name].attrs.update(attrs)
            ds[name].encoding["_FillValue"] = None
            if np.asarray(values).dtype.kind in "OSU":
                ds[name].encoding["dtype"] = "S1"
    if mech.profile_dim is not None and mech.profile_dim.name in ds.coords:
        pdim = mech.profile_dim
        ds[pdim.name].attrs.update(units=pdim.units, long_name=pdim.long_name,
                                   **({"label": pdim.label} if pdim.label else {}))
        ds[pdim.name].encoding["_FillValue"] = None
    for name in sweep.outputs:
        o = mech.output(name)
        ds[name].attrs.update(units=o.units, long_name=o.long_name,
                              ancillary_variables="status",
                              **({"label": o.label} if o.label else {}))
        if o.description:
            ds[name].attrs["comment"] = o.description
        chunks = chunk_shape + tuple(ds.sizes[d] for d in ds[name].dims[len(chunk_shape):])
        ds[name].encoding.update(zlib=level > 0, complevel=level, shuffle=True,
                                 chunksizes=chunks)
        if o.is_flag:
            ds[name].attrs.update(flag_attributes(o))
            ds[name].encoding["_FillValue"] = None
        else:
            ds[name].encoding["_FillValue"] = np.nan
    ds["status"].attrs.update(status_attributes(mech))
    ds["status"].encoding.update(zlib=level > 0, complevel=level, chunksizes=chunk_shape,
                                 _FillValue=None)
    if sweep.requirements:
        from sweep import requirements

        ds["requirements"].attrs.update(requirements.attributes(sweep.requirements))
        ds["requirements"].encoding.update(zlib=level > 0, complevel=level,
                                           chunksizes=chunk_shape, _FillValue=None)
        ds["requirement_margin"].attrs.update(requirements.MARGIN_ATTRIBUTES)
        ds["requirement_margin"].encoding.update(zlib=level > 0, complevel=level,
                                                 shuffle=True, chunksizes=chunk_shape,
                                                 _FillValue=np.nan)
    ds.attrs.update(
        Conventions=CONVENTIONS,
        title=sweep.title,
        institution="impact-sweep",
        source=f"impact-sweep {package_version()}, mechanism {mech.name}",
        references=mech.references,
        mechanism=mech.name,
        spec=sweep.spec_json(),
        requirements=json.dumps([limit.text for limit in sweep.requirements]),
        notes=json.dumps(list(sweep.notes)),
        **({"source_atlas": json.dumps(sweep.designs.provenance)} if sweep.designs else {}),
        method=json.dumps({"model": mech.summary, **sweep.method}),
        package_versions=json.dumps(package_versions()),
        code_version=code_version(),
    )
    return ds


def history_line(argv: list[str] | None = None) -> str:
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    args = " ".join(argv if argv is not None else ["sweep"] + sys.argv[1:])
    return f"{now}: {args}"


def file_status_counts(path) -> tuple[dict[str, int], set[str]]:
    """How many points of an atlas file carry each status meaning, and which meanings are
    usable designs (usable_flags), read with netCDF4 alone (a run's summary needs no
    xarray)."""
    import netCDF4

    with netCDF4.Dataset(path) as nc:
        status = nc["status"]
        status.set_auto_mask(False)
        values = [int(v) for v in np.atleast_1d(status.flag_values)]
        counts = np.bincount(np.asarray(status[...], dtype=np.int64).ravel(),
                             minlength=max(CODES.values()) + 1)
        usable = set(getattr(status, "usable_flags", "ok").split())
        return ({m: int(counts[v]) for v, m in zip(values, status.flag_meanings.split())},
                usable)


def status_summary(counts: dict[str, int], usable: set[str]) -> str:
    """``usable designs: ok 40,432, special_position 1,786; no design: not_assemblable
    1,454``: the statuses that carry design values apart from those that do not."""
    def listed(names):
        return ", ".join(f"{m} {counts[m]:,}" for m in names if counts[m])

    good = listed(m for m in counts if m in usable)
    bad = listed(m for m in counts if m not in usable)
    return "; ".join(part for part in (f"usable designs: {good or 'none'}",
                                       f"no design: {bad}" if bad else "") if part)
