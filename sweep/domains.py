"""What values a parameter or method key allows, in words, and the check of one value
against it: the one place both are written (spec validation, chained sweeps, ``sweep
parameters`` and ``sweep info`` read them)."""

from __future__ import annotations

import math

from kernels.declaration import Quantity


def domain_text(q: Quantity) -> str:
    """What values a quantity allows, in words: 'one of "a", "b"', 'a number > 0' ..."""
    if q.choices is not None:
        return "one of " + ", ".join(_literal(c) for c in q.choices)
    kind = "a whole number" if q.integer else "a number"
    lo, hi = q.minimum, q.maximum
    if math.isinf(lo) and math.isinf(hi):
        text = ("any finite non-zero number" if q.nonzero else "any finite number")
        if q.integer:
            text = text.replace("number", "whole number")
    else:
        if math.isinf(hi):
            text = f"{kind} {'>=' if q.min_inclusive else '>'} {lo:g}"
        elif math.isinf(lo):
            text = f"{kind} {'<=' if q.max_inclusive else '<'} {hi:g}"
        else:
            text = (f"{kind} in {'[' if q.min_inclusive else '('}{lo:g}, {hi:g}"
                    f"{']' if q.max_inclusive else ')'}")
        if q.nonzero:
            text += ", not 0"
    if q.aliases:
        text = " or ".join(_literal(a) for a in q.aliases) + " or " + text
    return text


def _literal(value) -> str:
    return f'"{value}"' if isinstance(value, str) else repr(value)


def check_value(q: Quantity, value) -> str | None:
    """None if ``value`` is allowed for ``q``, else what is allowed."""
    if q.choices is not None:
        ok = any(value == c and type(value) is type(c) for c in q.choices)
        return None if ok else domain_text(q)
    if q.aliases and isinstance(value, str) and value in q.aliases:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return domain_text(q)
    if q.integer and not isinstance(value, int):
        return domain_text(q)
    v = float(value)
    if (not math.isfinite(v) or v < q.minimum or (v == q.minimum and not q.min_inclusive)
            or v > q.maximum or (v == q.maximum and not q.max_inclusive)
            or (q.nonzero and v == 0.0)):
        return domain_text(q)
    return None
