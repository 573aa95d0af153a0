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
    recorded in the atlas's spec). Nothing is lost: a killed run leaves its finished blocks,
    and ``resume`` computes only the rest (refused for a different spec, code version or
    chunk size). At most 2 x workers blocks are in flight, so memory stays bounded whatever
    the grid size. Returns {"blocks": total, "reused": done before this run}.
    """
    from tqdm import tqdm

    sweep = sweep.with_run(chunk=chunk, workers=workers, scheduler=scheduler)
    plan = engine.Plan(sweep)
    store = BlockStore(sweep, plan, Path(path), resume, force)
    todo = [(index, loc) for index, loc in plan.locations() if not store.has(index)]
    if todo and not sweep.run.scheduler:
        compile_first(sweep, announce=progress)
    bar = tqdm(total=plan.n_blocks, initial=len(store.done), unit="block", delay=1.5,
               disable=not progress, file=sys.stderr, desc="sweep", **terminal_bar_size())

    def save(index, block):
        store.save(index, block)
        bar.update(1)

    try:
        if sweep.run.scheduler:
            _compute_distributed(sweep, todo, save, sweep.run.scheduler)
        else:
            _compute_local(sweep, todo, save, sweep.run.workers or os.cpu_count() or 1)
    finally:
        bar.close()
    write_atlas(store, plan, Path(path), history or history_line(), sweep.run.workers)
    store.discard()
    return {"blocks": plan.n_blocks, "reused": len(store.done)}


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
    this the progress bar would sit at 0 for that time."""
    started = time.perf_counter()
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        compiling = pool.submit(engine.warm_up, sweep)
        try:
            compiling.result(timeout=COMPILE_NOTICE_AFTER)
            return
        except cf.TimeoutError:
            if not announce:
                compiling.result()
                return
        _wait_with_clock(compiling, "compiling kernels (first run only; cached for later "
                                    "runs)")
    print(f"compiled in {time.perf_counter() - started:.0f} s", file=sys.stderr, flush=True)


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
    flight; every block that finishes is saved, even when another fails."""
    with cf.ThreadPoolExecutor(max_workers=workers) as pool:
        pending = {}
        queue = iter(todo)
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


def _compute_distributed(sweep, todo, save, address: str) -> None:
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
