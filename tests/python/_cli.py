"""Running the nvib command line inside the test process."""

from __future__ import annotations

from nvib import cli


def run_cli(capsys, *argv):
    """(exit status, stdout, stderr) of ``nvib argv`` run in this process."""
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as exc:  # argparse: --help, --version, usage errors
        code = exc.code
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return code, out, err
