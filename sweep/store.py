"""Where finished blocks are kept and how the atlas file is written.

The block store is a folder beside the target (``.ATLAS.nc.partial/``): one ``.npy`` per
finished block, written under a temporary name and renamed, and a manifest naming the spec,
code version and chunk shape it belongs to. The atlas is assembled from the store under a
temporary name and renamed, so a file at the target is always a whole atlas.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

import numpy as np

from sweep.errors import UserError
from sweep.metadata import code_version


def check_target(path: Path, force: bool) -> None:
    """Refuse, before any compute, to overwrite an atlas or to write where we cannot."""
    if path.exists() and not force:
        raise UserError(f"output: {path} exists; use --force to overwrite it")
    if path.is_dir():
        raise UserError(f"output: {path} is a directory")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise UserError(f"output: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"output: directory {parent} is not writable")


def partial_dir(path: Path) -> Path:
    """Where the finished blocks of a run on ``path`` are kept until the atlas is written."""
    return path.with_name(f".{path.name}.partial")


@contextlib.contextmanager
def atomic(path: Path):
    """A temporary name beside ``path`` to write to: renamed to ``path`` when the block
    succeeds, removed when it fails, so a file at ``path`` is always whole."""
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def open_partial(folder: Path, manifest: dict, compared: dict, resume: bool,
                 force: bool) -> bool:
    """The folder where an interrupted run keeps its state: created new (its manifest
    written), or, with ``resume``, checked against the manifest (each key of ``compared``,
    named in words by its value, must match). Never silently discarded: without resume or
    force an existing one is refused. Returns whether the run resumes."""
    if folder.exists():
        if resume:
            try:
                old = json.loads((folder / "manifest.json").read_text())
            except (OSError, ValueError):
                raise UserError(f"resume: {folder} has no readable manifest; rerun with "
                                "--force to start over") from None
            for key, what in compared.items():
                if old.get(key) != manifest[key]:
                    raise UserError(f"resume: the interrupted run used a different {what}; "
                                    "rerun with --force to start over")
            return True
        if not force:
            raise UserError(f"output: an interrupted run left {folder}; use --resume to "
                            "continue it or --force to start over")
        shutil.rmtree(folder)
    elif resume:
        raise UserError(f"resume: nothing to resume at {folder}")
    folder.mkdir()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    return False


def block_name(index) -> str:
    return "b" + "_".join(str(i) for i in index)


class BlockStore:
    """The finished blocks of one run: open (new or resumed), save, load, discard."""

    def __init__(self, sweep, plan, path: Path, resume: bool, force: bool):
        self.folder = partial_dir(path)
        # what the blocks depend on: the spec without [run] (threads, scheduler and
        # compression do not change a block; the chunk shape is compared on its own)
        spec = {k: v for k, v in sweep.spec.items() if k != "run"}
        manifest = {"spec": json.dumps(spec), "code_version": code_version(),
                    "chunk_shape": list(plan.chunk_shape), "rows": plan.rows,
                    "blocks": plan.n_blocks}
        self.done: set[str] = set()
        compared = {"spec": "spec", "code_version": "code version",
                    "chunk_shape": "chunk size"}
        if open_partial(self.folder, manifest, compared, resume, force):
            self.done = {name[:-4] for name in os.listdir(self.folder)
                         if name.endswith(".npy") and not name.startswith(".")}

    def has(self, index) -> bool:
        return block_name(index) in self.done

    def save(self, index, block: np.ndarray) -> None:
        with atomic(self.folder / f"{block_name(index)}.npy") as tmp, open(tmp, "wb") as fh:
            np.save(fh, block)

    def load(self, index) -> np.ndarray:
        return np.load(self.folder / f"{block_name(index)}.npy")

    def discard(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def write_atlas(store: BlockStore, plan, path: Path, history: str) -> None:
    """Write the atlas from the block store under a temporary name, then rename."""
    import netCDF4

    from sweep.engine import build

    template = build(plan.sweep, lazy=False)
    template.attrs["history"] = history
    with atomic(path) as tmp, netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
        _define(nc, template)
        for index, location in plan.locations():
            region = tuple(slice(a, b) for a, b in location)
            for name, values in plan.split(store.load(index)).items():
                nc[name][region] = values


def _define(nc, ds) -> None:
    """Create dimensions, coordinates (written) and data variables (empty) in ``nc``."""
    nc.setncatts({k: v for k, v in ds.attrs.items()})
    for dim, size in ds.sizes.items():
        nc.createDimension(dim, size)
    for name in ds.coords:
        values = ds[name].values
        if values.dtype.kind in "OUS":
            # fixed-width chars with _Encoding, not HDF5 vlen strings: reopening a file with
            # vlen strings after another handle on it closed segfaults (xarray #8289)
            strings = np.array([str(v) for v in values])
            width = max(1, max(len(v.encode("utf-8")) for v in strings))
            nc.createDimension(f"{name}_strlen", width)
            var = nc.createVariable(name, "S1", (name, f"{name}_strlen"))
            var._Encoding = "utf-8"
            var[:] = strings.astype(f"U{width}")
        else:
            var = nc.createVariable(name, values.dtype, (name,))
            var[:] = values
        var.setncatts(dict(ds[name].attrs))
    for name, item in ds.data_vars.items():
        enc = item.encoding
        fill = enc.get("_FillValue")
        var = nc.createVariable(
            name, item.dtype, item.dims, zlib=bool(enc.get("zlib", False)),
            complevel=int(enc.get("complevel", 4)), shuffle=bool(enc.get("shuffle", False)),
            chunksizes=enc.get("chunksizes"),
            fill_value=False if fill is None else fill)
        var.setncatts(dict(item.attrs))
        # blocks are written whole and aligned with the netCDF chunks, so the cache only
        # needs a couple of chunks; netCDF-C's default (up to 64 MiB per variable) made the
        # peak memory grow with the grid (1.46 GB at 10^7 points)
        chunk_bytes = int(np.prod(enc.get("chunksizes") or item.shape)) * item.dtype.itemsize
        var.set_var_chunk_cache(size=2 * chunk_bytes + 1024, nelems=11, preemption=1.0)
