"""Packaging: what the sdist holds (and not: figures, virtual environments,
builds, what the README's examples write at the root), the cached wheel build
surviving a new isolated build environment, the declared dependencies, the
pytest warnings policy, text files opened as UTF-8, and the README's g++
command for C++ users of the installed package.

The tests that read the source tree (pyproject.toml, README.md, CMakeLists.txt)
skip when the tests run from elsewhere than a source checkout."""

from __future__ import annotations

import ast
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tarfile
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import nvib

import _build_tools
import _readme

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
PYPROJECT = ROOT / "pyproject.toml"
PACKAGE = Path(nvib.__file__).resolve().parent


def _source_checkout() -> Path:
    if not (PYPROJECT.is_file() and (ROOT / "CMakeLists.txt").is_file() and (ROOT / "cpp" / "include").is_dir()):
        pytest.skip(f"{ROOT} is not a source checkout of nvib (no pyproject.toml, CMakeLists.txt, cpp/include)")
    return ROOT


def _pyproject() -> dict:
    _source_checkout()
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib
    with open(PYPROJECT, "rb") as fh:
        return tomllib.load(fh)


# ---- sdist -------------------------------------------------------------------------

_SKIPPED_IN_COPY = shutil.ignore_patterns(".git", "build", "_skbuild", "dist", ".venv*", "venv*", ".ci-venv",
                                          "__pycache__", ".pytest_cache", ".hypothesis", "*.so", "*.pyd")
_VENV_PARTS = {".venv", ".ci-venv", "venv", ".tox", ".nox"}


def test_sdist_holds_sources_tests_and_licence_but_no_figures_venvs_builds_or_example_outputs(tmp_path, monkeypatch):
    root = _source_checkout()
    try:
        from scikit_build_core.build import build_sdist
    except ImportError:
        pytest.fail("scikit-build-core not importable: install the test extras (pip install .[test])")
    # The tree as it is, plus what a developer's checkout typically also holds:
    # virtual environments (under names .gitignore does not list too) and build folders.
    src = tmp_path / "src"
    shutil.copytree(root, src, ignore=_SKIPPED_IN_COPY)
    # And what the README's examples write when run from the root: building.png, nvib paper's figures/, ...
    outputs = sorted(o + "summary.md" if o.endswith("/") else o
                     for o in _readme.outputs((root / "README.md").read_text(encoding="utf-8")))
    assert "building.png" in outputs
    for decoy in (".venv/pyvenv.cfg", ".venv-py39/pyvenv.cfg", ".ci-venv/lib/site.py", "venv/pyvenv.cfg",
                  "build/cp311-cp311-linux_x86_64/CMakeCache.txt", "python/nvib/_core.cpython-311-x86_64-linux-gnu.so",
                  *outputs):
        (src / decoy).parent.mkdir(parents=True, exist_ok=True)
        (src / decoy).write_text("decoy\n", encoding="utf-8")
    monkeypatch.chdir(src)
    name = build_sdist(str(tmp_path / "dist"))
    sdist = tmp_path / "dist" / name

    with tarfile.open(sdist) as tar:
        members = [m.name for m in tar.getmembers() if m.isfile()]
    prefix = members[0].split("/", 1)[0] + "/"
    assert all(m.startswith(prefix) for m in members)
    files = {m[len(prefix):] for m in members}

    for required in ("CMakeLists.txt", "pyproject.toml", "README.md", "LICENSE", "PKG-INFO",
                     "cmake/nvibConfig.cmake.in", "cpp/include/nvib/nvib.hpp", "python/src/module.cpp",
                     "python/nvib/__init__.py", "python/nvib/_core.pyi", "python/nvib/py.typed",
                     "tests/python/test_packaging.py", "tests/hard/test_hard_cases.py",
                     "tests/cmake_consumer/CMakeLists.txt"):
        assert required in files, required
    for tree in ("cpp/include", "cmake", "python/src", "python/nvib/scenes"):
        expected = {p.relative_to(root).as_posix() for p in (root / tree).rglob("*")
                    if p.is_file() and "__pycache__" not in p.parts}
        assert expected and expected <= files, sorted(expected - files)

    pngs = sorted(f for f in files if f.startswith("benchmarks/results/") and f.lower().endswith(".png"))
    assert not pngs, pngs
    venvs = sorted(f for f in files if f.endswith("pyvenv.cfg") or _VENV_PARTS & set(f.split("/"))
                   or f.split("/")[0].startswith((".venv", "venv")))
    assert not venvs, venvs
    builds = sorted(f for f in files if f.split("/")[0] in ("build", "_skbuild", "dist")
                    or f.endswith((".so", ".pyd", ".o")) or "__pycache__" in f.split("/"))
    assert not builds, builds
    written = sorted(set(outputs) & files)
    assert not written, written
    size = sdist.stat().st_size
    assert size < 2 * 1024 * 1024, f"sdist is {size / 1e6:.2f} MB"


# ---- a cached wheel build survives a new isolated build environment ---------------

def _copy_fresh(src: Path, dst: Path) -> None:
    # shutil.copy, not copy2: new timestamps, as a fresh pip install of the same wheel gives
    shutil.copytree(src, dst, copy_function=shutil.copy)


def _configure(cmake: str, build: Path, env_dir: Path, generator: list[str]) -> dict:
    cmd = [cmake, "-S", str(ROOT), "-B", str(build), *generator, "-DCMAKE_BUILD_TYPE=Release",
           "-DSKBUILD=2", "-DNVIB_BUILD_PYTHON=ON", "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON",
           f"-DPython_EXECUTABLE={sys.executable}",
           f"-Dpybind11_DIR={env_dir / 'pybind11' / 'share' / 'cmake' / 'pybind11'}",
           f"-DEigen3_DIR={env_dir / 'cmeel.prefix' / 'share' / 'eigen3' / 'cmake'}"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    with open(build / "compile_commands.json", encoding="utf-8") as fh:
        entries = json.load(fh)
    module = [e for e in entries if e["file"].replace("\\", "/").endswith("python/src/module.cpp")]
    assert len(module) == 1, entries
    return module[0]


def test_wheel_build_cache_survives_a_new_build_environment(tmp_path):
    """pip builds every wheel in a new isolated environment at a random path, and
    scikit-build-core, seeing it moved, deletes CMakeCache.txt and CMakeFiles/ of
    the cached build-dir before configuring. The module is compiled again unless
    its compile command stays the same (no path into the environment) and its
    object file lives outside CMakeFiles/. Configure as a wheel build does, from
    one environment, clear as scikit-build-core does, configure from another."""
    _source_checkout()
    cmake = _build_tools.cmake()
    pybind11 = pytest.importorskip("pybind11", reason="pybind11 (a build requirement) is not installed")
    cmeel_prefix = None
    for entry in sys.path:
        cand = Path(entry or ".") / "cmeel.prefix" / "share" / "eigen3" / "cmake" / "Eigen3Config.cmake"
        if cand.is_file():
            cmeel_prefix = cand.parents[3]
            break
    if cmeel_prefix is None:
        pytest.skip("the cmeel-eigen wheel's Eigen is not installed in this environment")
    if os.name == "nt":
        pytest.skip("compile_commands.json needs the Ninja or Makefile generator and a compiler on PATH")
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []

    build = tmp_path / "build"
    commands, stamps = [], []
    for name in ("env-a", "env-b"):
        env_dir = tmp_path / name
        _copy_fresh(Path(pybind11.__file__).resolve().parent, env_dir / "pybind11")
        _copy_fresh(cmeel_prefix, env_dir / "cmeel.prefix")
        if commands:  # what scikit-build-core does when the environment has moved
            (build / "CMakeCache.txt").unlink()
            shutil.rmtree(build / "CMakeFiles")
        entry = _configure(cmake, build, env_dir, generator)
        shutil.rmtree(env_dir)  # pip removes the environment after the build
        commands.append(entry)
        stamps.append({p: p.stat().st_mtime_ns for p in (build / "stable-include").rglob("*") if p.is_file()})
        for env in ("env-a", "env-b"):
            assert str(tmp_path / env) not in entry["command"], entry["command"]

    assert commands[0]["command"] == commands[1]["command"]
    assert stamps[0] and stamps[0] == stamps[1], "the copied headers were rewritten"
    words = shlex.split(commands[0]["command"])
    obj = commands[0].get("output") or words[words.index("-o") + 1]
    obj = Path(commands[0]["directory"], obj).resolve()
    assert (build / "CMakeFiles").resolve() not in obj.parents, obj


# ---- dependencies ----------------------------------------------------------------

def test_tomli_is_required_below_python_311_only():
    from packaging.markers import default_environment
    from packaging.requirements import Requirement

    deps = [Requirement(d) for d in _pyproject()["project"]["dependencies"]]
    tomli = [r for r in deps if r.name == "tomli"]
    assert len(tomli) == 1 and tomli[0].marker is not None, deps
    for version, needed in (("3.9", True), ("3.10", True), ("3.11", False), ("3.12", False), ("3.13", False)):
        env = dict(default_environment(), python_version=version, python_full_version=version + ".0")
        assert tomli[0].marker.evaluate(env) is needed, (version, str(tomli[0].marker))
    # _scenes reads scene files as tomllib does, load() of a binary file: tomli 1.1.0 and later
    assert not tomli[0].specifier.contains("1.0.4") and tomli[0].specifier.contains("1.1.0"), str(tomli[0])


# ---- warnings policy -------------------------------------------------------------

_PROBE = '''
import warnings


def _warn_from(module, category):
    # a warning attributed to `module`, as warnings.warn inside that module gives
    exec(compile(f"import warnings\\nwarnings.warn('probe', {category.__name__})", f"<{module}>", "exec"),
         {"__name__": module})


def test_third_party_deprecation():
    _warn_from("matplotlib._probe", DeprecationWarning)


def test_third_party_pending_deprecation():
    _warn_from("pyparsing.core", PendingDeprecationWarning)


def test_third_party_future_warning():
    _warn_from("scipy._probe", FutureWarning)


def test_third_party_user_warning():
    _warn_from("matplotlib._probe", UserWarning)


def test_nvib_deprecation():
    _warn_from("nvib._probe", DeprecationWarning)


def test_nvib_future_warning():
    _warn_from("nvib.cli.run", FutureWarning)


def test_nvib_runtime_warning():
    _warn_from("nvib._solve", RuntimeWarning)


def test_deprecation_in_a_test():
    warnings.warn("probe", DeprecationWarning)


def test_no_warning():
    pass
'''

_EXPECTED = {
    "test_third_party_deprecation": "passed",
    "test_third_party_pending_deprecation": "passed",
    "test_third_party_future_warning": "passed",
    "test_third_party_user_warning": "failed",
    "test_nvib_deprecation": "failed",
    "test_nvib_future_warning": "failed",
    "test_nvib_runtime_warning": "failed",
    "test_deprecation_in_a_test": "failed",
    "test_no_warning": "passed",
}


def test_warnings_fail_in_nvib_but_not_third_party_deprecations(tmp_path):
    """pytest with the project's own configuration on generated tests: deprecations
    raised inside third-party packages pass, anything attributed to nvib or to a
    test fails, and other warnings fail wherever they come from."""
    _source_checkout()
    probe = tmp_path / "test_probe.py"
    probe.write_text(_PROBE, encoding="utf-8")
    report = tmp_path / "report.xml"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    out = subprocess.run([sys.executable, "-m", "pytest", "-c", str(PYPROJECT), "--rootdir", str(tmp_path),
                          "-p", "no:cacheprovider", "-q", f"--junitxml={report}", str(probe)],
                         cwd=tmp_path, capture_output=True, text=True, env=env)
    assert report.is_file(), out.stdout + out.stderr
    outcome = {}
    for case in ET.parse(report).getroot().iter("testcase"):
        failed = case.find("failure") is not None or case.find("error") is not None
        outcome[case.get("name")] = "failed" if failed else "passed"
    assert outcome == _EXPECTED, out.stdout


# ---- text files are UTF-8 ----------------------------------------------------------

_BINARY_DEFAULT = {"gzip", "bz2", "lzma"}  # their open() is binary unless the mode says "t"
_NOT_TEXT = {"os", "tarfile", "zipfile", "webbrowser", "shelve", "dbm", "wave", "sunau", "Image"}
_NUMPY_TEXT = {"savetxt", "loadtxt", "genfromtxt"}


def _constant(node):
    return node.value if isinstance(node, ast.Constant) else None


def _unencoded_text_io(source: str, filename: str = "<source>") -> list[str]:
    """Calls in `source` that read or write text without an explicit encoding:
    open()/io.open()/Path.open() in a text mode, Path.read_text()/write_text(),
    numpy's savetxt/loadtxt/genfromtxt."""
    problems = []
    for node in ast.walk(ast.parse(source, filename)):
        if not isinstance(node, ast.Call):
            continue
        keywords = {k.arg for k in node.keywords}
        func = node.func
        name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else None
        owner = func.value.id if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) else None
        where = f"{filename}:{node.lineno}: {ast.unparse(node)}"
        if name == "open" and owner not in _NOT_TEXT:
            method = isinstance(func, ast.Attribute) and owner not in {"io", "codecs"} | _BINARY_DEFAULT
            mode_pos, encoding_pos = (0, 2) if method else (1, 3)  # Path.open(mode, buffering, encoding)
            mode = node.args[mode_pos] if len(node.args) > mode_pos else next(
                (k.value for k in node.keywords if k.arg == "mode"), None)
            mode = "rb" if mode is None and owner in _BINARY_DEFAULT else "r" if mode is None else _constant(mode)
            text = not (isinstance(mode, str) and "b" in mode) and not (
                owner in _BINARY_DEFAULT and isinstance(mode, str) and "t" not in mode)
            if text and "encoding" not in keywords and len(node.args) <= encoding_pos:
                problems.append(where)
        elif name == "read_text" and "encoding" not in keywords and not node.args:
            problems.append(where)
        elif name == "write_text" and "encoding" not in keywords and len(node.args) < 2:
            problems.append(where)
        elif name in _NUMPY_TEXT and owner in ("np", "numpy") and "encoding" not in keywords:
            problems.append(where)
    return problems


@pytest.mark.parametrize("snippet, flagged", [
    ('open(p, "w")', True),
    ("open(p)", True),
    ('open(p, mode="r")', True),
    ("open(p, mode)", True),
    ('io.open(p, "a")', True),
    ('Path(p).open("w")', True),
    ("p.read_text()", True),
    ('p.write_text("η")', True),
    ("np.savetxt(p, a)", True),
    ('open(p, "w", encoding="utf-8")', False),
    ('open(p, "r", -1, "utf-8")', False),
    ('open(p, "rb")', False),
    ('open(p, mode="wb")', False),
    ('Path(p).open("rb")', False),
    ('p.read_text(encoding="utf-8")', False),
    ('p.write_text("η", "utf-8")', False),
    ("os.open(p, os.O_WRONLY)", False),
    ("gzip.open(p)", False),
    ('gzip.open(p, "wt")', True),
    ('tarfile.open(p, "w:gz")', False),
    ('np.savetxt(p, a, encoding="utf-8")', False),
])
def test_the_encoding_check_finds_what_it_should(snippet, flagged):
    assert bool(_unencoded_text_io(snippet)) is flagged


def test_nvib_opens_every_text_file_as_utf8():
    """Windows' default code page cannot write 'GαM' or 'η': every text file nvib
    reads or writes names its encoding."""
    sources = sorted(PACKAGE.rglob("*.py"))
    assert len(sources) > 20, PACKAGE
    problems = []
    for path in sources:
        problems += _unencoded_text_io(path.read_text(encoding="utf-8"), str(path.relative_to(PACKAGE.parent)))
    assert not problems, "\n".join(problems)


# ---- C++: the README's g++ command against the installed package ------------------

def _installed_headers() -> str:
    inc = nvib.include_dir()
    if not os.path.isfile(os.path.join(inc, "nvib", "nvib.hpp")):
        pytest.skip(f"nvib is not an installed package here (no C++ headers in {inc}): pip install .")
    return inc


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "nvib", *args], capture_output=True, text=True)


def test_include_dir_prints_nvibs_header_folder():
    out = _cli("--include-dir")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == nvib.include_dir()


def test_cflags_name_nvibs_and_eigens_headers():
    inc = _installed_headers()
    out = _cli("--cflags")
    assert out.returncode == 0, out.stderr
    flags = out.stdout.split()
    assert flags[0] == f"-I{inc}" and len(flags) == 2, flags
    assert flags[1].startswith("-I") and os.path.isfile(os.path.join(flags[1][2:], "Eigen", "Dense")), flags


def _readme_gxx_command() -> str:
    readme = _source_checkout() / "README.md"
    text = readme.read_text(encoding="utf-8")
    cpp = text[text.index("\n## C++"):]
    cpp = cpp[:cpp.find("\n## ", 1)] if "\n## " in cpp[1:] else cpp
    lines = [ln.strip() for block in re.findall(r"```bash\n(.*?)```", cpp, re.S) for ln in block.splitlines()
             if ln.strip().startswith("g++ ")]
    assert len(lines) == 1, "README.md's C++ section should give one g++ command"
    return lines[0]


def test_readme_gxx_command_builds_a_program_against_the_installed_package(tmp_path):
    _installed_headers()
    command = _readme_gxx_command()
    bash, gxx = shutil.which("bash"), shutil.which("g++")
    if bash is None or gxx is None or os.name == "nt":
        pytest.skip("the README's g++ command needs g++ and a POSIX shell (bash)")
    source = re.search(r"(\S+\.cpp)\b", command)
    assert source, command
    shutil.copy(ROOT / "tests" / "cmake_consumer" / "main.cpp", tmp_path / source.group(1))
    # `nvib` in the command is this interpreter's nvib, whatever else is on PATH
    script = f'nvib() {{ "{sys.executable}" -m nvib "$@"; }}\nset -e\n{command}\n'
    bld = subprocess.run([bash, "-c", script], cwd=tmp_path, capture_output=True, text=True)
    assert bld.returncode == 0, command + "\n" + bld.stdout + bld.stderr
    exe = re.search(r"-o\s+(\S+)", command)
    assert exe, command
    run = subprocess.run([str(tmp_path / exe.group(1))], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "nvib consumer: steps 1000" in run.stdout
