"""The README tells the truth: what it lists, prints and runs is checked against nvib itself; and the
repository cites no document that it does not hold.

Skips when the tests run from elsewhere than a source checkout (no README.md beside them)."""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import nvib
from nvib.analysis import cost as cost_module

from _readme import README, ROOT, fenced_blocks, outputs, scene_file, shell_examples

STATUSES = [s.name for s in nvib.Status]


def readme() -> str:
    if not README.is_file():
        pytest.skip(f"no README.md in {ROOT}: not a source checkout")
    return README.read_text(encoding="utf-8")


# ---- statuses: every list of them has all of them ------------------------------------------------

def test_the_status_enum_is_listed_whole():
    m = re.search(r"`Status` \(an enum: (.*?)\) and `Failure`", readme(), re.S)
    assert m, "README.md no longer lists the members of Status where it names the bound types"
    listed = set(re.findall(r"`(\w+)`", m.group(1)))
    assert set(STATUSES) <= listed, sorted(set(STATUSES) - listed)


def test_cost_rows_name_every_failing_status():
    m = re.search(r"^- A run that fails is a row: (.*?)(?=^- )", readme(), re.S | re.M)
    assert m, "README.md's description of cost rows moved"
    listed = set(re.findall(r"`(\w+)`", m.group(1)))
    failing = set(STATUSES) - {"success"}
    assert failing <= listed, sorted(failing - listed)
    assert all(f"'{s}'" in cost_module.__doc__ for s in STATUSES)


def test_status_text_lists_every_status():
    from nvib._labels import status_text

    assert all(f"'{status_text(s)}'" in status_text.__doc__ for s in nvib.Status)


def test_the_type_stub_lists_every_status():
    stub = Path(nvib.__file__).with_name("_core.pyi")
    if not stub.is_file():
        pytest.skip("no _core.pyi beside the package")
    tree = ast.parse(stub.read_text(encoding="utf-8"))
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Status"]
    members = {t.id: node.value.value for node in cls.body if isinstance(node, ast.Assign)
               for t in node.targets}
    assert members == {s.name: s.value for s in nvib.Status}


# ---- the command line: every example runs as the README says ---------------------------------------

def _example_ids(examples):
    return [c[5:60] for c, *_ in examples]


def user_files(folder: Path) -> None:
    """The files the README's examples read, named as it names them: the user's records (each the
    synthetic record shipped with nvib) and the scene file it shows."""
    text = readme()
    record = (Path(nvib.__file__).parent / "scenes" / "records" / "sgm1.AT2").read_bytes()
    for name in set(re.findall(r"[\w-]+\.AT2", text)):
        (folder / name).write_bytes(record)
    (folder / "two_storey.toml").write_text(scene_file(text), encoding="utf-8")


def ida_file(path: Path) -> None:
    """An IDA's CSV as nvib ida --out writes it: building_collapse under two 12-s windows of SGM-1."""
    gm = nvib.GroundMotion.from_at2(Path(nvib.__file__).parent / "scenes" / "records" / "sgm1.AT2")
    windows = [nvib.GroundMotion.from_array(gm.a[i:i + 1200], dt=gm.dt, units="g", name=f"from {i}") for i in (0, 600)]
    nvib.ida(nvib.load_scene("building_collapse"), windows, dt=0.002, check=False, progress=False).to_csv(path)


EXAMPLES = shell_examples(README.read_text(encoding="utf-8")) if README.is_file() else []


def test_the_shell_examples_are_found():
    text = readme()
    commands = [c for c, *_ in shell_examples(text)]
    assert len(commands) >= 15
    assert any(s == 1 for _, s, _ in shell_examples(text))  # the example of a failure is checked as one


@pytest.mark.parametrize("command, status, shown", EXAMPLES, ids=_example_ids(EXAMPLES))
def test_shell_example_exits_as_the_readme_says(command, status, shown, tmp_path, monkeypatch, capsys):
    from _cli import run_cli

    user_files(tmp_path)
    if command.startswith("nvib fragility ida.csv"):  # the IDA file an nvib ida --out before it wrote
        ida_file(tmp_path / "ida.csv")
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, *command.split()[1:])
    assert code == status, f"{command}: exit status {code}, the README says {status}\n{out[-2000:]}{err[-2000:]}"
    got = {" ".join(x.split()) for x in out.splitlines()}
    missing = [x for x in shown if " ".join(x.split()) not in got]
    assert not missing, f"{command} no longer prints what the README shows: {missing}\n{out}"


# ---- the demo table is what `nvib demo` prints ------------------------------------------------------

def test_the_demo_table_is_what_nvib_demo_prints(capsys):
    from _cli import run_cli

    blocks = [body for lang, body in fenced_blocks(readme()) if body.startswith("Hardening oscillator")]
    assert len(blocks) == 1, "README.md should show the output of nvib demo once"
    code, out, _ = run_cli(capsys, "demo")
    assert code == 0

    def without_timing(text):
        # The wall-time column (the last one of each scheme's row) is the machine's; the rest is compared.
        lines = text.rstrip("\n").splitlines()
        rule = next(k for k, x in enumerate(lines) if x.startswith("---"))
        return lines[:rule + 1] + [x.rsplit(None, 1)[0] for x in lines[rule + 1:]]

    assert without_timing(blocks[0]) == without_timing(out)


# ---- the scene file is a sound model, and the README says what it gives ----------------------------

def test_the_scene_file_example_is_a_sound_model(tmp_path):
    import numpy as np

    text = readme()
    path = tmp_path / "two_storey.toml"
    path.write_text(scene_file(text), encoding="utf-8")
    model = nvib.load_scene(str(path))
    # Every storey is held: no free (zero-frequency) mode that a ground motion would carry away.
    w = model.linearized_frequencies(model.u0)
    assert np.all(w > 1.0), w
    stated = re.search(r"frequencies ([\d.]+) and\s+([\d.]+) rad/s, peak displacements ([\d.]+) mm \(x1\) "
                       r"and ([\d.]+) mm \(x2\)", text)
    assert stated, "README.md no longer says what the scene file gives"
    w1, w2, p1, p2 = map(float, stated.groups())
    assert np.allclose(np.sort(w), [w1, w2], atol=0.05)
    res = nvib.solve(model, nvib.CEMDTS(), dt=model.scene["dt"], t_end=model.scene["t_end"], energy=True)
    assert res.status == nvib.Status.success and not res.warnings
    peaks = np.abs(res.u).max(axis=0) * 1e3
    assert np.allclose(peaks, [p1, p2], atol=0.05), peaks


# ---- the Python snippets run, in the order the README shows them -----------------------------------

def test_the_python_snippets_run_in_order(tmp_path, monkeypatch):
    """One session through every Python block, each seeing the names the earlier ones defined, in a
    folder with the user's files the README names; with nvib's required dependencies only (the
    optional pandas, xarray and dask cannot be imported), and the block of compiled laws, which imports
    Numba (the nvib[numba] extra), only where Numba is installed."""
    import importlib.util

    blocks = [body for lang, body in fenced_blocks(readme()) if lang == "python"]
    assert len(blocks) >= 10
    user_files(tmp_path)
    monkeypatch.chdir(tmp_path)
    for optional in ("pandas", "xarray", "dask"):
        monkeypatch.setitem(sys.modules, optional, None)
    namespace = {"__name__": "readme"}
    for k, body in enumerate(blocks, 1):
        if body.startswith("import numba") and importlib.util.find_spec("numba") is None:
            continue
        try:
            exec(compile(body, f"README.md, Python block {k}", "exec"), namespace)
        except Exception as exc:
            pytest.fail(f"README.md's Python block {k} ({body.splitlines()[0].strip()}) raises {exc!r}")


# ---- what the examples write at the root is ignored by git (and kept out of the sdist: test_packaging)

def test_what_the_examples_write_is_ignored_by_git():
    written = outputs(readme())
    assert {"building.png", "figures/"} <= written
    git = shutil.which("git")
    if git is None or subprocess.run([git, "-C", str(ROOT), "rev-parse", "--is-inside-work-tree"],
                                     capture_output=True).returncode != 0:
        pytest.skip("not a git work tree")
    paths = sorted(p + "summary.md" if p.endswith("/") else p for p in written)
    check = subprocess.run([git, "-C", str(ROOT), "check-ignore", "--no-index", "-v", "-n", *paths],
                           capture_output=True, text=True)
    unmatched = [line.split("\t", 1)[1] for line in check.stdout.splitlines() if line.startswith("::")]
    assert not unmatched, f"not in .gitignore: {unmatched}"


# ---- the repository cites only documents it holds --------------------------------------------------

def _tracked_text_files() -> list[Path]:
    git = shutil.which("git")
    if git is None:
        pytest.skip("git is not installed")
    p = subprocess.run([git, "-C", str(ROOT), "ls-files", "-z"], capture_output=True)
    if p.returncode != 0:
        pytest.skip("not a git work tree")
    suffixes = {".py", ".pyi", ".md", ".toml", ".txt", ".cpp", ".hpp", ".h", ".in", ".cmake", ".sh", ".cfg"}
    return [ROOT / f for f in p.stdout.decode().split("\0") if f and Path(f).suffix in suffixes]


def test_every_document_cited_is_in_the_repository():
    """A document cited by a capitalised name ending in .md, as README.md is, must be a file of the
    repository: a reader of the sources, the tests or the results has nothing else (the paper itself
    is cited by its reference)."""
    files = _tracked_text_files()
    held = {f.name for f in files}
    cited = {}
    for f in files:
        for name in set(re.findall(r"\b([A-Z][A-Z0-9_]*\.md)\b", f.read_text(encoding="utf-8", errors="replace"))):
            if name not in held:
                cited.setdefault(name, []).append(str(f.relative_to(ROOT)))
    assert not cited, f"cited, but not in the repository: {cited}"
