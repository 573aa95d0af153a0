"""Nothing starts that cannot finish, nothing collides, and every failure says what to do
(issue 34). One class of input or fault per test, each run the way a user meets it: a real
second process for a lock, a real file-size limit for a full disk, a real socket for a
scheduler that is not one, a file overwritten in the middle for a damaged atlas.

Every failure is one line on standard error with exit status 2 (bad input) or 1 (a failure
outside the user's control), and leaves nothing behind that the next plain run trips over.
The suite grows with every class of input the command line takes: add a row to the tables
below for a new one.
"""

import json
import os
import re
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
import tracemalloc
from pathlib import Path

import netCDF4
import numpy as np
import pytest

import sweep
from tests.command_line import run_cli

SWEEP = str(Path(sys.executable).with_name("sweep"))
SMALL = 'mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.4, num = 6}\n' \
        'largest_link = {start = 2.0, stop = 6.0, num = 7}\n'
#: a run of a few seconds in eight blocks (the six-link kernel, cached after the first);
#: the tests that need it to last stop it (SIGSTOP) while they act, and let it go on after
SLOW = 'mechanism = "six_link"\n[grid]\nlambda2 = {start = 1.5, stop = 1.8, num = 40}\n' \
       'beta = {start = 0.0, stop = 1.0, num = 300}\n'


def one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


def leftovers(folder: Path, name: str) -> list[str]:
    """Files a run on ``name`` left beside it: its store, lock or temporaries."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(f".{name}"))


@pytest.fixture
def small_spec(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SMALL)
    return path


@pytest.fixture(scope="module")
def atlas_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("atlas")
    spec = sweep.Sweep.from_text(SMALL.replace("num = 6", "num = 60").replace("num = 7",
                                                                            "num = 70"))
    sweep.run(spec, folder / "a.nc").close()
    return folder / "a.nc"


# ---------------------------------------------------------------- runs too big

TOO_BIG = [
    ("grid", 'mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.4, num = 100000000}'
             '\nlargest_link = {start = 2.0, stop = 6.0, num = 100000000}\n'),
    ("grid", 'mechanism = "crank_rocker"\n[grid]\nR = {start = 0.1, stop = 0.4, num = 100000}\n'
             'largest_link = {start = 2.0, stop = 6.0, num = 100000}\n'),
    ("grid", 'mechanism = "linkage_forces"\n[grid]\nomega1 = {start = 1, stop = 30, num = 1000}'
             '\ntilt = {start = 0, stop = 1, num = 1000}\n[method]\nprofile_points = 100000\n'),
]


@pytest.mark.parametrize("field, text", TOO_BIG)
def test_a_run_that_cannot_fit_is_refused_at_once_without_allocating(tmp_path, field, text):
    """10^16 points (two axes of 10^8), 10^10 points at the cap, and 10^6 designs with
    10^5-angle profiles (petabytes): refused in one line naming the sizes, without
    allocating more than a few MB (counted from the axis specifications, not from built
    arrays: no grid is built, no block computed); nothing is written. (Its time is not
    asserted: a timed assertion failed at 1.25 CPU s under load.)"""
    spec = sweep.Sweep.from_text(text) if "100000000" not in text else None
    tracemalloc.start()
    with pytest.raises(sweep.UserError) as err:
        sweep.run(spec if spec is not None else sweep.Sweep.from_text(text), tmp_path / "x.nc")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    message = str(err.value)
    assert message.startswith(field) and "points" in message
    assert peak < 50e6, peak
    assert list(tmp_path.iterdir()) == []


def test_a_large_run_says_its_estimate_before_it_starts(tmp_path, monkeypatch, capsys):
    from sweep import resources

    monkeypatch.setattr(resources, "ANNOUNCE_BYTES", 1000)
    (tmp_path / "s.toml").write_text(SMALL)
    code, _, err = run_cli(capsys, "run", tmp_path / "s.toml", "-o", tmp_path / "s.nc")
    assert code == 0 and "42 points: block store" in err and "atlas up to" in err


def test_a_tampered_grid_in_the_recorded_spec_is_refused_before_boundaries_run(
        tmp_path, atlas_file, capsys):
    """An atlas whose spec attribute was edited to a huge grid: `sweep boundaries` refuses
    it in one line instead of allocating that grid (10^8 points: 800 MB an array; the
    allocation is asserted, not the time)."""
    target = tmp_path / "t.nc"
    with netCDF4.Dataset(atlas_file) as src, netCDF4.Dataset(target, "w") as dst:
        dst.setncatts({k: src.getncattr(k) for k in src.ncattrs()})
        for name, dim in src.dimensions.items():
            dst.createDimension(name, len(dim))
        for name, var in src.variables.items():
            out = dst.createVariable(name, var.datatype, var.dimensions)
            out.setncatts({k: var.getncattr(k) for k in var.ncattrs() if k != "_FillValue"})
            out[...] = var[...]
        spec = json.loads(src.spec)
        spec["grid"]["R"] = {"start": 0.1, "stop": 0.4, "num": 10**8}
        dst.spec = json.dumps(spec)
    tracemalloc.start()
    code, _, err = run_cli(capsys, "boundaries", target)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert code == 2 and "the file was changed after the run" in one_line(err)
    assert peak < 100e6, peak


# ---------------------------------------------------------------- collisions, interruptions

def _popen(*args):
    return subprocess.Popen([SWEEP, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for(path: Path, timeout=60.0):
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.005)


def test_two_runs_on_one_target_the_second_is_refused_with_the_first_ones_pid(tmp_path):
    spec = tmp_path / "slow.toml"
    spec.write_text(SLOW)
    target = tmp_path / "slow.nc"
    first = _popen("run", spec, "-o", target, "-q")
    try:
        _wait_for(tmp_path / ".slow.nc.lock")
        first.send_signal(signal.SIGSTOP)  # holding its lock while the others try
        assert first.poll() is None, "the first run ended before its lock was seen"
        for extra in ([], ["--force"], ["--resume"]):
            second = subprocess.run([SWEEP, "run", str(spec), "-o", str(target), *extra],
                                    capture_output=True, text=True)
            line = one_line(second.stderr)
            assert second.returncode == 2 and f"process {first.pid}" in line, line
    finally:
        first.send_signal(signal.SIGCONT)
        first.wait(timeout=300)
    assert first.returncode == 0 and target.is_file()
    assert leftovers(tmp_path, "slow.nc") == []


def test_the_lock_file_never_exists_without_its_holders_id(tmp_path, monkeypatch):
    """The second run names the first by its id even where the first was stopped while it
    took its lock (CI once stopped it between making the file and writing the id): at every
    write the lock makes, its file is absent or already names its holder."""
    from sweep import resources

    path = resources.lock_path(tmp_path / "s.nc")
    seen = []

    def watching(name):
        def call(*args):
            seen.append(path.read_text() if path.exists() else None)
            return getattr(os, name)(*args)
        return call

    spy = type("os", (), {name: staticmethod(watching(name)) if name in
                          ("write", "pwrite", "ftruncate", "link") else getattr(os, name)
                          for name in dir(os) if not name.startswith("__")})
    monkeypatch.setattr(resources, "os", spy)
    with resources.target_lock(tmp_path / "s.nc"):
        assert path.read_text() == f"{os.getpid()}\n"
    assert seen and all(text in (None, f"{os.getpid()}\n") for text in seen), seen
    assert leftovers(tmp_path, "s.nc") == []


def test_without_hard_links_the_lock_is_made_in_place(tmp_path, monkeypatch):
    """A file system without hard links (FAT: link says EPERM) still gets its lock, with the
    holder's id, and nothing left beside the target."""
    import errno

    from sweep import resources

    def no_link(source, target):
        raise OSError(errno.EPERM, os.strerror(errno.EPERM))

    spy = type("os", (), {name: staticmethod(no_link) if name == "link" else getattr(os, name)
                          for name in dir(os) if not name.startswith("__")})
    monkeypatch.setattr(resources, "os", spy)
    path = resources.lock_path(tmp_path / "s.nc")
    with resources.target_lock(tmp_path / "s.nc"):
        assert path.read_text() == f"{os.getpid()}\n"
        assert leftovers(tmp_path, "s.nc") == [".s.nc.lock"]
    assert leftovers(tmp_path, "s.nc") == []


#: one contender for a lock: waits for the start file, takes the lock or names its holder
CONTENDER = """
import os, sys, time
from pathlib import Path
from sweep.resources import target_lock
from sweep.errors import UserError
target, start = Path(sys.argv[1]), Path(sys.argv[2])
while not start.exists():
    time.sleep(0.001)
try:
    with target_lock(target):
        print("held", os.getpid(), flush=True)
        time.sleep(1.0)
except UserError as err:
    print("refused", err, flush=True)
"""


@pytest.mark.parametrize("stale", [False, True], ids=["free", "left by a dead process"])
def test_runs_that_start_together_one_holds_the_lock_and_the_others_name_it(tmp_path, stale):
    """Six processes race for one target's lock (free, or left by a dead process): exactly
    one holds it, every other is refused naming that one, and nothing is left behind."""
    target, start = tmp_path / "s.nc", tmp_path / "go"
    if stale:
        (tmp_path / ".s.nc.lock").write_text("999999\n")
    racers = [subprocess.Popen([sys.executable, "-c", CONTENDER, str(target), str(start)],
                               stdout=subprocess.PIPE, text=True) for _ in range(6)]
    time.sleep(1.0)  # every contender imported and waiting
    start.touch()
    said = [racer.communicate(timeout=60)[0].split(None, 2) for racer in racers]
    holders = [int(words[1]) for words in said if words[0] == "held"]
    assert len(holders) == 1, said
    refusals = [words[2] for words in said if words[0] == "refused"]
    assert len(refusals) == 5 and all(f"process {holders[0]})" in r for r in refusals), said
    assert leftovers(tmp_path, "s.nc") == []


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path, small_spec, capsys):
    """A lock file from a process that died (its flock went with it) does not block."""
    (tmp_path / ".s.nc.lock").write_text("999999\n")
    code, out, _ = run_cli(capsys, "run", small_spec, "-o", tmp_path / "s.nc")
    assert code == 0 and (tmp_path / "s.nc").is_file()
    assert leftovers(tmp_path, "s.nc") == []


def test_ctrl_c_says_how_many_blocks_were_kept_and_resume_finishes(tmp_path):
    spec = tmp_path / "slow.toml"
    spec.write_text(SLOW)
    target = tmp_path / "slow.nc"
    run = _popen("run", spec, "-o", target, "-q")
    store = tmp_path / ".slow.nc.partial"
    deadline = time.monotonic() + 120
    while not (store.is_dir() and any(p.suffix == ".npy" for p in store.iterdir())):
        assert time.monotonic() < deadline
        time.sleep(0.005)
    run.send_signal(signal.SIGSTOP)  # the Ctrl-C arrives while blocks are left to do
    run.send_signal(signal.SIGINT)
    run.send_signal(signal.SIGCONT)
    _, err = run.communicate(timeout=120)
    kept = sum(1 for p in store.iterdir() if p.suffix == ".npy")
    line = one_line(err)
    assert run.returncode == 130 and f"{kept} finished block" in line and "--resume" in line
    done = subprocess.run([SWEEP, "run", str(spec), "-o", str(target), "--resume"],
                          capture_output=True, text=True)
    resumed = re.search(rf"resumed: {kept} of (\d+) blocks", done.stdout)
    assert done.returncode == 0 and resumed and int(resumed.group(1)) > kept, done.stdout


def test_a_file_size_limit_is_one_line_keeps_the_blocks_and_resume_gives_the_same_atlas(
        tmp_path):
    """RLIMIT_FSIZE in a child: the writes fail with EFBIG; one line, exit 1, the blocks
    kept; without the limit --resume writes the atlas an uninterrupted run writes."""
    spec = tmp_path / "slow.toml"
    spec.write_text(SLOW)

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (400_000, 400_000))

    failed = subprocess.run([SWEEP, "run", str(spec), "-o", str(tmp_path / "a.nc"), "-q"],
                            capture_output=True, text=True, preexec_fn=limit)
    line = one_line(failed.stderr)
    assert failed.returncode == 1 and "file-size limit" in line and "--resume" in line
    assert not (tmp_path / "a.nc").exists() and (tmp_path / ".a.nc.partial").is_dir()
    resumed = subprocess.run([SWEEP, "run", str(spec), "-o", str(tmp_path / "a.nc"), "-q",
                              "--resume"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    whole = subprocess.run([SWEEP, "run", str(spec), "-o", str(tmp_path / "b.nc"), "-q"],
                           capture_output=True, text=True)
    assert whole.returncode == 0
    with netCDF4.Dataset(tmp_path / "a.nc") as a, netCDF4.Dataset(tmp_path / "b.nc") as b:
        for name in b.variables:
            np.testing.assert_array_equal(a[name][...], b[name][...])
    assert leftovers(tmp_path, "a.nc") == []


def test_a_temporary_file_left_by_a_kill_during_the_write_is_cleaned(tmp_path, small_spec,
                                                                      capsys):
    stale = tmp_path / ".s.nc.tmp-999999"
    stale.write_bytes(b"half an atlas")
    code, _, _ = run_cli(capsys, "run", small_spec, "-o", tmp_path / "s.nc")
    assert code == 0 and not stale.exists()


def test_resume_with_a_changed_spec_names_what_changed(tmp_path, small_spec, capsys):
    folder = tmp_path / ".s.nc.partial"
    folder.mkdir()
    old = sweep.Sweep.from_toml(small_spec).to_dict()
    old.pop("run")
    old["grid"]["R"]["num"] = 5
    (folder / "manifest.json").write_text(json.dumps({"spec": json.dumps(old)}))
    code, _, err = run_cli(capsys, "run", small_spec, "-o", tmp_path / "s.nc", "--resume")
    assert code == 2 and "grid.R.num 5 -> 6" in one_line(err)


# ---------------------------------------------------------------- clusters

@pytest.fixture
def not_a_scheduler():
    """A TCP server on a free port that answers every connection with garbage."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    stop = threading.Event()

    def serve():
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"\xff" * 64 + b"HTTP/1.1 200 OK\r\n\r\nhello" * 50)
                time.sleep(0.2)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join()
    server.close()


#: not a speed bound: a refusal by the run's own connect timeout (runner.CONNECT_TIMEOUT,
#: 3 s) comes well inside distributed's default of 30 s, which a run that waited on dask
#: would take; the margin is for a loaded machine's interpreter start-up
NOT_DASKS_WAIT = 25.0


def _closed_port() -> int:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


@pytest.mark.parametrize("address", ["not a url", "inproc://x", "tls://127.0.0.1:1",
                                     "tcp://127.0.0.1:{closed}", "tcp://:8786",
                                     "tcp://127.0.0.1:99999", "garbage"])
def test_a_bad_scheduler_is_one_line_without_waiting_for_dask_and_leaves_nothing(
        tmp_path, small_spec, address):
    address = address.format(closed=_closed_port())
    started = time.monotonic()
    done = subprocess.run([SWEEP, "run", str(small_spec), "-o", str(tmp_path / "s.nc"),
                           "--scheduler", address], capture_output=True, text=True)
    assert time.monotonic() - started < NOT_DASKS_WAIT
    assert done.returncode == 2 and one_line(done.stderr).startswith("sweep: error: scheduler")
    assert leftovers(tmp_path, "s.nc") == [] and not (tmp_path / "s.nc").exists()


def test_a_server_that_is_not_a_dask_scheduler_is_one_line(tmp_path, small_spec,
                                                           not_a_scheduler):
    started = time.monotonic()
    done = subprocess.run([SWEEP, "run", str(small_spec), "-o", str(tmp_path / "s.nc"),
                           "--scheduler", not_a_scheduler], capture_output=True, text=True)
    assert time.monotonic() - started < NOT_DASKS_WAIT
    assert done.returncode == 2 and "did not answer as a dask scheduler" in one_line(
        done.stderr)
    assert leftovers(tmp_path, "s.nc") == []


@pytest.mark.slow
def test_a_scheduler_lost_mid_run_is_one_line_and_the_blocks_are_kept(tmp_path):
    """A real scheduler and worker (the dask command line), the scheduler killed once the
    first blocks are in: one line, exit 1, the blocks kept; --resume finishes locally."""
    port = _closed_port()
    dask = str(Path(sys.executable).with_name("dask"))
    scheduler = subprocess.Popen([dask, "scheduler", "--port", str(port), "--no-dashboard"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        address = f"tcp://127.0.0.1:{port}"
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < deadline
                time.sleep(0.2)
        worker = subprocess.Popen([dask, "worker", address, "--nthreads", "2",
                                   "--no-dashboard"], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        spec = tmp_path / "slow.toml"
        spec.write_text(SLOW.replace("num = 300", "num = 3000"))  # outlasts the poll below
        run = _popen("run", spec, "-o", tmp_path / "slow.nc", "-q", "--scheduler", address)
        store = tmp_path / ".slow.nc.partial"
        deadline = time.monotonic() + 180
        while not (store.is_dir() and any(p.suffix == ".npy" for p in store.iterdir())):
            assert time.monotonic() < deadline and run.poll() is None, run.stderr.read()
            time.sleep(0.1)
        scheduler.kill()
        _, err = run.communicate(timeout=120)
        line = one_line(err)
        assert run.returncode == 1 and "lost the cluster" in line and "--resume" in line
        assert any(p.suffix == ".npy" for p in store.iterdir())
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.kill()
                process.wait()
    done = subprocess.run([SWEEP, "run", str(spec), "-o", str(tmp_path / "slow.nc"),
                           "--resume", "-q"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert leftovers(tmp_path, "slow.nc") == []


# ---------------------------------------------------------------- other commands' outputs

def _other_outputs(atlas, folder):
    """(command line, what it writes) for each command that writes a file."""
    return [
        (["chart", atlas, "--x", "R", "--y", "largest_link", "--color", "impact_speed", "-o"],
         ".png"),
        (["examples", "crank_rocker", "-o"], ".toml"),
        (["boundaries", atlas, "-q", "-o"], ".nc"),
    ]


@pytest.mark.parametrize("where, words", [
    ("missing/out", "does not exist"), ("/proc/out", "cannot write in /proc"),
    ("", "an empty file name"), ("x" * 250, "bytes long"), ("out.wrong", "must end in"),
])
def test_every_command_checks_its_output_before_it_works(tmp_path, capsys, atlas_file,
                                                         where, words):
    for argv, suffix in _other_outputs(atlas_file, tmp_path):
        name = where if where in ("", ) or where.endswith(".wrong") else where + suffix
        target = name if name.startswith("/") or not name else str(tmp_path / name)
        code, _, err = run_cli(capsys, *argv, target)
        assert code == 2 and words in one_line(err), (argv, err)


def test_an_existing_file_is_overwritten_only_with_force_by_every_command(tmp_path, capsys,
                                                                          atlas_file):
    for argv, suffix in _other_outputs(atlas_file, tmp_path):
        target = tmp_path / f"exists{suffix}"
        target.write_text("keep me")
        code, _, err = run_cli(capsys, *argv, target)
        assert code == 2 and "exists" in one_line(err) and target.read_text() == "keep me"
        code, _, err = run_cli(capsys, *argv, target, "--force")
        assert code == 0, err


# ---------------------------------------------------------------- damaged or foreign atlases

def test_a_damaged_atlas_is_one_line_exit_2(tmp_path, atlas_file, capsys):
    damaged = tmp_path / "d.nc"
    data = bytearray(atlas_file.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 60_000] = os.urandom(min(60_000, len(data) - middle))
    damaged.write_bytes(bytes(data))
    for argv in (["query", damaged], ["info", damaged],
                 ["chart", damaged, "--x", "R", "--y", "largest_link", "--color",
                  "impact_speed", "-o", tmp_path / "c.png"]):
        code, _, err = run_cli(capsys, *argv)
        if code == 0:  # the overwritten part held nothing this command reads
            continue
        assert code == 2 and "damaged" in one_line(err), err


def test_a_file_without_flag_meanings_is_not_an_atlas(tmp_path, capsys):
    path = tmp_path / "nf.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("x", 3)
        nc.createVariable("status", "i1", ("x",))[:] = [0, 1, 0]
        nc.mechanism = "crank_rocker"
    for command in ("query", "info"):
        code, _, err = run_cli(capsys, command, path)
        assert code == 2 and "not an atlas of this tool" in one_line(err)


def test_a_where_on_a_profile_is_one_line(tmp_path, capsys):
    atlas = tmp_path / "lf.nc"
    sweep.run({"mechanism": "linkage_forces", "grid": {"omega1": [20.0, 30.0]},
               "method": {"profile_points": 37}}, atlas).close()
    code, _, err = run_cli(capsys, "query", atlas, "--where", "F21_n > 0")
    assert code == 2 and "F21_n is a profile over crank_angle" in one_line(err)
    code, out, _ = run_cli(capsys, "query", atlas, "--where", "F21_n > 0", "--at",
                           "crank_angle=90deg", "--columns", "F21_n")
    assert code == 0 and "matching points" in out


# ---------------------------------------------------------------- specs

SPECS = [
    ("deep", "a = " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
    ("long name", 'mechanism = "' + "x" * 100_000 + '"\n[grid]\nR = [0.3]\n', "characters"),
    ("chart x = y", SMALL + '[chart]\nx = "R"\ny = "R"\ncolor = "impact_speed"\n',
     "also the x axis"),
    ("chart at on x", SMALL + '[chart]\nx = "R"\ny = "largest_link"\ncolor = "gamma"\n'
                              'at = {R = 0.2}\n', "the chart's x axis"),
    ("chart x an output", SMALL + '[chart]\nx = "gamma"\ny = "R"\ncolor = "impact_speed"\n',
     "chart"),
]


@pytest.mark.parametrize("name, text, words", SPECS, ids=[s[0] for s in SPECS])
def test_a_bad_spec_is_one_short_line_before_any_compute(tmp_path, capsys, name, text, words):
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    code, _, err = run_cli(capsys, "run", spec, "-o", tmp_path / "bad.nc")
    line = one_line(err)
    assert code == 2 and words in line and len(line) < 400, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_a_chart_of_the_status_is_accepted_in_a_spec_as_on_the_command_line(tmp_path,
                                                                            capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(SMALL + '[chart]\nx = "R"\ny = "largest_link"\ncolor = "status"\n')
    code, _, err = run_cli(capsys, "run", spec, "-o", tmp_path / "s.nc")
    assert code == 0 and (tmp_path / "s.png").is_file(), err


def test_a_fifo_or_a_device_as_the_spec_is_refused_without_reading(tmp_path, capsys):
    fifo = tmp_path / "f.toml"
    os.mkfifo(fifo)
    for path in (fifo, "/dev/zero"):
        code, _, err = run_cli(capsys, "run", path, "-o", tmp_path / "f.nc")
        assert code == 2 and "not a regular file" in one_line(err)


@pytest.mark.parametrize("value, traceback", [("0", False), ("", False), ("no", False),
                                              ("1", True), ("yes", True)])
def test_sweep_debug_shows_a_traceback_only_when_set_on(value, traceback):
    from sweep.cli import debugging

    os.environ["SWEEP_DEBUG"] = value
    try:
        assert debugging() is traceback
    finally:
        del os.environ["SWEEP_DEBUG"]
