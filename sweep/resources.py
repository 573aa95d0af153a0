"""What a run needs and what it holds: the disk and memory it will take, checked against what
the machine has before anything is allocated, and the lock on its target.

A run is refused before it starts (one line, exit status 2) when its block store or atlas
cannot fit the free disk, or its blocks in flight cannot fit the available memory; the
estimate is printed for large runs. Two runs never share a target: each holds an advisory
lock (``fcntl.flock``) on ``.TARGET.lock`` beside it for its whole life; the lock file names
the holder's process id, and a lock whose process is gone is free (the kernel releases it).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from sweep.errors import UserError

#: the part of the free disk and of the available memory a run may plan to use
DISK_SHARE = 0.95
MEMORY_SHARE = 0.8
#: a run whose estimate is larger than this is announced before it starts
ANNOUNCE_BYTES = 1 << 30
#: the file-system's limit on a name, kept for the run's own names beside the target
#: (".NAME.partial", ".NAME.tmp-PID", ".NAME.lock", ".NAME.lock-PID")
NAME_ROOM = 24


class RunFailed(RuntimeError):
    """A run stopped by something outside the user's input (a full disk, a file-size limit,
    a lost scheduler): one line saying what, what was kept and how to continue (exit 1)."""


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during a run, with what was kept: ``message`` says how to continue."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message


def size_text(n: float) -> str:
    """Bytes in words: 1.2 GB, 340 MB, 12 kB."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


@dataclass(frozen=True)
class Estimate:
    """What a run of ``points`` grid points will take: the block store (every finished
    block as float64), the atlas (at most uncompressed: float64 outputs and profiles,
    int8 flags and status) and the memory of the blocks in flight (2 per worker, each
    with its parameter matrix, kernel output and stacked result)."""

    points: int
    store: int
    atlas: int
    memory: int

    def text(self) -> str:
        return (f"{self.points:,} points: block store {size_text(self.store)}, atlas up to "
                f"{size_text(self.atlas)}, memory about {size_text(self.memory)}")


def estimate(points: int, rows_per_point: int, flag_rows: int, parameters: int,
             block_points: int, workers: int, outputs: int) -> Estimate:
    """The Estimate of a run (see ``Estimate``) from its sizes alone: nothing is built."""
    store = 8 * rows_per_point * points
    atlas = (8 * (rows_per_point - flag_rows - 1) + flag_rows + 1) * points
    per_block = 8 * block_points * (parameters + outputs + 2 * rows_per_point)
    return Estimate(points, store, atlas, 2 * max(1, workers) * per_block)


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (psutil's ``available``), or None."""
    import psutil

    try:
        return int(psutil.virtual_memory().available)
    except (OSError, RuntimeError):
        return None


def free_disk(folder: Path) -> int | None:
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


def check_fits(e: Estimate, folder: Path | None, keeps_store: bool = True) -> None:
    """Refuse a run that cannot fit: the store and the atlas on the target's disk (the
    store is deleted only after the atlas is written, so both at once), the blocks in
    flight in memory."""
    if folder is not None:
        free = free_disk(folder)
        need = (e.store if keeps_store else 0) + e.atlas
        if free is not None and need > DISK_SHARE * free:
            raise UserError(f"grid: {e.text()}; the run needs up to {size_text(need)} of disk "
                            f"in {folder} and {size_text(free)} are free: sweep fewer points "
                            "or outputs, or write elsewhere")
    memory = available_memory()
    if memory is not None and e.memory > MEMORY_SHARE * memory:
        raise UserError(f"run: {e.text()}; the blocks in flight need about "
                        f"{size_text(e.memory)} of memory and {size_text(memory)} are "
                        "available: set a smaller [run] chunk or fewer workers")


def check_name(path: Path) -> None:
    """Refuse a target whose name (with the run's own names beside it) is longer than the
    file system allows, before anything is written."""
    try:
        limit = os.pathconf(path.parent if str(path.parent) else ".", "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    size = len(os.fsencode(path.name))
    if size + NAME_ROOM > limit:
        raise UserError(f"path: the file name is {size} bytes long; at most "
                        f"{limit - NAME_ROOM} here (the run keeps its blocks and lock beside "
                        "it under longer names)")


def lock_path(target: Path) -> Path:
    return target.with_name(f".{target.name}.lock")


#: the targets this process holds (a lock is taken once: a run inside a command that
#: already holds its target's lock, as ``sweep run`` holds it over its chart too)
_HELD: set[str] = set()


@contextlib.contextmanager
def target_lock(target: Path):
    """Hold the lock on ``target`` for the block's life, or refuse: another live process
    holds it (named by its process id). A lock left by a process that died is free: the
    kernel released it with the process, and this run takes it over. The lock file is
    removed when the run ends, however it ends, and by no failure left behind. (filelock's
    Unix lock keeps its file on purpose: removing it lets a process that opened the old
    file lock a deleted inode while another locks a new one; here the lock is checked to
    be the path's file after it is taken, and taken again where the path moved on.)"""
    path = lock_path(target)
    key = str(path.resolve())
    if key in _HELD:
        yield
        return
    fd = _locked_fd(path, target)
    try:
        _HELD.add(key)
        try:
            yield
        finally:
            _HELD.discard(key)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)  # releases the lock


def _locked_fd(path: Path, target: Path) -> int:
    """An open file descriptor of ``path`` holding its lock, with this process's id in it;
    a UserError naming the holder where another live process has it; RunFailed (and no
    file left) where it cannot be written. The lock file appears with its holder's id in
    it and already locked (it is written and locked under a name of its own, then linked
    to ``path``), so a run that finds it held can always say by whom."""
    pending = path.with_name(f"{path.name}-{os.getpid()}")
    try:
        for attempt in range(100):
            try:
                fd = os.open(path, os.O_RDWR)
            except FileNotFoundError:
                fd = _publish(pending, path, target)
                if fd is not None:
                    return fd
                continue  # another run published its lock first, or ours was swept away
            except OSError as err:
                raise _cannot_lock(target, err) from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as err:
                holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "unknown"
                os.close(fd)
                if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise
                if not _running(holder) and attempt < 99:
                    time.sleep(0.005)  # another run is taking over a dead process's lock
                    continue
                raise UserError(f"path: another run (process {holder}) is writing {target}; "
                                "wait for it to finish, or stop it first") from None
            # the lock of a process that is gone: removed while held, then ours is published
            with contextlib.suppress(FileNotFoundError):
                if os.fstat(fd).st_ino == os.stat(path).st_ino:
                    os.unlink(path)
            os.close(fd)
        raise RunFailed(f"path: cannot lock {target}: its lock file keeps changing")
    finally:
        with contextlib.suppress(OSError):
            os.unlink(pending)


def _running(holder: str) -> bool:
    """Whether the process named in a lock file is running (a lock file names its holder
    from the moment it appears, except while a dead process's lock is being taken over)."""
    try:
        os.kill(int(holder), 0)
    except (ValueError, ProcessLookupError):
        return False
    except PermissionError:
        return True
    return True


def _publish(pending: Path, path: Path, target: Path) -> int | None:
    """Write this process's id into ``pending``, lock it and link it to ``path``: the open,
    locked descriptor, or None where ``path`` appeared first (or ``pending`` was removed as
    a stale temporary by the run that holds the target). On a file system without hard
    links (FAT) the lock file is made in place, its id written a moment after."""
    try:
        fd = os.open(pending, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o644)
    except OSError as err:
        raise _cannot_lock(target, err) from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # nobody else opens this name
        os.write(fd, f"{os.getpid()}\n".encode())
        try:
            os.link(pending, path)
        except OSError as err:
            if err.errno not in NO_HARD_LINKS:
                raise
            os.close(fd)
            fd = -1
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os.write(fd, f"{os.getpid()}\n".encode())
    except (FileExistsError, FileNotFoundError, BlockingIOError):
        _close(fd)
        return None
    except OSError as err:
        _close(fd)
        raise _cannot_lock(target, err) from None
    return fd


def _close(fd: int) -> None:
    if fd >= 0:
        os.close(fd)


#: what ``link`` says on a file system that has no hard links
NO_HARD_LINKS = (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP)


def _cannot_lock(target: Path, err: OSError) -> RunFailed:
    return RunFailed(f"path: cannot lock {target}: {disk_failure(err) or err.strerror or err}")


def remove_stale_temporaries(target: Path) -> None:
    """Temporary files of earlier runs on ``target`` (``.NAME.tmp-PID``, left by a kill
    during the final write, and ``.NAME.lock-PID``, by a kill while taking the lock): gone
    once this run holds the target's lock."""
    for pattern in (f".{target.name}.tmp-*", f".{target.name}.lock-*"):
        for stale in target.parent.glob(pattern):
            with contextlib.suppress(OSError):
                stale.unlink()


#: errors of the disk, not of the input: (errno, what it means for the user)
DISK_ERRORS = {errno.ENOSPC: "no space left on the device", errno.EDQUOT: "the disk quota is "
               "exhausted", errno.EFBIG: "the file is larger than this process may write "
               "(a file-size limit)"}


def disk_failure(err: BaseException) -> str | None:
    """What a disk failure means, or None when ``err`` is not one. netCDF-C and HDF5 raise
    RuntimeError with the errno in their text ("... errno = 28 ...")."""
    code = getattr(err, "errno", None)
    if code in DISK_ERRORS:
        return DISK_ERRORS[code]
    text = str(err)
    for number, meaning in DISK_ERRORS.items():
        if (f"errno = {number}" in text or os.strerror(number) in text
                or (number == errno.EFBIG and "File too large" in text)):
            return meaning
    if isinstance(err, OSError) and "requested and" in text and "written" in text:
        return DISK_ERRORS[errno.ENOSPC]  # numpy's short write: the disk filled up
    return None
