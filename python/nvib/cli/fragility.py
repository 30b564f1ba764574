"""nvib fragility: lognormal fragility curves fitted by maximum likelihood (Baker 2015) to an IDA's runs
(the CSV of ``nvib ida --out``), to collapse intensities, or to multiple stripes."""

from __future__ import annotations

import argparse

from . import _common as c


def add_parser(sub) -> None:
    p = sub.add_parser("fragility", help="lognormal fragility curves from an IDA or from stripes",
                       description="Fit lognormal fragility curves by maximum likelihood (Baker 2015). FILE is the "
                                   "CSV of nvib ida --out (collapse fragility from each record's first collapse, and "
                                   "with --demand-limit the fragility of exceeding a demand), or a CSV of columns "
                                   "im,n,z (multiple stripes: runs n and exceedances z at each intensity im), or a "
                                   "CSV of one column im (the intensities at which records collapsed; with a second "
                                   "column collapsed of 0/1, a 0 is a record that did not collapse up to im).",
                       epilog="example:\n  nvib ida building_collapse r1.AT2 r2.AT2 r3.AT2 --out ida.csv\n"
                              "  nvib fragility ida.csv --demand-limit 2 --plot fragility.png",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="FILE", help="the CSV (see above)")
    p.add_argument("--demand-limit", type=c.positive_real, nargs="+", metavar="D",
                   help="with an IDA file: also the fragility of the demand exceeding D (in the IDA's demand unit, "
                        "%% for a drift ratio)")
    p.add_argument("--im-name", default=None, help="name of the intensity measure (for im,n,z or im files)")
    p.add_argument("--im-unit", default="", help="unit of the intensity measure (for im,n,z or im files)")
    p.add_argument("--plot", metavar="PNG", help="write the curves with their data to this PNG")
    p.set_defaults(func=lambda args, parser: c.run_checked(run, args, parser), subparser=p)


def _read_table(path: str) -> tuple[list[str], list[list[float]]]:
    import csv

    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = [r for r in csv.reader(line for line in fh if not line.startswith("#")) if r]
    except (OSError, UnicodeDecodeError) as exc:
        raise c.Usage("FILE", f"{path!r}: cannot read it: {getattr(exc, 'strerror', None) or exc}") from None
    if not rows:
        raise c.Usage("FILE", f"{path!r}: empty")
    head = [h.strip().split(" [")[0] for h in rows[0]]
    try:
        values = [[float(x) for x in r] for r in rows[1:]]
    except ValueError:
        raise c.Usage("FILE", f"{path!r}: expected numbers under the header {rows[0]}") from None
    if any(len(r) != len(head) for r in values):
        raise c.Usage("FILE", f"{path!r}: every row needs {len(head)} values, as the header")
    return head, values


def run(args) -> int:
    from .. import fragility
    from ..analysis.ida import read_ida

    if args.plot is not None:
        c.check_output("--plot", args.plot, c.PLOT_FORMATS)
    fits = []
    try:
        with open(args.file, encoding="utf-8") as fh:
            is_ida = fh.readline().startswith("# im_name:")
    except (OSError, UnicodeDecodeError) as exc:
        raise c.Usage("FILE", f"{args.file!r}: cannot read it: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        if is_ida:
            res = read_ida(args.file)
            print(f"{args.file}: IDA of {len(res.curves)} records, {res.im_name} [{res.im_unit}] against "
                  f"{res.measure_name} [{res.measure_unit}]")
            fits.append(fragility.from_ida(res))
            for d in args.demand_limit or []:
                fits.append(fragility.from_ida(res, demand_limit=d))
        else:
            if args.demand_limit:
                raise c.Usage("--demand-limit", "applies to an IDA file (nvib ida --out)")
            head, rows = _read_table(args.file)
            cols = {h: [r[k] for r in rows] for k, h in enumerate(head)}
            label = dict(im_name=args.im_name or "IM", im_unit=args.im_unit)
            if {"im", "n", "z"} <= set(cols):
                fits.append(fragility.fit_stripes(cols["im"], cols["n"], cols["z"], **label))
            elif "im" in cols:
                done = cols.get("collapsed", [1.0] * len(cols["im"]))
                fits.append(fragility.fit_collapse_ims([x for x, k in zip(cols["im"], done) if k],
                                                       censored=[x for x, k in zip(cols["im"], done) if not k],
                                                       **label))
            else:
                raise c.Usage("FILE", f"{args.file!r}: expected an IDA file, or columns im,n,z, or im "
                                      f"[,collapsed]; got {', '.join(head)}")
    except (ValueError, TypeError) as exc:
        raise c.usage_from(exc, {"demand_limit": "--demand-limit", "path": "FILE", "ims": "FILE", "z": "FILE",
                                 "n": "FILE", "levels": "FILE", "censored": "FILE", "ida": "FILE"}, default="FILE") from None
    print(fragility.markdown_table(fits))
    return c.write_output("fragility", "--plot", args.plot, lambda path: _plot(fits, path))


def _plot(fits, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(fits), figsize=(6.0 * len(fits), 4.6), squeeze=False)
    for f, ax in zip(fits, axes[0]):
        f.plot(ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
