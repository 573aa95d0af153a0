"""Running a sweep: blocks computed on local threads or a dask.distributed cluster, each
finished block kept in the block store, then the atlas written from the store.

Why the local path has its own thread pool rather than dask's threaded scheduler: a run must
store every block the moment it finishes (so that a killed run resumes), keep at most a few
blocks in memory whatever the grid size, and write netCDF from one thread only (HDF5 is not
thread-safe). A thread pool with a bounded queue does exactly that; dask's ``compute``
returns results only at the end. Both paths call the same ``engine.run_block``, so the
atlas is the same bits whichever runs it. ``engine.build`` still gives the lazy dask-backed
Dataset for use from Python.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import sys
import time
from pathlib import Path

from sweep import engine
from sweep.errors import UserError
from sweep.metadata import history_line
from sweep.store import BlockStore, write_atlas


def run_sweep(sweep, path: Path, chunk: int | None = None, workers: int | None = None,
              progress: bool = True, history: str | None = None, resume: bool = False,
              force: bool = False, scheduler: str | None = None) -> dict:
    """Compute every block, keep each finished block in a store beside the target, then
    write the atlas atomically from the store.

    ``chunk``, ``workers`` and ``scheduler`` override the spec's ``[run]`` settings (and are
    recorded in the atlas's spec). Before anything is written: the run's disk and memory are
    estimated and a run that cannot fit is refused; the target is locked (another live run
    on it is refused); a cluster is connected to. Nothing is lost: a killed run leaves its
    finished blocks, and ``resume`` computes only the rest (refused for a different spec,
    code version or chunk size); Ctrl-C, a full disk or a lost cluster say how many blocks
    were kept. At most 2 x workers blocks are in flight, so memory stays bounded whatever
    the grid size. Returns {"blocks": total, "reused": done before this run}.
    """
    from sweep import resources

    path = Path(path)
    sweep = sweep.with_run(chunk=chunk, workers=workers, scheduler=scheduler)
    plan, need = check_run(sweep, path)
    if progress and (need.store > resources.ANNOUNCE_BYTES or sweep.size >= 10**7):
        print(f"sweep: {need.text()}", file=sys.stderr, flush=True)
    with resources.target_lock(path):
        resources.remove_stale_temporaries(path)
        client = connect(sweep.run.scheduler) if sweep.run.scheduler else None
        try:
            store = BlockStore(sweep, plan, path, resume, force)
            todo = [(index, loc) for index, loc in plan.locations() if not store.has(index)]
            with kept_on_failure(store, path):
                compute(sweep, plan, todo, store.save, progress, done=len(store.done),
                        client=client)
                write_atlas(store, plan, path, history or history_line(), sweep.run.workers)
        finally:
            if client is not None:
                client.close()
        store.discard()
    return {"blocks": plan.n_blocks, "reused": len(store.done)}


def check_run(sweep, path: Path):
    """(the plan, the Estimate) of a run of ``sweep`` (its run settings final) into
    ``path``, refused where it cannot fit on the target's disk or in memory: before the
    target is locked or anything is written."""
    from sweep import resources

    plan = engine.Plan(sweep)
    need = run_estimate(sweep, plan)
    resources.check_fits(need, path.parent if str(path.parent) else Path("."))
    return plan, need


def run_estimate(sweep, plan):
    """The disk and memory a run of ``sweep`` will take (resources.Estimate), from its
    sizes alone."""
    from sweep import resources

    flags = 1 + sum(1 for name in sweep.scalar_outputs if sweep.mechanism.output(name).is_flag)
    block = max(1, min(sweep.size, __import__("math").prod(plan.chunk_shape)))
    return resources.estimate(sweep.size, plan.rows, flags, len(sweep.mechanism.parameters),
                              block, sweep.run.workers or os.cpu_count() or 1,
                              len(sweep.mechanism.outputs))


@contextlib.contextmanager
def kept_on_failure(store, path: Path):
    """Say what was kept when a run stops: Ctrl-C (RunInterrupted) or a disk that is full
    or refuses the file's size (RunFailed), with how to continue."""
    from sweep import resources

    try:
        yield
    except KeyboardInterrupt:
        raise resources.RunInterrupted(
            f"interrupted; {_kept(store)} in {store.folder}; `sweep run SPEC -o {path} "
            "--resume` continues") from None
    except (OSError, RuntimeError) as err:
        meaning = resources.disk_failure(err)
        if meaning is None:
            raise
        raise resources.RunFailed(
            f"path: cannot write {path}: {meaning}; {_kept(store)} in {store.folder}; "
            "`--resume` continues once there is room") from None


def _kept(store) -> str:
    n = store.kept
    return f"{n} finished block{'' if n == 1 else 's'} {'is' if n == 1 else 'are'} kept"


def compute(sweep, plan, todo, save, progress: bool, done: int = 0, client=None) -> None:
    """Compute the blocks ``todo`` ([(index, location)]) on local threads or on the cluster
    of ``client``, handing each finished one to ``save(index, block)`` as it comes, under a
    progress bar (with the time left, once the first blocks are timed)."""
    from tqdm import tqdm

    if todo and client is None:
        compile_first(sweep, announce=progress)
    bar = tqdm(total=plan.n_blocks, initial=done, unit="block", delay=1.5,
               disable=not progress, file=sys.stderr, desc="sweep", **terminal_bar_size())

    def saved(index, block):
        save(index, block)
        bar.update(1)

    try:
        if client is not None:
            _compute_distributed(sweep, todo, saved, client)
        else:
            _compute_local(sweep, todo, saved, sweep.run.workers or os.cpu_count() or 1)
    finally:
        bar.close()


def memory_estimate(sweep) -> int:
    """Bytes an atlas of ``sweep`` takes in memory: every output, status and profile."""
    plan = engine.Plan(sweep)
    return 8 * plan.rows * sweep.size


def run_in_memory(sweep, progress: bool = False, history: str | None = None):
    """The atlas of a sweep as an xarray Dataset in memory: the same blocks through the
    same kernels as a file run (so the same values), the same attributes and encodings
    (``to_netcdf`` writes it as ``sweep run`` would)."""
    import numpy as np
    import xarray as xr

    plan = engine.Plan(sweep)
    template = engine.build(sweep, lazy=False)
    arrays = {name: np.empty(v.shape, v.dtype) for name, v in template.data_vars.items()}
    blocks = list(plan.locations())
    location_of = dict(blocks)

    def save(index, block):
        part = tuple(slice(start, stop) for start, stop in location_of[index])
        for name, values in plan.split(block).items():
            arrays[name][part] = values

    client = connect(sweep.run.scheduler) if sweep.run.scheduler else None
    try:
        compute(sweep, plan, blocks, save, progress, client=client)
    finally:
        if client is not None:
            client.close()
    ds = xr.Dataset({name: (v.dims, arrays[name]) for name, v in template.data_vars.items()},
                    coords={name: (v.dims, v.values) for name, v in template.coords.items()})
    for name, v in list(template.coords.items()) + list(template.data_vars.items()):
        ds[name].attrs.update(v.attrs)
        ds[name].encoding.update(v.encoding)
    ds.attrs.update(template.attrs, history=history or history_line(["python", "sweep.run"]))
    return ds


def terminal_bar_size() -> dict:
    """tqdm's line size on standard error: its terminal's own, or 80 x 24 where the terminal
    reports none. A new pseudo-terminal reports 0 x 0, and tqdm then prints every line
    empty (the sweep's block bar and the compile's clock alike)."""
    try:
        columns, rows = os.get_terminal_size(sys.stderr.fileno())
    except (AttributeError, OSError, ValueError):  # not a terminal, or no file descriptor
        return {}
    return {} if columns and rows else {"ncols": 80, "nrows": 24}


COMPILE_NOTICE_AFTER = 0.5  # s: a warm run takes less; numba's first compile far more


def compile_first(sweep, announce: bool) -> None:
    """Compile the kernels the sweep needs (engine.warm_up) before the blocks start, and
    say so when it takes long: numba compiles on a first run (tens of seconds for the
    pendulum's integration core), and the cache makes later runs start at once. Without
    this the progress bar would sit at 0 for that time. Where the spec needs several entry
    points (engine.compile_groups) and the first is not in the cache, the others compile
    meanwhile in processes of their own (compile_ahead.compile_in_parallel), one per core."""
    started = time.perf_counter()
    params = engine.sample_parameters(sweep)
    groups = engine.compile_groups(sweep, params)
    with cf.ThreadPoolExecutor(max_workers=3) as pool:
        compiling = pool.submit(engine.warm_up, sweep, groups[0])
        try:
            compiling.result(timeout=COMPILE_NOTICE_AFTER)
            if len(groups) > 1:
                engine.warm_up(sweep)
            return
        except cf.TimeoutError:
            pass
        if len(groups) > 1:
            from sweep.compile_ahead import compile_in_parallel, cores

            others = pool.submit(compile_in_parallel, sweep, groups[1:], max(1, cores() - 1))
            compiling = pool.submit(_after, compiling, others, sweep)
        if announce:
            _wait_with_clock(compiling, "compiling kernels (first run only; cached for later "
                                        "runs)")
        compiling.result()
    if announce:
        print(f"compiled in {time.perf_counter() - started:.0f} s", file=sys.stderr,
              flush=True)


def _after(first, others, sweep) -> None:
    """The first group compiled here and the others in their processes: all of them
    loaded here."""
    first.result()
    others.result()
    engine.warm_up(sweep)


def _wait_with_clock(future, label: str):
    """Wait for ``future`` under ``label``: on a terminal with the time so far, ticking
    every second (the stability example compiles for about a minute: a line that does not
    move looks like a hang); in a log, the label once."""
    from tqdm import tqdm

    if not sys.stderr.isatty():
        print(f"{label} ...", file=sys.stderr, flush=True)
        return future.result()
    with tqdm(total=None, desc=label, bar_format="{desc}: {elapsed}", file=sys.stderr,
              **terminal_bar_size()) as bar:
        while True:
            try:
                return future.result(timeout=1.0)
            except cf.TimeoutError:
                bar.refresh()


def _compute_local(sweep, todo, save, workers: int) -> None:
    """Blocks on a thread pool (the kernels release the GIL), at most 2 per thread in
    flight; every block that finishes is saved, even when another fails. On Ctrl-C the
    blocks not started are cancelled and the running ones finish and are saved (a second
    Ctrl-C leaves at once)."""
    with cf.ThreadPoolExecutor(max_workers=workers) as pool:
        pending = {}
        queue = iter(todo)
        try:
            while True:
                while len(pending) < 2 * workers:
                    item = next(queue, None)
                    if item is None:
                        break
                    pending[pool.submit(engine.run_block, sweep, item[1])] = item[0]
                if not pending:
                    return
                finished, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
                failure = _save_finished(finished, pending, save)
                if failure is not None:
                    _save_finished(cf.wait(pending)[0], pending, save)
                    raise failure
        except KeyboardInterrupt:
            for future in pending:
                future.cancel()
            _save_finished([f for f in cf.wait(pending)[0] if not f.cancelled()], pending,
                           save)
            raise


def _save_finished(finished, pending, save):
    """Store every successful block of ``finished``; return the first failure, if any."""
    failure = None
    for future in finished:
        index = pending.pop(future)
        error = future.exception()
        if error is None:
            save(index, future.result())
        elif failure is None:
            failure = error
    return failure


#: the schemes of a dask.distributed scheduler address a command line can reach
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss")
#: seconds to reach a scheduler, and for it to answer
CONNECT_TIMEOUT = 3.0


def connect(address: str):
    """A dask.distributed Client of the scheduler at ``address``, or one UserError line
    within a few seconds: an address that is not one, a port nobody listens on, a server
    that is not a dask scheduler, TLS without its security settings."""
    import socket
    import urllib.parse

    allowed = "tcp://HOST:PORT (or tls://, ws://, wss://)"
    try:
        parts = urllib.parse.urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
        parts = None
    if parts is None or parts.scheme not in SCHEDULER_SCHEMES or not host or not port:
        raise UserError(f"scheduler: {address!r} is not a scheduler address; allowed: "
                        f"{allowed}")
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT).close()
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise UserError(f"scheduler: cannot reach {address} ({reason})") from None
    # ask who answers before a Client is made: a Client of a server that is not a
    # scheduler hangs for its timeout and complains again when it is collected
    try:
        who = _identity(address, CONNECT_TIMEOUT)
    except (Exception, MemoryError) as err:  # noqa: BLE001 (any failure is the address's)
        who = type(err).__name__
    if not (isinstance(who, dict) and who.get("type") == "Scheduler"):
        raise UserError(f"scheduler: {address} did not answer as a dask scheduler "
                        f"({who if isinstance(who, str) else 'another server'})")
    from distributed import Client

    try:
        return Client(address, timeout=f"{CONNECT_TIMEOUT}s", set_as_default=False)
    except (Exception, MemoryError) as err:  # noqa: BLE001
        raise UserError(f"scheduler: {address} did not answer as a dask scheduler "
                        f"({type(err).__name__})") from None


def _identity(address: str, timeout: float):
    """The scheduler's identity reply (a dict with type "Scheduler"), asked over one
    connection with a deadline for the whole exchange."""
    import asyncio

    from distributed.comm import connect as open_comm

    async def ask():
        comm = await open_comm(address, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    return asyncio.run(asyncio.wait_for(ask(), timeout))


def _compute_distributed(sweep, todo, save, client) -> None:
    """Blocks on a dask.distributed cluster, at most 2 per worker thread in flight; a task
    on a worker that dies is rescheduled by the scheduler, so the result is unchanged. A
    lost scheduler stops the run with RunFailed (the finished blocks are kept)."""
    from distributed import as_completed

    from sweep.resources import RunFailed

    import logging

    # a lost scheduler is said once, by RunFailed; the client's own log lines would repeat it
    logging.getLogger("distributed.client").setLevel(logging.CRITICAL)
    lost = _lost_connection_errors()
    try:
        client.run(_limit_numba_threads)
        threads = max(1, sum(client.nthreads().values()))
        remote = client.scatter(sweep, broadcast=True)
        queue = iter(todo)

        def submit(item):
            return client.submit(engine.run_block, remote, item[1], key=f"block-{item[0]}",
                                 retries=2, pure=False)

        first = [submit(item) for item in (next(queue, None) for _ in range(2 * threads))
                 if item is not None]
        if not first:
            return
        keys = {f"block-{index}": index for index, _ in todo}
        futures = as_completed(first, loop=client.loop)
        for future in futures:
            save(keys[future.key], future.result())
            future.release()
            item = next(queue, None)
            if item is not None:
                futures.add(submit(item))
    except lost as err:
        raise RunFailed(f"scheduler: lost the cluster at {client.scheduler.address} "
                        f"({type(err).__name__}); the finished blocks are kept, `--resume` "
                        "continues") from None


def _lost_connection_errors() -> tuple:
    """The exceptions that mean the cluster went away (not a block's own failure)."""
    import asyncio

    from distributed.comm.core import CommClosedError

    errors = [CommClosedError, asyncio.CancelledError, asyncio.TimeoutError, ConnectionError]
    try:
        from distributed.client import FutureCancelledError

        errors.append(FutureCancelledError)
    except ImportError:
        pass
    return tuple(errors)


def _limit_numba_threads():
    """On each worker: one numba thread per dask thread, so the cores are not oversubscribed
    (numba.set_num_threads is thread-local; NUMBA_NUM_THREADS covers new threads)."""
    os.environ["NUMBA_NUM_THREADS"] = "1"
    try:
        import numba

        numba.set_num_threads(1)
    except (ImportError, ValueError):
        pass
