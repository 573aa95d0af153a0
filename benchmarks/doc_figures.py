"""The example charts of the documentation, made again from the built-in examples.

Run:  .venv/bin/python benchmarks/doc_figures.py [FOLDER]

FOLDER holds the examples' atlases and charts as ``reference_atlases.py write FOLDER`` (or
``sweep run`` of each example) leaves them; without it they are run here, in a temporary
folder. Each example's chart (what ``sweep run`` draws from its [chart]) is copied into
docs/ under the name the pages use, and the two profile charts are drawn with the same
function as ``sweep profile``; the explorer's screenshot is the page of
``crank_rocker_limits`` in headless Chromium with the designs of at least 20 J a blow
brushed; the papers' figures and [SIX]'s claim are drawn by their pages' blocks, run as
written. The
work-precision and failure charts are made by
``benchmarks/charts.py``.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import sweep  # noqa: E402

DOCS = HERE.parent / "docs"
#: example -> the name of its chart in docs/
CHARTS = {"crank_rocker": "crank_rocker_atlas.png",
          "rotary_pendulum": "rotary_pendulum_atlas.png",
          "rotary_pendulum_blade": "blade_regime.png",
          "rotary_pendulum_stability": "rotary_pendulum_stability.png",
          "spring_balancer": "spring_balancer_atlas.png",
          "impact_machine": "impact_machine_atlas.png"}
#: (example, profile variables, the grid point, the chart's name in docs/)
PROFILES = [("linkage_forces", ["F21_n", "F34_n", "F32_n", "F14_n", "balancing_moment"],
             "omega1 == 30 and abs(tilt - 0.5235987755982988) < 1e-9",
             "linkage_forces_profile.png"),
            ("six_link", ["rocker_angle"], "abs(beta - 0.628318) < 1e-6 and abs(mu5 - 2.5) < 1e-9",
             "six_link_rocker_profile.png"),
            ("six_link_forces", ["F21_n", "F36_n", "F43_n", "F56_n", "balancing_moment"],
             "abs(beta - 0.6) < 1e-6 and abs(mu5 - 2.5) < 1e-9",
             "six_link_forces_profile.png")]


def atlas_of(example: str, folder: Path) -> Path:
    """The example's atlas in ``folder``, run there if it is not."""
    path = folder / f"{example}.nc"
    if not path.exists():
        sweep.run(sweep.example(example), path, progress=True).close()
    return path


def main(folder: Path) -> None:
    for example, name in CHARTS.items():
        atlas_of(example, folder)
        shutil.copyfile(folder / f"{example}.png", DOCS / name)
        print(f"docs/{name}: the chart of `sweep run` of {example}")
    for example, names, where, name in PROFILES:
        with sweep.open_atlas(atlas_of(example, folder)) as atlas:
            sweep.profile(atlas, names, where, path=DOCS / name, force=True)
        print(f"docs/{name}: `sweep profile` of {example} at {where}")
    explorer_screenshot(folder)
    robust_figure(folder)
    page_figures(folder, "papers_figures.md")
    page_figures(folder, "six_link.md", "## Does the two-stage")
    page_figures(folder, "rotary_pendulum.md", "## Loads: the hinge reaction")


def explorer_screenshot(folder: Path, name: str = "explorer.png") -> None:
    """The README's explorer: the limits example's page with blow energy >= 20 J brushed."""
    import time

    from tests.browser import driver, ready

    atlas = atlas_of("crank_rocker_limits", folder)
    page = sweep.explore(atlas, folder / "crank_rocker_limits.html", force=True)
    browser = driver(width=1500, height=1000)
    try:
        browser.get(page.as_uri())
        ready(browser)
        browser.execute_script(
            "const r = model('range_blow_energy'); r.value = [20, r.end];")
        time.sleep(1.0)
        browser.save_screenshot(str(DOCS / name))
    finally:
        browser.quit()
    print(f"docs/{name}: `sweep explore` of crank_rocker_limits, blow energy >= 20 J brushed")


def robust_figure(folder: Path, name: str = "robust_rock_band.png") -> None:
    """The robust design guide's chart, from its own spec (the page's first TOML block)."""
    import re

    text = (DOCS / "guide" / "robust.md").read_text()
    spec = re.search(r"```toml\n(# file: rock_band.toml.*?)```", text, re.S).group(1)
    (folder / "rock_band.toml").write_text(spec)
    atlas = sweep.run(sweep.Sweep.from_toml(folder / "rock_band.toml"),
                      folder / "rock_band.nc")
    robust = sweep.robust(atlas, "R")
    sweep.chart(robust, "largest_link", "m3", "requirements", overlay="blow_energy_min",
                path=DOCS / name, force=True)
    print(f"docs/{name}: the robust design guide's chart")


def page_figures(folder: Path, page: str, section: str | None = None) -> None:
    """The figures a guide page links (``../NAME.png``) that its own blocks draw, made by
    running those blocks as written in ``folder`` (its TOML files, then its commands) from
    the heading ``section`` on (the whole page without one), and copied into docs/."""
    import re
    import shlex
    import subprocess

    text = (DOCS / "guide" / page).read_text()
    if section is not None:
        text = text[text.index(section):]
    for kind, body in re.findall(r"```(toml|bash)\n(.*?)```", text, re.S):
        if kind == "toml":
            name = re.match(r"# file: (\S+)", body).group(1)
            (folder / name).write_text(body)
            continue
        for line in body.strip().splitlines():
            subprocess.run([str(Path(sys.executable).parent / "sweep"),
                            *shlex.split(line)[1:]], cwd=folder, check=True,
                           stdout=subprocess.DEVNULL)
    for png in sorted(set(re.findall(r"\(\.\./([a-z0-9_]+\.png)\)", text))):
        if (folder / png).exists():
            shutil.copyfile(folder / png, DOCS / png)
            print(f"docs/{png}: drawn by the blocks of {page}, as written")


if __name__ == "__main__":
    if len(sys.argv) > 1:
        main(Path(sys.argv[1]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main(Path(tmp))
