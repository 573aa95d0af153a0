"""The command line as the tests call it: in this process, through ``sweep.cli.main``."""

import pytest

from sweep.cli import main


def run_cli(capsys, *args):
    """(exit status, standard output, standard error) of ``sweep ARGS``."""
    with pytest.raises(SystemExit) as e:
        main([str(a) for a in args])
    out = capsys.readouterr()
    return e.value.code, out.out, out.err
