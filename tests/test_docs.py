"""The documentation: it builds strictly (a broken link, a missing page or a benchmark figure
whose results are gone fails), the tutorial's and the README's code runs as written, and the
README stays a front door (issue 35)."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
BLOCK = re.compile(r"^```(python|bash|toml)\n(.*?)^```", re.MULTILINE | re.DOTALL)
FILE = re.compile(r"^# file: (\S+)\n")


def code_blocks(path: Path) -> list[tuple[str, str]]:
    """The ```python and ```bash blocks of a Markdown file, in order, and the ```toml
    blocks that begin with ``# file: NAME`` (written as that file where they stand)."""
    return [(kind, body) for kind, body in BLOCK.findall(path.read_text(encoding="utf-8"))
            if kind != "toml" or FILE.match(body)]


def run_blocks(blocks, where: Path) -> None:
    """Python blocks in one namespace, bash blocks line by line (continuations joined),
    all in ``where``; the first failure fails the test with the block that failed."""
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
               MPLBACKEND="Agg")
    namespace: dict = {}
    cwd = os.getcwd()
    os.chdir(where)
    try:
        for kind, body in blocks:
            if kind == "toml":
                (where / FILE.match(body).group(1)).write_text(body, encoding="utf-8")
                continue
            if kind == "python":
                exec(compile(body, "<doc block>", "exec"), namespace)  # noqa: S102
                continue
            command = body.replace("\\\n", " ")
            for line in command.splitlines():
                line = line.split("  #")[0].strip()
                if not line or line.startswith("#"):
                    continue
                done = subprocess.run(line, shell=True, cwd=where, env=env,
                                      capture_output=True, text=True)
                assert done.returncode == 0, f"{line}\n{done.stderr}"
    finally:
        os.chdir(cwd)


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


@pytest.mark.slow
def test_the_readmes_tour_runs_as_written(tmp_path):
    run_blocks([b for b in code_blocks(ROOT / "README.md") if "./tasks" not in b[1]],
               tmp_path)
    assert (tmp_path / "speed.png").is_file() and (tmp_path / "rp.bounds.nc").is_file()


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


@pytest.mark.slow
def test_the_decision_guide_runs_as_written(tmp_path):
    """docs/guide/deciding.md end to end: the limits atlas, the chained forces, the front
    and its chart, the picked design's own chained sweep and profile, the claim's query."""
    blocks = code_blocks(ROOT / "docs" / "guide" / "deciding.md")
    assert [k for k, _ in blocks].count("toml") == 2
    run_blocks(blocks, tmp_path)
    for name in ("limits.nc", "forces.nc", "front.nc", "front.png", "picked.nc",
                 "picked.png"):
        assert (tmp_path / name).is_file(), name
