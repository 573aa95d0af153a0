"""The documentation: it builds strictly (a broken link, a missing page or a benchmark figure
whose results are gone fails), the tutorial's and the README's code runs as written, and the
README stays a front door (issue 35)."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tests.command_line import run_sweep

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
BLOCK = re.compile(r"^```(python|bash|toml)\n(.*?)^```", re.MULTILINE | re.DOTALL)
FILE = re.compile(r"^# file: (\S+)\n")


def code_blocks(path: Path) -> list[tuple[str, str]]:
    """The ```python and ```bash blocks of a Markdown file, in order, and the ```toml
    blocks that begin with ``# file: NAME`` (written as that file where they stand)."""
    return [(kind, body) for kind, body in BLOCK.findall(path.read_text(encoding="utf-8"))
            if kind != "toml" or FILE.match(body)]


def run_blocks(blocks, where: Path, no_overwrite: bool = False) -> None:
    """Python blocks in one namespace, bash blocks line by line (continuations joined),
    all in ``where``; the first failure fails the test with the block that failed. With
    ``no_overwrite``, a block that writes over a file an earlier one wrote fails too."""
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
               MPLBACKEND="Agg")
    namespace: dict = {}
    cwd = os.getcwd()
    os.chdir(where)
    try:
        for kind, body in blocks:
            before = {p.name: p.stat().st_mtime_ns for p in where.iterdir()}
            _run_block(kind, body, where, env, namespace)
            if no_overwrite:
                again = [p.name for p in where.iterdir()
                         if p.name in before and p.stat().st_mtime_ns != before[p.name]]
                assert not again, f"{again} written again by:\n{body}"
    finally:
        os.chdir(cwd)


def _run_block(kind, body, where, env, namespace) -> None:
    """One block: a ``# file:`` TOML block written, Python executed in ``namespace``, bash
    line by line."""
    if kind == "toml":
        (where / FILE.match(body).group(1)).write_text(body, encoding="utf-8")
        return
    if kind == "python":
        exec(compile(body, "<doc block>", "exec"), namespace)  # noqa: S102
        return
    for line in body.replace("\\\n", " ").splitlines():
        line = line.split("  #")[0].strip()
        if not line or line.startswith("#"):
            continue
        words = shlex.split(line)
        if words[0] == "sweep" and not SHELL.search(QUOTED.sub("", line)):
            code, _, stderr = run_sweep(words[1:])
            assert code == 0, f"{line}\n{stderr}"
            continue
        done = subprocess.run(line, shell=True, cwd=where, env=env, capture_output=True,
                              text=True)
        assert done.returncode == 0, f"{line}\n{done.stderr}"


#: what makes a line the shell's to run, outside quotes: a pipe, a redirection, a sequence,
#: a subshell, an expansion or a glob
SHELL = re.compile(r"[|&;<>()$`*?~\[]")
QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"")


def test_the_documentation_builds_strictly(tmp_path):
    done = subprocess.run([str(BIN / "mkdocs"), "build", "--strict", "--site-dir",
                           str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    performance = (tmp_path / "site" / "performance" / "index.html").read_text()
    assert "{{" not in performance and "points/s" in performance
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    for name in ("run", "query", "chart", "boundaries", "open_atlas", "from_toml"):
        assert f"{name}" in api


def test_a_figure_whose_results_are_gone_stops_the_build():
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import hooks
    finally:
        sys.path.pop(0)
    from mkdocs.exceptions import PluginError

    text = "{{ bench: step.json | results/C SIMD/ns_per_design_step | .0f }} ns"
    assert hooks.render(text).endswith(" ns") and "{{" not in hooks.render(text)
    for broken in ("{{ bench: step.json | results/no such row/ns | .0f }}",
                   "{{ bench: nothing.json | a | g }}", "{{ measured: nothing.json }}"):
        with pytest.raises(PluginError):
            hooks.render(broken)


def test_the_tutorial_runs_as_written(tmp_path):
    blocks = code_blocks(ROOT / "docs" / "tutorial.md")
    assert [k for k, _ in blocks].count("python") >= 4 and any(k == "bash" for k, _ in blocks)
    run_blocks(blocks, tmp_path)
    assert (tmp_path / "transfer.png").is_file() and (tmp_path / "cr_chart.png").is_file()


def test_the_readme_is_a_front_door():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 200
    text = "\n".join(lines)
    for must in ("./tasks demo", "./tasks test", "import sweep", "sweep run", "docs/"):
        assert must in text
    # every file the README links to exists
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http"):
            assert (ROOT / target).exists(), target


#: the walk-throughs a reader follows, in the order the manual gives them: the README's
#: tour, the tutorial, then the guides in the navigation's order
WALK_THROUGHS = ["README.md", "docs/tutorial.md", "docs/guide/cli.md", "docs/guide/specs.md",
                 "docs/guide/boundaries.md", "docs/guide/deciding.md", "docs/guide/reading.md",
                 "docs/guide/robust.md", "docs/guide/papers_figures.md",
                 *(f"docs/guide/{m}.md" for m in ("crank_rocker", "linkage_forces", "six_link",
                                                   "spring_balancer", "rotary_pendulum",
                                                   "impact_machine"))]


@pytest.mark.slow
def test_the_walk_throughs_run_in_sequence_in_one_folder(tmp_path):
    """The README's tour, the tutorial and every guide's examples, run as written one after
    another in one empty folder: no command needs --force and none writes over a file an
    earlier one wrote (a name used twice would fail with "exists"), and the decision guide
    runs end to end (the limits atlas, the chained forces, the front and its chart, the
    picked design's chained sweep and profile, the claim's query)."""
    blocks = [b for path in WALK_THROUGHS for b in code_blocks(ROOT / path)
              if "./tasks" not in b[1]]
    assert not any("--force" in body for kind, body in blocks if kind == "bash")
    assert [k for k, _ in code_blocks(ROOT / "docs/guide/deciding.md")].count("toml") == 2
    run_blocks(blocks, tmp_path, no_overwrite=True)
    for name in ("speed.png", "rp.bounds.nc", "transfer.png", "cr_chart.png", "breaker.nc",
                 "breaker_forces.nc", "breaker_front.nc", "breaker_front.png",
                 "breaker_pick.nc", "breaker_pick.png", "limits.html", "pick.html",
                 "breaker.html", "breaker_sheet.html", "breaker_sheet.pdf",
                 "breaker_pick_sheet.html", "breaker_explorer.html", "rock_band_robust.png",
                 "rock_band_front.nc", "breaker_tolerance.png", "breaker_sensitivity.png",
                 "paper_cr_fig2.png", "paper_guim.png", "paper_six_fig4.png",
                 "paper_six_fig6.png", "six_claim.png", "six_link_forces_profile.png",
                 "paper_rp_fig3.png"):
        assert (tmp_path / name).is_file(), name
