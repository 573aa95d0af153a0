"""What a chart writes: a variable's short label with its units (``blow energy $E$ [J]``),
a value with its units (``ω1 = 60 rad/s``), and the title of what is drawn. The short label
is the one its mechanism declares (``Quantity.label``, the atlas's ``label`` attribute); the
long_name stays in the atlas, ``sweep info`` and the docs. Angles are shown in degrees
unless asked otherwise, a rotor angle of many turns in turns (a declared chart unit); the
atlas stays in radians."""

from __future__ import annotations

import re
import textwrap

import numpy as np
import xarray as xr

#: superscript digits, for units written as powers
_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def marks(ds: xr.Dataset, name: str) -> tuple:
    """The declared (value, meaning) levels an output is read against (K = 1), from the
    mechanism's declaration; () for any other variable."""
    output = declared(ds, name)
    return getattr(output, "marks", ()) if output is not None else ()


def declared(ds: xr.Dataset, name: str):
    """The declaration of an atlas variable's output (or parameter), or None (status, a
    coordinate of a chain, an atlas of an unknown mechanism)."""
    from sweep import registry

    mech = ds.attrs.get("mechanism", "")
    if mech not in registry.names():
        return None
    declaration = registry.get(mech).declaration
    for find in (declaration.output, declaration.parameter):
        try:
            return find(name)
        except KeyError:
            continue
    if declaration.profile_dim is not None and declaration.profile_dim.name == name:
        return declaration.profile_dim
    return None


def chart_units(ds: xr.Dataset, name: str) -> tuple[str, float] | None:
    """(units, factor) a chart shows a variable in instead of its own, if declared."""
    output = declared(ds, name)
    return getattr(output, "chart_units", None) if output is not None else None


def units(ds: xr.Dataset, name: str, degrees: bool) -> str:
    """The units a variable is shown in, as the atlas writes them (``m s-1``, ``deg``,
    ``turn``; ``1`` for none)."""
    own = ds[name].attrs.get("units", "") or "1"
    other = chart_units(ds, name)
    if other is not None:
        return other[0]
    if degrees and own == "rad":
        return "deg"
    return own


def pretty_units(text: str) -> str:
    """CF units as a reader writes them: ``m s-1`` -> ``m/s``, ``kg m2`` -> ``kg·m²``,
    ``rad s-2`` -> ``rad/s²``, ``min-1`` -> ``1/min``, ``deg`` -> ``°``; "" for ``1``."""
    if text in ("1", ""):
        return ""
    if text == "deg":
        return "°"
    above, below = [], []
    for token in text.split():
        match = re.fullmatch(r"([A-Za-z]+)(-?\d+)?", token)
        if match is None:
            return text
        unit, power = match.group(1), int(match.group(2) or 1)
        shown = unit + (str(abs(power)).translate(_SUPERSCRIPT) if abs(power) != 1 else "")
        (above if power > 0 else below).append(shown)
    numerator = "·".join(above) or "1"
    return numerator + ("/" + "·".join(below) if below else "")


def label(ds: xr.Dataset, name: str) -> str:
    """A variable's short label: the atlas's, else its declaration's, else its name."""
    text = ds[name].attrs.get("label") if name in ds.variables else None
    if not text:
        item = declared(ds, name)
        text = getattr(item, "label", "") if item is not None else ""
    return text or str(name).replace("_", " ")


def axis_label(ds: xr.Dataset, name: str, degrees: bool = True) -> str:
    """``blow energy $E$ [J]``: the short label and the units it is shown in (none for a
    number without units)."""
    shown = pretty_units(units(ds, name, degrees))
    return f"{label(ds, name)} [{shown}]" if shown else label(ds, name)


def shown_values(var: xr.DataArray, degrees: bool, ds: xr.Dataset | None = None
                 ) -> np.ndarray:
    """A variable's values as drawn: in its declared chart units (a rotor angle in turns),
    radians in degrees when asked."""
    values = np.asarray(var.values)
    other = chart_units(ds, str(var.name)) if ds is not None else None
    if other is not None:
        return values * other[1]
    if degrees and var.attrs.get("units") == "rad":
        return np.degrees(values)
    return values


def value_text(ds: xr.Dataset, name: str, value, degrees: bool = True,
               digits: int = 4, plain: bool = False) -> str:
    """``crank speed $\\omega_1$ = 60 rad/s``: a variable held at a value, as a title
    shows it (``plain``: ``omega1 = 60 rad/s``, as a terminal shows it)."""
    shown_name = str(name) if plain else label(ds, name)
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, (str, np.str_)):
        return f"{shown_name} = {value}"
    shown = units(ds, name, degrees)
    number = float(value)
    if shown == "deg" and ds[name].attrs.get("units") == "rad":
        number = np.degrees(number)
    other = chart_units(ds, name)
    if other is not None:
        number *= other[1]
    unit = pretty_units(shown)
    return f"{shown_name} = {number:.{digits}g}" + (
        "" if not unit else ("°" if unit == "°" else f" {unit}"))


_GREEK = {"alpha": "α", "beta": "β", "gamma": "γ", "delta": "δ", "varepsilon": "ε",
          "epsilon": "ϵ", "eta": "η", "theta": "θ", "kappa": "κ", "lambda": "λ", "mu": "μ",
          "nu": "ν", "xi": "ξ", "pi": "π", "sigma": "σ", "tau": "τ", "varphi": "φ",
          "phi": "ϕ", "psi": "ψ", "omega": "ω", "Delta": "Δ", "Omega": "Ω", "Pi": "Π",
          "Psi": "Ψ", "max": "max", "min": "min", "arg": "arg "}
_SUBSCRIPT = dict(zip("0123456789+-aehijklmnoprstuvx", "₀₁₂₃₄₅₆₇₈₉₊₋ₐₑₕᵢⱼₖₗₘₙₒₚᵣₛₜᵤᵥₓ"))
_SUPER = dict(zip("0123456789+-*", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻*"))


def plain(text: str) -> str:
    """A label's mathtext as plain Unicode, for a page that draws no TeX: ``$\\omega_1$``
    -> ``ω₁``, ``$|u_{31}|$`` -> ``|u₃₁|``, ``$\\bar\\omega_1$`` -> ``ω̄₁``; a subscript
    Unicode has no letters for stays written with ``_``."""
    def script(match, table, mark):
        body = match.group(1) if match.group(1) is not None else match.group(2)
        if all(c in table for c in body):
            return "".join(table[c] for c in body)
        return mark + body

    def math(span: str) -> str:
        span = re.sub(r"\\mathrm\{([^}]*)\}", r"{\1}", span)
        span = re.sub(r"\\bar\s*\\?([A-Za-z]+)",
                      lambda m: _GREEK.get(m.group(1), m.group(1)) + "\u0304", span)
        span = re.sub(r"\\([A-Za-z]+)\s?", lambda m: _GREEK.get(m.group(1), m.group(1)),
                      span)
        span = re.sub(r"_(?:\{([^}]*)\}|(.))", lambda m: script(m, _SUBSCRIPT, "_"), span)
        span = re.sub(r"\^(?:\{([^}]*)\}|(.))", lambda m: script(m, _SUPER, "^"), span)
        return span.replace("{", "").replace("}", "")

    return re.sub(r"\$([^$]*)\$", lambda m: math(m.group(1)), text)


def wrapped(text: str, width: int) -> str:
    """Text wrapped to lines of ``width`` characters, a mathtext span ($...$) never cut."""
    glue = "\x00"
    kept = re.sub(r"\$[^$]*\$", lambda m: m.group(0).replace(" ", glue), text)
    lines = textwrap.wrap(kept, width, break_long_words=False, break_on_hyphens=False)
    return "\n".join(line.replace(glue, " ") for line in lines)
