"""The explorer of a 10^5-point atlas: the page's size, the CPU time to write it
(``sweep explore``, a whole process) and the time to its first render in the
distribution's headless Chromium with the network off (from navigation to Bokeh's views
built and a frame drawn), in rounds. Its 99,960 designs are every design (the page shows
up to 100,000).

Run: .venv/bin/python benchmarks/bench_explorer.py [--rounds N]
     (writes benchmarks/results/explorer.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
SWEEP = str(Path(sys.executable).with_name("sweep"))

SPEC = """mechanism = "crank_rocker"
title = "Crank-rocker atlas of 99,960 designs for the explorer's benchmark"
outputs = ["lambda0", "lambda2", "lambda3", "impact_transfer_ratio", "impact_speed",
           "transmission_angle_working", "envelope", "crank_length", "omega1",
           "blow_energy", "blow_rate"]
[grid]
R = {start = 0.05, stop = 0.40, num = 40}
largest_link = {start = 1.5, stop = 8.0, num = 833, scale = "log"}
type = ["a", "b", "c"]
[fixed]
envelope = 0.6
impact_speed_limit = 10.0
rocker_inertia = 0.05
[requirements]
transmission_angle_working = ">= 20deg"
blow_energy = ">= 10"
"""


def cpu_of(command: list[str]) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def first_render(page: Path) -> float:
    """Seconds from navigation to the views built and one frame drawn after it."""
    from tests.browser import driver, errors, ready

    browser = driver()
    try:
        start = time.perf_counter()
        browser.get(page.as_uri())
        ready(browser, timeout=300)
        browser.execute_async_script(
            "const done = arguments[0]; requestAnimationFrame(() => done(true));")
        seconds = time.perf_counter() - start
        problems = errors(browser)
        assert not problems, problems
        shown = browser.execute_script("return model('designs').data['grid_point'].length")
        assert shown == 99_960, shown
        return seconds
    finally:
        browser.quit()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        (folder / "big.toml").write_text(SPEC)
        atlas = folder / "big.nc"
        subprocess.run([SWEEP, "run", str(folder / "big.toml"), "-o", str(atlas), "-q"],
                       check=True)
        write, render, size = [], [], 0
        for k in range(args.rounds):
            page = folder / f"big{k}.html"
            write.append(cpu_of([SWEEP, "explore", str(atlas), "-o", str(page)]))
            size = page.stat().st_size
            render.append(first_render(page))
            print(f"round {k}: write {write[-1]:.2f} CPU-s, first render {render[-1]:.2f} s, "
                  f"{size / 1e6:.1f} MB", flush=True)
    result = {
        "what": "sweep explore of a 99,960-point crank_rocker atlas (every design shown): "
                "page size, CPU seconds of the whole `sweep explore` process, seconds from "
                "navigation to the first frame in headless Chromium (network off)",
        "designs": 99_960, "page_bytes": size, "rounds": args.rounds,
        "write_cpu_s": write, "write_cpu_s_median": statistics.median(write),
        "first_render_s": render, "first_render_s_median": statistics.median(render),
        "machine": platform.machine(), "python": platform.python_version(),
        "date": time.strftime("%Y-%m-%d"),
    }
    out = HERE / "results" / "explorer.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
