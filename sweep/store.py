"""Where finished blocks are kept and how the atlas file is written.

The block store is a folder beside the target (``.ATLAS.nc.partial/``): one ``.npy`` per
finished block, written under a temporary name and renamed, and a manifest naming the spec,
code version and chunk shape it belongs to. The atlas is assembled from the store under a
temporary name and renamed, so a file at the target is always a whole atlas.
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
import contextlib
import json
import os
import shutil
import tempfile
import zlib
from pathlib import Path

import numpy as np

from sweep.errors import UserError
from sweep.metadata import code_version


def same_file(a, b) -> bool:
    """Whether two paths name one file (links and relative names resolved)."""
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except OSError:
        return False


def check_target(path: Path, force: bool, suffix: str = ".nc", inputs=()) -> None:
    """Refuse, before any compute, to overwrite a file without ``force``, to write over one
    of the command's ``inputs`` (force or not), or to write where we cannot: a wrong
    suffix, an empty or too long name, a missing or read-only folder, a file system that
    does not take new files (/proc). The folder is tried by creating and removing a file
    in it."""
    from sweep.resources import check_name

    if not path.name or str(path) in (".", ""):
        raise UserError(f"path: an empty file name; give one ending in {suffix}")
    if path.suffix != suffix:
        raise UserError(f"path: {path} must end in {suffix}")
    check_name(path)  # before any look at the path: a name too long fails every call on it
    for source in inputs:
        if source and same_file(path, source):
            raise UserError(f"path: {path} is this command's input {source}; write to "
                            "another file (force=True never overwrites an input)")
    if path.is_dir():
        raise UserError(f"path: {path} is a directory")
    if path.exists() and not force:
        raise UserError(f"path: {path} exists; pass force=True to overwrite it")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise UserError(f"path: directory {parent} does not exist")
    try:
        with tempfile.NamedTemporaryFile(dir=parent, prefix=".sweep-probe-"):
            pass
    except OSError as err:
        raise UserError(f"path: cannot write in {parent} ({err.strerror or err})") from None


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
                raise UserError(f"resume: {folder} has no readable manifest; run again with "
                                "force=True to start over") from None
            for key, what in compared.items():
                if old.get(key) != manifest[key]:
                    changed = ""
                    if key == "spec":
                        changed = " (" + ", ".join(spec_changes(old.get(key), manifest[key])) + ")"
                    raise UserError(f"resume: the interrupted run used a different {what}"
                                    f"{changed}; run again with force=True to start over")
            return True
        if not force:
            raise UserError(f"path: an interrupted run left {folder}; pass resume=True to "
                            "continue it or force=True to start over")
        shutil.rmtree(folder)
    elif resume:
        raise UserError(f"resume: nothing to resume at {folder}")
    folder.mkdir()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    return False


def spec_changes(old_json, new_json, limit: int = 3) -> list[str]:
    """What changed between two recorded specs, as dotted keys with the old and new value:
    ``grid.R.num 36 -> 37``, ``method.tol 1e-08 -> 1e-06`` (at most ``limit``)."""
    try:
        old, new = json.loads(old_json or "{}"), json.loads(new_json)
    except ValueError:
        return ["unreadable"]
    found: list[str] = []

    def walk(a, b, where):
        if len(found) >= limit:
            return
        if isinstance(a, dict) and isinstance(b, dict):
            for key in list(a) + [k for k in b if k not in a]:
                walk(a.get(key, "(not given)"), b.get(key, "(not given)"),
                     f"{where}.{key}" if where else key)
        elif a != b:
            found.append(f"{where} {json.dumps(a)[:40]} -> {json.dumps(b)[:40]}")

    walk(old, new, "")
    return found or ["its layout"]


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
            self.done = self._finished()

    def _finished(self) -> set[str]:
        """The names of the finished blocks on disk (a block being written has a hidden
        temporary name)."""
        return {name[:-4] for name in os.listdir(self.folder)
                if name.endswith(".npy") and not name.startswith(".")}

    @property
    def kept(self) -> int:
        """Finished blocks in the store, from earlier runs and from this one, counted on
        disk: a Ctrl-C between a block's rename and a count kept in memory made the
        message one short of what was kept."""
        return len(self._finished())

    def has(self, index) -> bool:
        return block_name(index) in self.done

    def save(self, index, block: np.ndarray) -> None:
        with atomic(self.folder / f"{block_name(index)}.npy") as tmp, open(tmp, "wb") as fh:
            np.save(fh, block)

    def load(self, index) -> np.ndarray:
        return np.load(self.folder / f"{block_name(index)}.npy")

    def discard(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def write_atlas(store: BlockStore, plan, path: Path, history: str,
                workers: int | None = None) -> None:
    """Write the atlas from the block store under a temporary name, then rename.

    netCDF4 defines the file (dimensions, coordinates, attributes, the variables' chunking
    and filters); the blocks, which are aligned with the netCDF chunks, are then encoded
    by the file's own filter pipeline (shuffle, zlib) on ``workers`` threads and stored as
    whole chunks (HDF5 direct chunk writes). netCDF4 itself compresses on one thread after
    all compute, a single pass that was a large part of a cheap sweep's run."""
    import h5py
    import netCDF4

    from sweep.engine import build

    template = build(plan.sweep, lazy=False)
    template.attrs["history"] = history
    with atomic(path) as tmp:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            _define(nc, template)
        with h5py.File(tmp, "r+") as h5:
            _write_blocks(h5, store, plan, workers or os.cpu_count() or 1)


#: HDF5's filter identifiers (H5Zpublic.h): the ones netCDF4 puts in an atlas's pipeline
_DEFLATE, _SHUFFLE = 1, 2
#: deflate levels compressed by ISA-L (its levels stop at 3), above by zlib
ISAL_LEVEL_MAX = 3


def _deflate(level: int):
    """``compress(data) -> bytes``: a zlib stream at deflate effort ``level`` (1-9), which
    any netCDF/HDF5 reader inflates: ISA-L's for levels 1-3 (on an atlas's shuffled doubles
    its level 1 ran at 1.1 GB/s against zlib's 75 MB/s at level 1, for a file 3 % larger),
    zlib's above, where a user asked for the smallest file. Chosen once per variable, not
    per chunk."""
    if level <= ISAL_LEVEL_MAX:
        from isal import isal_zlib

        return lambda data: isal_zlib.compress(data, level)
    return lambda data: zlib.compress(data, level)


def _chunk_encoder(dataset):
    """``encode(values) -> bytes``: a block as one whole chunk of ``dataset``, through the
    dataset's filter pipeline in its order (the writer defines shuffle and deflate only)."""
    plist = dataset.id.get_create_plist()
    steps = []
    for i in range(plist.get_nfilters()):
        code, _, options, _ = plist.get_filter(i)
        if code not in (_SHUFFLE, _DEFLATE):
            raise ValueError(f"{dataset.name}: HDF5 filter {code} is not written here")
        steps.append((code, dataset.dtype.itemsize if code == _SHUFFLE
                      else _deflate(int(options[0]))))
    dtype, shape = dataset.dtype, dataset.chunks

    def encode(values):
        chunk = np.ascontiguousarray(values, dtype=dtype)
        if chunk.shape != shape:  # an edge chunk is stored whole; the rest is never read
            whole = np.zeros(shape, dtype)
            whole[tuple(slice(0, n) for n in chunk.shape)] = chunk
            chunk = whole
        data = chunk.view(np.uint8)
        for code, option in steps:
            if code == _SHUFFLE:  # byte j of every element together
                data = data.reshape(-1, option).T.copy()
            else:
                data = option(data.tobytes())
        return data if isinstance(data, bytes) else data.tobytes()

    return encode


def _write_blocks(h5, store: BlockStore, plan, workers: int) -> None:
    """Every block of the store into the defined file as whole chunks (blocks are aligned
    with the chunks: Plan cuts the grid by the chunk shape). Deflate releases the GIL, so
    the chunks of a few blocks are encoded on ``workers`` threads while this one loads the
    next block and writes the finished chunks in order."""
    encoders: dict = {}
    pending: collections.deque = collections.deque()

    def write_oldest():
        dataset, offset, encoded = pending.popleft()
        dataset.id.write_direct_chunk(offset, encoded.result())

    with cf.ThreadPoolExecutor(max_workers=workers) as pool:
        for index, location in plan.locations():
            starts = tuple(a for a, _ in location)
            for name, values in plan.split(store.load(index)).items():
                dataset = h5[name]
                if name not in encoders:
                    encoders[name] = _chunk_encoder(dataset)
                offset = starts + (0,) * (values.ndim - len(starts))
                pending.append((dataset, offset, pool.submit(encoders[name], values)))
            while len(pending) > 2 * workers * len(encoders):
                write_oldest()
        while pending:
            write_oldest()


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
            var = nc.createVariable(name, "S1", ds[name].dims + (f"{name}_strlen",))
            var._Encoding = "utf-8"
            var[:] = strings.astype(f"U{width}")
        else:
            var = nc.createVariable(name, values.dtype, ds[name].dims)
            var[:] = values
        var.setncatts(dict(ds[name].attrs))
    # coordinates that are not a dimension's (what each design of a chained sweep sets):
    # named in each variable over their dimension, as CF and xarray read them
    auxiliary = [name for name in ds.coords if ds[name].dims != (name,)]
    for name, item in ds.data_vars.items():
        enc = item.encoding
        fill = enc.get("_FillValue")
        var = nc.createVariable(
            name, item.dtype, item.dims, zlib=bool(enc.get("zlib", False)),
            complevel=int(enc.get("complevel", 4)), shuffle=bool(enc.get("shuffle", False)),
            chunksizes=enc.get("chunksizes"),
            fill_value=False if fill is None else fill)
        var.setncatts(dict(item.attrs))
        linked = [c for c in auxiliary if set(ds[c].dims) <= set(item.dims)]
        if linked:
            var.setncattr("coordinates", " ".join(linked))
