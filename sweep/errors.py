"""User-facing errors: one line, naming the field and what is allowed (exit status 2)."""


class UserError(ValueError):
    """Bad user input: a spec file, a CLI argument or an atlas query."""
