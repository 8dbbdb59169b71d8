"""``lipspace clusters``: the phone cluster table (paper section 5 and Table 1).

Input: a manifold file from ``lipspace build``, a native corpus file (a manifold is
fitted first), or nothing (the synthetic talker). Prints one row per phone — count,
mean in Y, the fraction of mid-points on the opening side of the zero-velocity plane,
broad and lip-reading classes, and the nearest phone with its separation in Y (with
dynamics) and in X (shape only) — and optionally writes the rows as CSV. With
``--phones`` it also prints the pairwise separations of those phones in Y and in X,
the numbers behind the paper's claim that dynamics separate /m/ from /p, b/.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from app.cli.options import add_quiet_option, add_talker_options

MEASURES = ("bhattacharyya", "dprime")


def add_arguments(p):
    p.add_argument("input", nargs="?", metavar="MANIFOLD_OR_CORPUS",
                   help="manifold file (.npz from 'lipspace build') or native corpus file; "
                        "omit for the synthetic talker")
    add_talker_options(p, when="when no input is given")
    p.add_argument("--phones", default=None, metavar="P1,P2,...",
                   help="only these phones (comma-separated), plus their pairwise separation matrices")
    p.add_argument("--csv", default=None, metavar="OUT.csv", help="also write the table as CSV")
    p.add_argument("--dims", type=int, default=3, help="dimensions of Y and X used (default: %(default)s)")
    p.add_argument("--min-count", type=int, default=3, help="smallest cluster kept (default: %(default)s)")
    p.add_argument("--measure", choices=MEASURES, default="bhattacharyya",
                   help="separation measure (default: %(default)s)")
    p.add_argument("--normalize", action="store_true",
                   help="merge labels through the phone-set table (e.g. AH0 and ax become ax)")
    p.add_argument("--keep-pauses", action="store_true", help="keep pause labels (sil, sp, ...) as a cluster")
    p.add_argument("--labels", choices=("auto", "phones", "kinematic"), default="auto",
                   help="cluster phone mid-points, or kinematic landmarks (aperture maxima 'open', minima "
                        "'closed', peak velocities 'opening' / 'closing'); auto = phones when the corpus has any "
                        "(default: %(default)s)")
    add_quiet_option(p)


def _manifold(args):
    from app.cli import CliError
    from app.cli._common import load_corpus_arg, load_manifold_arg, progress_bar
    from engine.manifold.model import Manifold

    if args.input is not None:
        try:
            return load_manifold_arg(args.input)
        except CliError as exc:
            if "corpus file" not in str(exc):
                raise
    with progress_bar(disable=True if args.quiet else None) as progress:
        corpus = load_corpus_arg(args.input, synthetic_preset=args.preset, progress=progress)
        try:
            return Manifold().fit(corpus, progress=progress)
        except ValueError as exc:
            raise CliError(str(exc)) from None


def _cell(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.3f}"
    return str(v)


def format_table(rows, columns, headers=None) -> str:
    """Rows of dicts as an aligned text table (numbers right-aligned, text left-aligned)."""
    headers = list(headers or columns)
    cells = [[_cell(r.get(c)) for c in columns] for r in rows]
    numeric = [all(isinstance(r.get(c), (int, float)) or r.get(c) is None for r in rows) for c in columns]
    width = [max([len(h)] + [len(row[k]) for row in cells]) for k, h in enumerate(headers)]

    def line(vals):
        return "  ".join(v.rjust(w) if num else v.ljust(w) for v, w, num in zip(vals, width, numeric)).rstrip()

    return "\n".join([line(headers), line(["-" * w for w in width])] + [line(r) for r in cells])


def run(args) -> int:
    from app.cli import CliError
    from engine.manifold.clusters import clusters_of

    if args.dims < 1:
        raise CliError(f"--dims {args.dims}: must be at least 1")
    if args.min_count < 2:
        raise CliError(f"--min-count {args.min_count}: must be at least 2 (a covariance needs two members)")
    if args.csv is not None and Path(args.csv).suffix.lower() != ".csv":
        raise CliError(f"{args.csv}: the table file must end in .csv")
    manifold = _manifold(args)
    c = manifold.corpus_
    try:
        pc, labels, note = clusters_of(manifold, labels=args.labels, n_dims=args.dims, min_count=args.min_count,
                                       exclude_pauses=not args.keep_pauses, normalize_labels=args.normalize)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if note:
        print(note.replace(f"{c.name} has no phone labels: using", "labels:"), file=sys.stderr)
    if not pc.phones_:
        fix = (f"lower --min-count (at least 2; now {args.min_count})" if args.min_count > 2 else
               "use more speech, or labels with more instances")
        raise CliError(f"no {'phone' if labels == 'phones' else 'kinematic landmark'} has {args.min_count} or more "
                       f"mid-points in {c.name}; {fix}")
    phones = None
    if args.phones:
        phones = [p.strip() for p in args.phones.split(",") if p.strip()]
        try:
            phones = [pc.phones_[pc.index(p)] for p in phones]
        except ValueError as exc:
            raise CliError(str(exc)) from None
    rows = pc.table(phones, measure=args.measure)

    ycols = [f"y{k + 1}" for k in range(pc.n_dims_)]
    columns = ["phone", "count", *ycols, "opening_fraction", "broad_class", "lipreading_class",
               "nearest_y", "separation_y", "separation_x", "nearest_x", "separation_nearest_x"]
    headers = ["phone", "count", *ycols, "opening", "class", "lipreading", "nearest Y", "sep Y", "sep X",
               "nearest X", "sep X(nX)"]
    n_inst = int(pc.counts_.sum())
    what = "phone mid-points" if labels == "phones" else "kinematic landmarks"
    print(f"{manifold.corpus_.name}: {n_inst} {what} in {len(pc.phones_)} clusters "
          f"(F^y and F^x, {pc.n_dims_} / {pc.n_dims_x_} dims; separation: {args.measure}; labels: "
          f"{pc.phoneset_ if labels == 'phones' else 'open / closed / opening / closing'}"
          f"{', normalised' if args.normalize else ''})")
    if pc.excluded_phones_:
        few = ", ".join(f"{p} {n}" for p, n in zip(pc.excluded_phones_, pc.excluded_counts_))
        print(f"fewer than {args.min_count} mid-points (left out): {few}")
    if pc.n_pauses_:
        print(f"pauses left out: {pc.n_pauses_}")
    print(format_table(rows, columns, headers))
    if phones and len(phones) > 1:
        for space, what in (("y", "Y (shape + velocity)"), ("x", "X (shape only)")):
            S = pc.separation_matrix(space, measure=args.measure, phones=phones)
            mrows = [{"": a, **{b: float(S[i, j]) for j, b in enumerate(phones)}} for i, a in enumerate(phones)]
            print(f"\n{args.measure} separation in {what}:")
            print(format_table(mrows, ["", *phones]))
    if args.csv:
        from app.cli._common import command_outputs
        from engine.io.writers.export import write_table_csv

        with command_outputs(args) as outputs:
            write_table_csv(outputs.file(args.csv, option="--csv"), rows, columns=columns)
        print(f"wrote {args.csv}", file=sys.stderr)
    return 0
