"""Atlas metadata (CF attributes, provenance) and the atomic netCDF writer (atlas.md §2)."""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

import sweep as _pkg
from kernels.status import FLAG_MEANINGS
from sweep.errors import UserError

CONVENTIONS = "CF-1.10"


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for name in ("impact-sweep", "numpy", "numba", "llvmlite", "xarray", "dask", "netCDF4",
                 "pydantic", "click"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def code_version() -> str:
    """Package version, plus the git commit (and '-dirty') when run from a checkout."""
    here = Path(__file__).resolve().parent.parent
    try:
        rev = subprocess.run(["git", "-C", str(here), "describe", "--always", "--dirty",
                              "--abbrev=12"], capture_output=True, text=True, timeout=5)
        if rev.returncode == 0 and rev.stdout.strip():
            return f"{_pkg.__version__}+git.{rev.stdout.strip()}"
    except (OSError, subprocess.SubprocessError):
        pass
    return _pkg.__version__


def flag_attributes(flags: tuple[str, ...], usable: tuple[str, ...] = ()) -> dict:
    values = np.array([FLAG_MEANINGS.index(f) for f in flags], dtype=np.int8)
    return {"long_name": "status of the grid point", "units": "1",
            "flag_values": values, "flag_meanings": " ".join(flags),
            "usable_flags": " ".join(("ok",) + tuple(usable)),
            "comment": "usable_flags: statuses whose outputs are design values"}


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
    for axis in sweep.axes:
        p = axis.parameter
        ds[axis.name].attrs.update(units=p.units, long_name=p.long_name)
    by_name = {o.name: o for o in mech.outputs + mech.profiles}
    level = sweep.run.compress_level
    if mech.profile_dim is not None and mech.profile_dim.name in ds.coords:
        pdim = mech.profile_dim
        ds[pdim.name].attrs.update(units=pdim.units, long_name=pdim.long_name)
        ds[pdim.name].encoding["_FillValue"] = None
    for name in sweep.outputs:
        o = by_name[name]
        ds[name].attrs.update(units=o.units, long_name=o.long_name,
                              ancillary_variables="status")
        if o.description:
            ds[name].attrs["comment"] = o.description
        if o.flags:
            ds[name].attrs.update(flag_values=np.arange(len(o.flags), dtype=np.float64),
                                  flag_meanings=" ".join(o.flags))
        chunks = chunk_shape + tuple(ds.sizes[d] for d in ds[name].dims[len(chunk_shape):])
        ds[name].encoding.update(zlib=level > 0, complevel=level, shuffle=True,
                                 chunksizes=chunks, _FillValue=np.nan)
    ds["status"].attrs.update(flag_attributes(mech.flags, mech.usable_flags))
    ds["status"].encoding.update(zlib=level > 0, complevel=level, chunksizes=chunk_shape,
                                 _FillValue=None)
    for axis in sweep.axes:
        ds[axis.name].encoding["_FillValue"] = None
        if axis.parameter.choices is not None:
            # fixed-width chars, not HDF5 variable-length strings: reopening a file with
            # vlen strings after closing another handle on it segfaults (xarray #8289)
            ds[axis.name].encoding["dtype"] = "S1"
    ds.attrs.update(
        Conventions=CONVENTIONS,
        title=sweep.title,
        institution="impact-sweep",
        source=f"impact-sweep {_pkg.__version__}, mechanism {mech.name}",
        mechanism=mech.name,
        spec=sweep.spec_json(),
        method=json.dumps({"model": mech.method_text, **sweep.method}),
        package_versions=json.dumps(package_versions()),
        code_version=code_version(),
    )
    return ds


def history_line(argv: list[str] | None = None) -> str:
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    args = " ".join(argv if argv is not None else ["sweep"] + sys.argv[1:])
    return f"{now}: {args}"


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


def _define(nc, ds: xr.Dataset) -> None:
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


def partial_dir(path: Path) -> Path:
    """Where the finished blocks of a run on ``path`` are kept until the atlas is written."""
    return path.with_name(f".{path.name}.partial")


def _manifest(sweep, plan) -> dict:
    return {"spec": sweep.spec_json(), "code_version": code_version(),
            "chunk_shape": list(plan.chunk_shape), "rows": plan.rows,
            "blocks": plan.n_blocks}


def _open_store(sweep, plan, path: Path, resume: bool, force: bool) -> tuple[Path, set]:
    """The block store beside the target: new, or checked and reused with --resume."""
    store = partial_dir(path)
    manifest = _manifest(sweep, plan)
    if store.exists():
        if resume:
            try:
                old = json.loads((store / "manifest.json").read_text())
            except (OSError, ValueError):
                raise UserError(f"resume: {store} has no readable manifest; rerun with "
                                "--force to start over") from None
            for key, what in (("spec", "spec"), ("code_version", "code version"),
                              ("chunk_shape", "chunk size")):
                if old.get(key) != manifest[key]:
                    raise UserError(f"resume: the interrupted run used a different {what}; "
                                    "rerun with --force to start over")
            done = {name[:-4] for name in os.listdir(store)
                    if name.endswith(".npy") and not name.startswith(".")}
            return store, done
        if not force:
            raise UserError(f"output: an interrupted run left {store}; use --resume to "
                            "continue it or --force to start over")
        shutil.rmtree(store)
    elif resume:
        raise UserError(f"resume: nothing to resume at {store}")
    store.mkdir()
    (store / "manifest.json").write_text(json.dumps(manifest))
    return store, set()


def _block_name(index) -> str:
    return "b" + "_".join(str(i) for i in index)


def run_sweep(sweep, path: Path, chunk: int | None = None, workers: int | None = None,
              progress: bool = True, history: str | None = None, resume: bool = False,
              force: bool = False, scheduler: str | None = None) -> dict:
    """Compute every block (threads here, or a dask.distributed cluster), keep each finished
    block in a store beside the target, then write the atlas atomically from the store.

    Nothing is lost: a killed run leaves its finished blocks, and ``resume`` computes only
    the rest (refused for a different spec, code version or chunk size). Blocks are written
    to the store under a temporary name and renamed, so a kill mid-write leaves no half
    block. At most 2 x workers blocks are in flight, so memory stays bounded whatever the
    grid size. Returns {"blocks": total, "reused": done before this run}.
    """
    import concurrent.futures as cf

    from tqdm import tqdm

    from sweep.engine import Plan, kernel_array, run_block

    plan = Plan(sweep, chunk)
    store, done = _open_store(sweep, plan, path, resume, force)
    todo = [(index, loc) for index, loc in plan.locations() if _block_name(index) not in done]

    def save(index, block):
        name = _block_name(index)
        with open(store / f".{name}.tmp", "wb") as fh:
            np.save(fh, block)
        os.replace(store / f".{name}.tmp", store / f"{name}.npy")

    bar = tqdm(total=plan.n_blocks, initial=len(done), unit="block", delay=1.5,
               disable=not progress, file=sys.stderr, desc="sweep")
    try:
        if scheduler:
            _compute_distributed(sweep, todo, save, bar, scheduler, run_block)
        else:
            stacked = kernel_array(plan)
            workers = workers or os.cpu_count() or 1
            with cf.ThreadPoolExecutor(max_workers=workers) as pool:
                pending = {}
                queue = iter(todo)
                while True:
                    while len(pending) < 2 * workers:
                        item = next(queue, None)
                        if item is None:
                            break
                        index = item[0]
                        future = pool.submit(
                            lambda i: stacked.blocks[(0,) + i].compute(scheduler="sync"), index)
                        pending[future] = index
                    if not pending:
                        break
                    finished, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
                    failure = _save_finished(finished, pending, save, bar)
                    if failure is not None:
                        # keep every block that still finishes, then report the failure
                        _save_finished(cf.wait(pending)[0], pending, save, bar)
                        raise failure
    finally:
        bar.close()
    _assemble(sweep, plan, store, path, history)
    shutil.rmtree(store, ignore_errors=True)
    return {"blocks": plan.n_blocks, "reused": len(done)}


def _save_finished(finished, pending, save, bar):
    """Store every successful block of ``finished``; return the first failure, if any."""
    failure = None
    for future in finished:
        index = pending.pop(future)
        error = future.exception()
        if error is None:
            save(index, future.result())
            bar.update(1)
        elif failure is None:
            failure = error
    return failure


def _compute_distributed(sweep, todo, save, bar, address, run_block) -> None:
    """Blocks on a dask.distributed cluster, at most 2 per worker thread in flight; a task
    on a worker that dies is rescheduled by the scheduler, so the result is unchanged."""
    from distributed import Client, as_completed

    try:
        client = Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        raise UserError(f"scheduler: cannot connect to {address} ({type(err).__name__})") \
            from None
    try:
        client.run(_limit_numba_threads)
        threads = max(1, sum(client.nthreads().values()))
        remote = client.scatter(sweep, broadcast=True)
        queue = iter(todo)
        first = []
        for _ in range(2 * threads):
            item = next(queue, None)
            if item is None:
                break
            first.append(client.submit(run_block, remote, item[1], key=f"block-{item[0]}",
                                       retries=2, pure=False))
        if not first:
            return
        keys = {f"block-{index}": index for index, _ in todo}
        futures = as_completed(first, loop=client.loop)
        for future in futures:
            index = keys[future.key]
            save(index, future.result())
            future.release()
            bar.update(1)
            item = next(queue, None)
            if item is not None:
                futures.add(client.submit(run_block, remote, item[1], key=f"block-{item[0]}",
                                          retries=2, pure=False))
    finally:
        client.close()


def _limit_numba_threads():
    """On each worker: one numba thread per dask thread, so the cores are not oversubscribed
    (numba.set_num_threads is thread-local; NUMBA_NUM_THREADS covers new threads)."""
    os.environ["NUMBA_NUM_THREADS"] = "1"
    try:
        import numba

        numba.set_num_threads(1)
    except (ImportError, ValueError):
        pass


def _assemble(sweep, plan, store: Path, path: Path, history: str | None) -> None:
    """Write the atlas from the block store under a temporary name, then rename."""
    import netCDF4

    from sweep.engine import build

    template = build(sweep, plan.requested)
    template.attrs["history"] = history or history_line()
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            _define(nc, template)
            for index, location in plan.locations():
                block = np.load(store / f"{_block_name(index)}.npy")
                region = tuple(slice(a, b) for a, b in location)
                for name, values in plan.split(block).items():
                    nc[name][region] = values
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def status_counts(ds: xr.Dataset) -> dict[str, int]:
    status = ds["status"]
    values = [int(v) for v in np.atleast_1d(status.attrs["flag_values"])]
    meanings = status.attrs["flag_meanings"].split()
    counts = np.bincount(np.asarray(status.values, dtype=np.int64).ravel(),
                         minlength=len(FLAG_MEANINGS))
    return {m: int(counts[v]) for v, m in zip(values, meanings)}
