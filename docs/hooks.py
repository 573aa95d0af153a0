"""MkDocs hook: the numbers a page quotes from a benchmark, read from its results file at
build time instead of typed by hand.

A page writes ``{{ bench: FILE | KEY/PATH | FORMAT }}``: FILE a JSON file in
benchmarks/results/, KEY/PATH the keys (or list indices) down to the value, separated by
"/", FORMAT a Python format spec (``,.0f``, ``.2f``, ``.3g``; empty: the value as it is).
``{{ measured: FILE }}`` gives the day the file was last committed. A token whose file or
key does not exist stops the build (``mkdocs build --strict`` runs in the tests), so a
renamed benchmark cannot leave a stale figure behind. ``{{ pendulum_systems }}`` is the
table of pendulum systems (kernels/pendulum/table.py), as the kernels declare it.
"""

from __future__ import annotations

import json
import re
import subprocess
from functools import lru_cache
from pathlib import Path

from mkdocs.exceptions import PluginError

RESULTS = Path(__file__).resolve().parent.parent / "benchmarks" / "results"
TOKEN = re.compile(r"\{\{\s*(bench|measured):\s*([^}|]+?)\s*(?:\|\s*([^}|]*?)\s*)?"
                   r"(?:\|\s*([^}|]*?)\s*)?\}\}")


@lru_cache(maxsize=None)
def _results(name: str):
    path = RESULTS / name
    if not path.is_file():
        raise PluginError(f"benchmark results {name!r} not found in {RESULTS}")
    return json.loads(path.read_text(encoding="utf-8"))


def value(name: str, key_path: str):
    """The value at ``key_path`` ("a/b/0/c") of a results file."""
    node = _results(name)
    for key in key_path.split("/"):
        if isinstance(node, list) and key.isdigit() and int(key) < len(node):
            node = node[int(key)]
        elif isinstance(node, dict) and key in node:
            node = node[key]
        else:
            raise PluginError(f"benchmark results {name}: no {key!r} on the way to "
                              f"{key_path!r}")
    return node


@lru_cache(maxsize=None)
def measured(name: str) -> str:
    """The day a results file was last committed (or 'not committed yet')."""
    if not (RESULTS / name).is_file():
        raise PluginError(f"benchmark results {name!r} not found in {RESULTS}")
    try:
        day = subprocess.run(["git", "-C", str(RESULTS), "log", "-1", "--format=%cs", "--",
                              name], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        day = ""
    return day.strip() or "not committed yet"


SYSTEMS_TOKEN = "{{ pendulum_systems }}"


def pendulum_systems() -> str:
    """The table of pendulum systems as a Markdown table, one row a system."""
    import sys

    root = str(Path(__file__).resolve().parent.parent)
    if root not in sys.path:
        sys.path.insert(0, root)
    from kernels.pendulum.table import PendulumSystem, SYSTEMS, entry_name

    flags = PendulumSystem._fields[2:]
    lines = ["| model | tool | " + " | ".join(flags) + " | entry point |",
             "|---" * (len(flags) + 3) + "|"]
    for s in SYSTEMS:
        marks = " | ".join("yes" if getattr(s, f) else "" for f in flags)
        lines.append(f"| {s.model} | {s.tool} | {marks} | `{entry_name(s)}` |")
    return "\n".join(lines)


def render(markdown: str) -> str:
    """Every token of a page replaced by its value."""
    def one(match):
        kind, name, key_path, spec = match.groups()
        if kind == "measured":
            return measured(name)
        if not key_path:
            raise PluginError(f"{match.group(0)}: give the key path after '|'")
        found = value(name, key_path)
        if not spec:
            return str(found)
        try:
            return format(found, spec)
        except (TypeError, ValueError) as err:
            raise PluginError(f"{match.group(0)}: {err}") from None

    if SYSTEMS_TOKEN in markdown:
        markdown = markdown.replace(SYSTEMS_TOKEN, pendulum_systems())
    return TOKEN.sub(one, markdown)


def on_page_markdown(markdown, page, config, files):  # noqa: ARG001 (MkDocs' signature)
    return render(markdown)
