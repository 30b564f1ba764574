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


def nvib_subprocess(*argv, cwd=None, timeout: float = 120):
    """``python -m nvib argv`` in a subprocess that finds this nvib (source layout or installed)."""
    import os
    import subprocess
    import sys

    import nvib

    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.abspath(nvib.__file__)))
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return subprocess.run([sys.executable, "-m", "nvib", *map(str, argv)], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=timeout)
