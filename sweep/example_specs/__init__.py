"""The built-in specs (``sweep examples``): one TOML file each, by name."""

import tomllib
from importlib import resources


def names() -> list[str]:
    """The built-in specs' names, sorted."""
    return sorted(entry.name[:-len(".toml")] for entry in resources.files(__name__).iterdir()
                  if entry.name.endswith(".toml"))


def text(name: str) -> str:
    """The TOML text of a built-in spec."""
    return resources.files(__name__).joinpath(f"{name}.toml").read_text("utf-8")


def titles() -> dict[str, str]:
    """{name: title} of every built-in spec."""
    return {name: tomllib.loads(text(name)).get("title", "") for name in names()}


def mechanisms() -> dict[str, str]:
    """{name: mechanism} of every built-in spec."""
    return {name: tomllib.loads(text(name))["mechanism"] for name in names()}
