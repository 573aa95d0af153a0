"""Colours that mean what they say, readable by colour-blind readers (Okabe and Ito's
palette): a category the same colour in every atlas of a mechanism; a design that meets
its requirements in blue and each failing limit in its own warm shade (never a green
beside a red); a signed quantity on a diverging map centred on 0, a one-signed one on a
sequential map; cells without a design value in greys, one per status."""

from __future__ import annotations

import numpy as np

#: Okabe and Ito's eight colours, black last (it is the boundaries' and contours' colour)
OKABE_ITO = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442",
             "#000000")
#: categories: Okabe and Ito's without black, then two more distinguishable ones
CATEGORY_COLOURS = OKABE_ITO[:7] + ("#882255", "#44AA99")
UNDETERMINED_COLOUR = "#7f7f7f"  # a flag's negative code: no category was decided
#: requirements: met in one hue, each failing limit in its own warm shade, no value grey
MET_COLOUR = "#0072B2"
FAILING_COLOURS = ("#D55E00", "#E69F00", "#CC79A7", "#882255", "#8C510A", "#F0A0A0")
NO_VALUE_COLOUR = "#BBBBBB"
#: cells without a design value, one grey per status (light to mid, never black)
BLANK_GREYS = ("0.86", "0.72", "0.58", "0.93", "0.65", "0.79")
#: sequential and diverging colour maps
SEQUENTIAL = "viridis"
DIVERGING = "RdBu_r"


def category_colour(code: int, codes) -> str:
    """A category's colour, the same in every atlas of a mechanism whatever else it holds:
    by the meaning's place among the flag's codes >= 0; a negative code (undetermined)
    grey."""
    if code < 0:
        return UNDETERMINED_COLOUR
    decided = sorted(c for c in codes if c >= 0)
    return CATEGORY_COLOURS[decided.index(code) % len(CATEGORY_COLOURS)]


def requirement_colour(meaning: str, meanings: list[str]) -> str:
    """The colour of a meaning of the ``requirements`` flag: ``met`` blue, ``no_value``
    grey, the failing limits (above_NAME, below_NAME) warm shades in their order."""
    if meaning == "met":
        return MET_COLOUR
    if meaning == "no_value":
        return NO_VALUE_COLOUR
    failing = [m for m in meanings if m not in ("met", "no_value")]
    return FAILING_COLOURS[failing.index(meaning) % len(FAILING_COLOURS)]


def flag_colours(name: str, names: dict[int, str]) -> dict[int, str]:
    """{code: colour} of every meaning of a flag variable called ``name``."""
    if name == "requirements":
        meanings = [names[c] for c in sorted(names)]
        return {c: requirement_colour(names[c], meanings) for c in names}
    return {c: category_colour(c, names) for c in names}


def signed(values: np.ndarray) -> bool:
    """Whether finite values fall on both sides of 0: a diverging map centred on 0."""
    finite = values[np.isfinite(values)]
    return bool(finite.size) and finite.min() < 0.0 < finite.max()
