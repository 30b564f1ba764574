"""What the commands share: argument types, tables, output checks, and the
scheme options, generated from the registry (each scheme's declared
parameters, its named constructors and the Newton options of the implicit ones)."""

from __future__ import annotations

import argparse
import errno
import math
import os
from fractions import Fraction

PLOT_FORMATS = (".png", ".svg", ".pdf")


class Usage(Exception):
    """Bad input found after parsing: becomes ``nvib CMD: error: argument X: ...`` and exit status 2."""

    def __init__(self, argument: str | None, message: str):
        super().__init__(message)
        self.argument = argument
        self.message = message


def flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def run_checked(body, args, parser) -> int:
    """body(args); a Usage error becomes argparse's usage error (exit status 2)."""
    try:
        return body(args)
    except Usage as exc:
        parser.error(f"argument {exc.argument}: {exc.message}" if exc.argument else exc.message)
    return 2  # not reached: parser.error exits


def usage_from(exc: Exception, flags: dict[str, str], default: str | None = None) -> Usage:
    """A library error (its .argument names the argument, "a, b" for several) as a Usage naming the options."""
    argument = getattr(exc, "argument", None)
    message = str(exc)
    if argument and message.startswith(argument + ": "):
        message = message[len(argument) + 2:]
    names = [n.strip() for n in argument.split(",")] if argument else []
    if names and all(n in flags for n in names):
        return Usage("/".join(flags[n] for n in names), message)
    return Usage(default, message if default else str(exc))


# ---------------------------------------------------------------- argument types

def real(text: str) -> float:
    """A finite real number; fractions such as 1/4 or 1/12 are accepted."""
    try:
        x = float(text)
    except ValueError:
        try:
            x = float(Fraction(text.strip()))
        except (ValueError, ZeroDivisionError):
            raise argparse.ArgumentTypeError(f"expected a number (such as 0.25 or 1/4), got {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return x


def positive_real(text: str) -> float:
    x = real(text)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return x


def bound(text: str) -> float:
    """A positive real number or 'inf'."""
    if text.strip().lower() in ("inf", "infinity"):
        return math.inf
    return positive_real(text)


def integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


def positive_int(text: str) -> int:
    k = integer(text)
    if k < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return k


# ---------------------------------------------------------------- output

def seconds(x: float) -> str:
    if x < 1e-3:
        return f"{x * 1e6:.0f} us"
    if x < 1.0:
        return f"{x * 1e3:.3g} ms"
    return f"{x:.3g} s"


def table(rows: list[list[str]], right: set[int] = frozenset()) -> list[str]:
    """Aligned columns, a rule under the header row."""
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out = []
    for r in rows:
        cells = [c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        out.append("  ".join(cells).rstrip())
    out.insert(1, "-" * max(len(line) for line in out))
    return out


def isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def write_output(command: str, arg: str, path: str | None, write) -> int:
    """write(path) for the output option ``arg`` when given: "wrote PATH", or an error naming the option on
    the standard error. Returns the exit status it asks for: 0, or 1 when the file could not be written."""
    import sys

    if path is None:
        return 0
    try:
        write(path)
    except OSError as exc:
        print(f"nvib {command}: error: {arg}: cannot write {path!r}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    print(f"wrote {path}")
    return 0


def check_output(arg: str, path: str, formats: tuple[str, ...]) -> None:
    if not path:
        raise Usage(arg, f"expected a file name ending in {' or '.join(formats)}, got an empty one")
    ext = os.path.splitext(path)[1].lower()
    if ext not in formats:
        raise Usage(arg, f"expected a file ending in {' or '.join(formats)}, got {path!r}")
    if os.path.isdir(path):
        raise Usage(arg, f"{path!r} is a folder; give a file name in it")
    try:
        os.stat(path)
    except OSError as exc:  # a new file is FileNotFoundError; its folder is checked below
        if exc.errno == errno.ELOOP:
            raise Usage(arg, f"{path!r} is a loop of symbolic links") from None
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        if os.path.exists(folder):
            raise Usage(arg, f"{folder!r} is a file, not a folder")
        raise Usage(arg, f"folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise Usage(arg, f"folder {folder!r} is not writable")
    if ext in PLOT_FORMATS:
        import importlib.util

        if importlib.util.find_spec("matplotlib") is None:
            raise Usage(arg, "needs matplotlib (pip install matplotlib)")


# ---------------------------------------------------------------- scheme options

def scheme_options() -> dict[str, dict]:
    """option name -> {kind, doc, bounds, choices, where ('param' | 'newton' | 'factory'), schemes: [keys]},
    generated from the registry: every scheme parameter, every named constructor (its flag is its
    parameter for from_<parameter>, its own name otherwise) and, for the implicit schemes, the Newton
    options (Newton's iteration as --iteration)."""
    from .. import Newton, schemes

    options: dict[str, dict] = {}

    def add(name, info, key):
        entry = options.setdefault(name, dict(info, schemes=[]))
        entry["schemes"].append(key)

    for key, cls in schemes().items():
        for p in cls.parameters():
            if p["kind"] == "newton":
                for q in Newton.parameters():
                    add(q["name"], dict(q, where="newton", formerly=None), key)  # the command line never had --mode
            else:
                add(p["name"], dict(p, where="param"), key)
        for f in cls.factories():
            # from_<parameter> is set by --<parameter>; another constructor by --<its name>
            name = f["method"][len("from_"):] if f["method"].startswith("from_") else f["method"]
            add(name, dict(kind="real", doc=f["doc"], bounds="", default=None, method=f["method"],
                           where="factory"), key)
    return options


def add_scheme_options(group, *, iteration: bool = True) -> None:
    """One option per entry of scheme_options(); each applies to the schemes that have it."""
    for name, opt in scheme_options().items():
        if not iteration and opt["where"] == "newton":
            continue
        applies = "/".join(opt["schemes"])
        default = "" if opt["default"] is None else f"; default {opt['default']}"
        help_text = f"{applies}: {opt['doc']}" + (f" ({opt['bounds']}{default})" if opt["bounds"] else default)
        kw = dict(help=help_text.replace("%", "%%"))
        if opt["kind"] == "choice":
            kw["choices"] = [c.strip(" '") for c in opt["bounds"].replace(" or ", ", ").split(",")]
        else:
            kw["type"] = real if opt["kind"] == "real" else integer
            kw["metavar"] = "X"
        group.add_argument(flag(name), dest=f"scheme_{name}", **kw)
        if opt.get("formerly"):  # the old name of a renamed parameter: refused, naming the new one
            group.add_argument(flag(opt["formerly"]), dest=f"renamed_{name}", metavar="X", help=argparse.SUPPRESS)


def make_scheme(key: str, args, *, only_applicable: bool = False):
    """The scheme `key` with the scheme options given in args. An option that does not apply is an error
    (or, with only_applicable, skipped); library errors name the option."""
    from .. import Newton, schemes

    options = scheme_options()
    cls = schemes()[key]
    for n, opt in options.items():
        if opt.get("formerly") and getattr(args, f"renamed_{n}", None) is not None:
            raise Usage(flag(opt["formerly"]), f"renamed {flag(n)} ({opt['doc']})")
    given = {n: getattr(args, f"scheme_{n}") for n in options if getattr(args, f"scheme_{n}", None) is not None}
    for n in list(given):
        if key not in options[n]["schemes"]:
            if only_applicable:
                del given[n]
                continue
            raise Usage(flag(n), f"does not apply to --scheme {key} (only to {', '.join(options[n]['schemes'])})")
    params = {n: v for n, v in given.items() if options[n]["where"] == "param"}
    newton = {n: v for n, v in given.items() if options[n]["where"] == "newton" and n != "iteration"}
    factory = [n for n in given if options[n]["where"] == "factory"]
    flags = {n: flag(n) for n in options} | {"newton": "--iteration"}
    for f in factory:
        flags[f] = flag(f)
    if len(factory) > 1 or (factory and params):
        clash = factory[1:] + list(params)
        raise Usage(flag(factory[0]), f"sets the scheme's parameters itself; drop {', '.join(flag(c) for c in clash)}")
    try:
        kw = {}
        if newton or "iteration" in given:
            kw["newton"] = Newton(**newton, **({"iteration": given["iteration"]} if "iteration" in given else {}))
        if factory:
            return getattr(cls, options[factory[0]]["method"])(given[factory[0]], **kw)
        return cls(**params, **kw)
    except (ValueError, TypeError) as exc:
        raise usage_from(exc, flags, default="--scheme") from None
