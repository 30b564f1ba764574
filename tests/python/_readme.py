"""The README's examples as the tests read them: its fenced blocks, its nvib commands (with the exit
status it gives each and the output it shows), its scene file, and the files its examples write into
the working folder (tests/python/test_readme.py runs them; test_packaging.py keeps those files out of
the sdist)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
README = ROOT / "README.md"


def fenced_blocks(text: str) -> list[tuple[str, str]]:
    """(language, body) of every fenced block."""
    return re.findall(r"^```(\w*)\n(.*?)^```", text, re.S | re.M)


def shell_examples(text: str) -> list[tuple[str, int, list[str]]]:
    """(command, expected exit status, README lines of output shown after it) of every `nvib ...` example:
    the lines of the shell blocks (``$ nvib ...`` with the output shown below it in a plain block) and the
    inline `nvib run ...` commands of the prose. A trailing comment ``# exits N`` gives the status N,
    otherwise 0; optional arguments in [brackets] are left out; a template, whose first argument is a
    placeholder in capitals (``nvib paper OUTDIR``), is not run, its concrete form is; a command shown
    twice runs once."""
    out = []
    for lang, body in fenced_blocks(text):
        if lang not in ("bash", ""):
            continue
        lines = body.splitlines()
        for k, line in enumerate(lines):
            shown = []
            if line.startswith("$ nvib "):
                line = line[2:]
                shown = [x for x in lines[k + 1:] if not x.startswith("$ ")]
            if not line.startswith("nvib "):
                continue
            command, _, comment = line.partition(" #")
            status = re.search(r"exits (\d+)", comment)
            command = re.sub(r"\[[^\]]*\]", " ", command)
            argv = command.split()
            if len(argv) > 2 and re.fullmatch(r"[A-Z]+", argv[2]):
                continue
            out.append((" ".join(command.split()), int(status.group(1)) if status else 0, shown))
    for span in re.findall(r"`(nvib run [^`]+)`", text):
        out.append((span, 0, []))
    first = {}
    for command, status, shown in out:  # a command shown twice is run once
        first.setdefault(command, (command, status, shown))
    return list(first.values())


def scene_file(text: str) -> str:
    """The README's example of a scene file."""
    m = re.search(r"^A scene file \(TOML\).*?^```toml\n(.*?)^```", text, re.S | re.M)
    assert m, "README.md's scene-file example moved"
    return m.group(1)


def outputs(text: str) -> set[str]:
    """What the README's examples write into the folder they run in: the files and folders named by
    --plot, --out and --table, nvib paper's folder, nvib cost's default cost_SCENE.md and .png, and the
    figures and files the Python blocks save (a string literal ending in .png, .npz, .csv or .nc)."""
    found = set()
    for command, _, _ in shell_examples(text):
        argv = command.split()
        for k, arg in enumerate(argv[:-1]):
            if arg in ("--plot", "--out", "--table"):
                found.add(argv[k + 1])
        if argv[1] == "paper":
            found.add(argv[2].rstrip("/") + "/")
        if argv[1] == "cost" and "--plot" not in argv:
            found |= {f"cost_{argv[2]}.png", f"cost_{argv[2]}.md"}
    for lang, body in fenced_blocks(text):
        if lang == "python":
            found |= set(re.findall(r"[\"']([\w.-]+\.(?:png|npz|csv|nc))[\"']", body))
    return found
