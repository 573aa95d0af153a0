"""The command line as the tests call it: in this process, through ``sweep.cli.main``."""

import contextlib
import io

import pytest

from sweep.cli import main


def run_cli(capsys, *args):
    """(exit status, standard output, standard error) of ``sweep ARGS``."""
    with pytest.raises(SystemExit) as e:
        main([str(a) for a in args])
    out = capsys.readouterr()
    return e.value.code, out.out, out.err


def run_sweep(args: list[str]) -> tuple[int, str, str]:
    """(exit status, standard output, standard error) of ``sweep ARGS`` outside a test's
    capsys (the documentation's walk-throughs): the script's own parsing, errors and exit
    status, with one interpreter's imports and loaded kernels shared by every line."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in args])
            code = 0
        except SystemExit as done:
            code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    return code, out.getvalue(), err.getvalue()
