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


#: the Python API's words for what the command line names otherwise: an argument's name at
#: the start of a message, and a keyword's value inside it
_TO_COMMAND_LINE = (
    (re.compile(r"^path:"), "output:"),
    (re.compile(r"^variables:"), "vars:"),
    (re.compile(r"^maximize:"), "--max:"),
    (re.compile(r"\bmaximize=NAME\b"), "--max NAME"),
    (re.compile(r"\bminimize=NAME\b"), "--min NAME"),
    (re.compile(r"\bpass force=True\b"), "use --force"),
    (re.compile(r"\bpass resume=True\b"), "use --resume"),
    (re.compile(r"\bforce=True\b"), "--force"),
    (re.compile(r"\bresume=True\b"), "--resume"),
)


def for_command_line(message: str) -> str:
    """A message written in the Python API's words (``path:``, ``pass force=True``) in
    the command line's (``output:``, ``use --force``): one set of messages, two doors."""
    for pattern, words in _TO_COMMAND_LINE:
        message = pattern.sub(words, message)
    return message
