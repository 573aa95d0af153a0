"""Where finished blocks are kept and how the atlas file is written.

The block store is a folder beside the target (``.ATLAS.nc.partial/``): one ``.npy`` per
finished block, written under a temporary name and renamed, and a manifest naming the spec,
code version and chunk shape it belongs to. The atlas is assembled from the store under a
temporary name and renamed, so a file at the target is always a whole atlas.
"""

from __future__ import annotations

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
        if self.folder.exists():
            if resume:
                self.done = self._resumable(manifest)
                return
            if not force:
                raise UserError(f"output: an interrupted run left {self.folder}; use "
                                "--resume to continue it or --force to start over")
            shutil.rmtree(self.folder)
        elif resume:
            raise UserError(f"resume: nothing to resume at {self.folder}")
        self.folder.mkdir()
        (self.folder / "manifest.json").write_text(json.dumps(manifest))

    def _resumable(self, manifest: dict) -> set[str]:
        try:
            old = json.loads((self.folder / "manifest.json").read_text())
        except (OSError, ValueError):
            raise UserError(f"resume: {self.folder} has no readable manifest; rerun with "
                            "--force to start over") from None
        for key, what in (("spec", "spec"), ("code_version", "code version"),
                          ("chunk_shape", "chunk size")):
            if old.get(key) != manifest[key]:
                raise UserError(f"resume: the interrupted run used a different {what}; "
                                "rerun with --force to start over")
        return {name[:-4] for name in os.listdir(self.folder)
                if name.endswith(".npy") and not name.startswith(".")}

    def has(self, index) -> bool:
        return block_name(index) in self.done

    def save(self, index, block: np.ndarray) -> None:
        name = block_name(index)
        with open(self.folder / f".{name}.tmp", "wb") as fh:
            np.save(fh, block)
        os.replace(self.folder / f".{name}.tmp", self.folder / f"{name}.npy")

    def load(self, index) -> np.ndarray:
        return np.load(self.folder / f"{block_name(index)}.npy")

    def discard(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def write_atlas(store: BlockStore, plan, path: Path, history: str) -> None:
    """Write the atlas from the block store under a temporary name, then rename."""
    import netCDF4

    from sweep.engine import build

    template = build(plan.sweep)
    template.attrs["history"] = history
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            _define(nc, template)
            for index, location in plan.locations():
                region = tuple(slice(a, b) for a, b in location)
                for name, values in plan.split(store.load(index)).items():
                    nc[name][region] = values
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


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
