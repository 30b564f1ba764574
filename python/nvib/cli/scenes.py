"""nvib scenes: the built-in scenes."""

from __future__ import annotations

from . import _common as c


def add_parser(sub) -> None:
    p = sub.add_parser("scenes", help="list the built-in scenes", description="List the built-in scenes.")
    p.set_defaults(func=lambda args, parser: run(args), subparser=p)


def run(args) -> int:
    from .. import load_scene, scene_names
    from .run import effect_summary

    rows = [["name", "DOFs", "dt [s]", "t_end [s]", "effects", "title"]]
    sources = []
    for name in scene_names():
        try:
            m = load_scene(name)
        except (ValueError, OSError) as exc:  # a broken built-in scene should not hide the others
            rows.append([name, "?", "?", "?", "?", f"cannot load: {exc}"])
            continue
        s = m.scene
        rows.append([name, str(m.n), "-" if s["dt"] is None else f"{s['dt']:g}",
                     "-" if s["t_end"] is None else f"{s['t_end']:g}", effect_summary(m), s["title"]])
        sources.append((name, s["source"]))
    print("\n".join(c.table(rows, right={1, 2, 3})))
    if sources:
        print("\nsources:")
        w = max(len(n) for n, _ in sources)
        for n, src in sources:
            print(f"  {n:<{w}}  {src or '-'}")
    print("\nrun one with: nvib run NAME  (--without takes an effect name or type; see nvib run --help)")
    return 0
