"""Nothing is lost: SIGKILL and resume, a dask.distributed cluster with a worker killed
mid-run, bit-identical atlases (issue: scale out and lose nothing)."""

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import xarray as xr

from sweep import runner, spec
from sweep.store import partial_dir
from tests.conftest import interrupted_after

SLOW = '''
mechanism = "linkage_forces"
[grid]
omega1 = {start = 5.0, stop = 40.0, num = 60}
tilt = {start = 0.0, stop = 1.5, num = 100}
[method]
quadrature_points = 200
peak_samples = 1441
'''


def reference_atlas(tmp_path, text, chunk):
    path = tmp_path / "reference.nc"
    runner.run_sweep(spec.parse(text), path, chunk=chunk, progress=False, workers=2,
                    history="reference")
    return xr.open_dataset(path)


def same(a, b):
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name


@pytest.mark.slow
def test_sigkill_then_resume_gives_the_same_atlas_and_reuses_finished_blocks(tmp_path):
    spec_file = tmp_path / "slow.toml"
    spec_file.write_text(SLOW)
    target = tmp_path / "slow.nc"
    store = partial_dir(target)
    cmd = [sys.executable, "-m", "sweep", "run", str(spec_file), "-o", str(target), "-q",
           "--chunk", "100", "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:
        if store.exists() and len(list(store.glob("*.npy"))) >= 8:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run finished before it could be killed"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not target.exists()
    before = {p.name: p.stat().st_mtime_ns for p in store.glob("*.npy")}
    assert len(before) >= 8
    loud = [c for c in cmd if c != "-q"]  # the summary says how many blocks were reused
    again = subprocess.run(loud + ["--resume"], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert f"resumed: {len(before)} of 60 blocks were already done" in again.stdout
    assert not store.exists()
    same(xr.open_dataset(target), reference_atlas(tmp_path, SLOW, 100))
    # a spec change is refused: rerun, kill, resume with another spec
    proc = subprocess.Popen([c if c != str(target) else str(tmp_path / "b.nc") for c in cmd],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    store_b = partial_dir(tmp_path / "b.nc")
    while time.time() < deadline and proc.poll() is None and not list(store_b.glob("*.npy")):
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    spec_file.write_text(SLOW.replace("num = 60", "num = 61"))
    refused = subprocess.run(cmd[:-4] + ["-o", str(tmp_path / "b.nc"), "--resume", "-q"],
                             capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "different spec" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_resumed_blocks_are_not_recomputed(tmp_path):
    """In-process view of the same property: the kernel runs only for missing blocks."""
    from sweep import engine

    s = spec.parse(SLOW.replace("num = 100", "num = 10"))
    target = tmp_path / "r.nc"
    runner.run_sweep(s, target, chunk=100, progress=False, workers=1)
    total = len(list(engine.Plan(s.with_run(chunk=100)).locations()))
    store = partial_dir(target)
    # recreate an interrupted state from the finished atlas' blocks: run again, stop early
    with interrupted_after(3):
        runner.run_sweep(s, tmp_path / "r2.nc", chunk=100, progress=False, workers=2)
    stored = len(list(partial_dir(tmp_path / "r2.nc").glob("*.npy")))
    assert stored == 3  # every block that finished was kept, though another failed
    real, calls = engine.run_block, []
    try:
        engine.run_block = lambda sweep, location: (calls.append(location),
                                                     real(sweep, location))[1]
        result = runner.run_sweep(s, tmp_path / "r2.nc", chunk=100, progress=False, workers=1,
                                 resume=True)
    finally:
        engine.run_block = real
    assert result["reused"] == 3 and len(calls) == total - 3
    assert not store.exists()
    same(xr.open_dataset(tmp_path / "r2.nc"), xr.open_dataset(target))


@pytest.mark.slow
def test_distributed_cluster_with_a_worker_killed_gives_the_same_atlas(tmp_path):
    distributed = pytest.importorskip("distributed")
    text = SLOW  # 6000 points in 100 blocks: long enough to kill a worker partway
    reference = reference_atlas(tmp_path, text, 60)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=50) as cluster:
        with distributed.Client(cluster) as client:
            pids = list(client.run(os.getpid).values())
        target = tmp_path / "cluster.nc"
        store = partial_dir(target)
        killed = []

        def kill_one_worker():
            end = time.time() + 120
            while time.time() < end:
                if store.exists() and len(list(store.glob("*.npy"))) >= 3:
                    os.kill(pids[0], signal.SIGKILL)
                    killed.append(pids[0])
                    return
                time.sleep(0.02)

        killer = threading.Thread(target=kill_one_worker)
        killer.start()
        runner.run_sweep(spec.parse(text), target, chunk=60, progress=False,
                        scheduler=cluster.scheduler_address, history="cluster")
        killer.join()
    assert killed, "no worker was killed: the run was too fast to test the retry"
    same(xr.open_dataset(target), reference)


@pytest.mark.slow
def test_unreachable_scheduler_is_a_one_line_error(tmp_path, capsys):
    from sweep.cli import main

    spec_file = tmp_path / "s.toml"
    spec_file.write_text('mechanism = "crank_rocker"\n[grid]\nlargest_link = [3.0]\n')
    with pytest.raises(SystemExit) as e:
        main(["run", str(spec_file), "-o", str(tmp_path / "s.nc"), "-q",
              "--scheduler", "tcp://127.0.0.1:9"])
    err = capsys.readouterr().err.strip().splitlines()
    assert e.value.code == 2 and len(err) == 1 and "scheduler" in err[0]
    assert not (tmp_path / "s.nc").exists()
