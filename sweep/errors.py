"""User-facing errors: one line, naming the field and what is allowed (exit status 2)."""

import re

#: a word longer than this in a message (a name or value the user gave) is shortened
LONGEST_WORD = 80
_LONG_WORD = re.compile(r"\S{%d,}" % (LONGEST_WORD + 1))


def _shortened(match: re.Match) -> str:
    word = match.group(0)
    return f"{word[:48]}…({len(word):,} characters)…{word[-12:]}"


class UserError(ValueError):
    """Bad user input: a spec file, a CLI argument, an atlas query or a Python call. The
    message is one line: line breaks become spaces, and a word the user gave that is longer
    than LONGEST_WORD characters is shown by its ends and its length."""

    def __init__(self, message: str):
        text = " ".join(str(message).split())
        super().__init__(_LONG_WORD.sub(_shortened, text))
