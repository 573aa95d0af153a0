"""A mechanism's declaration in words: what ``sweep parameters NAME`` prints."""

from __future__ import annotations

import textwrap

from kernels.declaration import Mechanism, Quantity, used_when_text
from sweep.spec import domain_text


def units_text(units: str) -> str:
    return "-" if units in ("", "1") else units


def _default(q: Quantity) -> str:
    if q.default is None:
        return "-"
    return f'"{q.default}"' if isinstance(q.default, str) else f"{q.default:.6g}" \
        if isinstance(q.default, float) else str(q.default)


def _quantity_rows(items) -> list[str]:
    rows = []
    width = max((len(q.name) for q in items), default=4)
    for q in items:
        meaning = q.long_name + (f"; used only with {used_when_text(q)}" if q.used_when
                                 else "")
        head = (f"  {q.name:{width}s}  [{units_text(q.units)}]  default {_default(q)};"
                f" allowed: {domain_text(q)}")
        rows.append(head)
        rows.extend(textwrap.wrap(meaning, 92, initial_indent=" " * (width + 4),
                                  subsequent_indent=" " * (width + 4)))
    return rows


def mechanism_text(mech: Mechanism) -> str:
    """Parameters, method keys, outputs and statuses of a mechanism, with units."""
    lines = [f"{mech.name}: {mech.title}",
             *textwrap.wrap(f"source: {mech.references}", 96, subsequent_indent="  "),
             "", "parameters (grid axes or [fixed] values):"]
    lines += _quantity_rows(mech.parameters)
    if mech.method:
        lines += ["", "method keys ([method]):"]
        lines += _quantity_rows(mech.method)
    width = max(len(o.name) for o in mech.outputs + mech.profiles)
    lines += ["", "outputs:"]
    for o in mech.outputs:
        kind = (" flag: " + ", ".join(o.flags)) if o.is_flag else ""
        lines.append(f"  {o.name:{width}s}  [{units_text(o.units)}]  {o.long_name}{kind}")
    if mech.profiles:
        lines += ["", f"profiles over {mech.profile_dim.name} "
                      f"[{units_text(mech.profile_dim.units)}] (set method.profile_points):"]
        for o in mech.profiles:
            lines.append(f"  {o.name:{width}s}  [{units_text(o.units)}]  {o.long_name}")
    usable = ", ".join(("ok",) + mech.usable)
    lines += [""] + textwrap.wrap(f"statuses: {', '.join(mech.status)} (those with design "
                                  f"values: {usable})", 96, subsequent_indent="  ")
    return "\n".join(lines)
