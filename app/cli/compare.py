"""``lipspace compare``: where and how the levels of a field (speakers, emotions, groups) move differently.

Input: a manifold file from ``lipspace build`` (a corpus file, or any format ``lipspace import``
reads, is fitted first, as ``lipspace figures`` does), and a per-utterance field. The levels
are compared on the one manifold (:class:`engine.comparison.compare.ConditionComparison`):
per cluster the shift of its centre in Y and X and the change of its spread, per level the
dynamics on the manifold, per state the enrichment of one level against the other -- every
test resampling whole utterances (or speakers), with bootstrap intervals and
Benjamini-Hochberg q-values, the design stated. Prints the design and what differs;
``--csv`` writes one row per comparison, ``--figure`` the journal-width figure.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from app.cli.options import add_quiet_option, add_seed_option

FIGURE_SUFFIXES = (".pdf", ".png", ".svg")


def add_arguments(p):
    p.add_argument("input", metavar="FILE", help="manifold file (.npz from 'lipspace build'), or a corpus file "
                                                 "(fitted first)")
    p.add_argument("--by", required=True, metavar="FIELD",
                   help="the per-utterance field whose levels are compared (speaker, text, or one read on import)")
    p.add_argument("--levels", default=None, metavar="A,B",
                   help="the two levels to compare (B against A), or a reference and several levels (REF,B,C: "
                        "each against REF); default: the field's two levels")
    p.add_argument("--paired-by", default=None, metavar="FIELD",
                   help="compare within blocks of this field, e.g. text: the same sentence said in each level")
    p.add_argument("--csv", default=None, metavar="STATS.csv", help="write the table, one row per comparison")
    p.add_argument("--figure", default=None, metavar="DIFF.pdf", help="write the figure (.pdf, .png or .svg)")
    p.add_argument("--width", default="180mm", metavar="85mm|180mm",
                   help="figure width: 85mm (one journal column) or 180mm (two; default)")
    p.add_argument("--dpi", type=float, default=300, help="PNG resolution (default: %(default)s)")
    p.add_argument("--permutations", type=int, default=4999,
                   help="random permutations per contrast (every arrangement when there are fewer; default: "
                        "%(default)s)")
    p.add_argument("--bootstrap", type=int, default=1000, help="bootstrap draws for the intervals (default: "
                                                               "%(default)s; 0: none)")
    p.add_argument("--alpha", type=float, default=0.05, help="q-value below which a row counts as a difference "
                                                             "(default: %(default)s)")
    p.add_argument("--horizon-ms", type=float, default=100.0,
                   help="horizon of the future hemisphere (default: %(default)s ms, the window's)")
    p.add_argument("--labels", choices=("auto", "phones", "kinematic"), default="auto",
                   help="clusters of phone mid-points or of kinematic landmarks (default: %(default)s)")
    add_seed_option(p, what="the permutations and the bootstrap")
    p.add_argument("--show", type=int, default=10, metavar="N", help="rows printed per family (default: 10)")
    add_quiet_option(p)


def _check(args):
    from app.cli import CliError

    if args.csv is not None and Path(args.csv).suffix.lower() != ".csv":
        raise CliError(f"--csv {args.csv}: the table file must end in .csv")
    if args.figure is not None and Path(args.figure).suffix.lower() not in FIGURE_SUFFIXES:
        raise CliError(f"--figure {args.figure}: the figure must end in {', '.join(FIGURE_SUFFIXES)}")
    if not 1 <= args.permutations <= 1_000_000:
        raise CliError(f"--permutations {args.permutations}: must be from 1 to 1000000")
    if not 0 <= args.bootstrap <= 1_000_000:
        raise CliError(f"--bootstrap {args.bootstrap}: must be from 0 to 1000000")
    if not 0 < args.alpha < 1:
        raise CliError(f"--alpha {args.alpha:g}: must be between 0 and 1 (e.g. 0.05)")
    if not (math.isfinite(args.horizon_ms) and args.horizon_ms > 0):
        raise CliError(f"--horizon-ms {args.horizon_ms:g}: must be a positive number of milliseconds")
    if not 10 <= args.dpi <= 1200:
        raise CliError(f"--dpi {args.dpi:g}: must be from 10 to 1200")
    from app.figures.style import parse_width

    try:
        return parse_width(args.width)
    except ValueError as exc:
        raise CliError(f"--width: {exc}") from None


def _source(args, progress):
    """(manifold or None, corpus): a manifold file's manifold, or a corpus to fit (later, after the checks)."""
    from app.cli import CliError
    from app.cli._common import load_corpus_arg, load_manifold_arg
    from app.files.source_loading import source_kind

    try:
        kind = source_kind(args.input)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if kind == "manifold":
        m = load_manifold_arg(args.input)
        return m, m.corpus_
    return None, load_corpus_arg(args.input, progress=progress)


def _designs(args, fields, name):
    """The contrasts and their designs, resolved before any fitting (bad input stops here)."""
    from engine.comparison.compare import default_contrasts
    from engine.comparison.design import resolve_design
    from engine.comparison.fields import field_values

    values = field_values(fields, args.by, source=name)
    pairs = field_values(fields, args.paired_by, source=name) if args.paired_by else None
    if args.paired_by and args.paired_by == args.by:
        from engine.comparison.design import ComparisonError

        raise ComparisonError(f"--paired-by {args.paired_by}: the field compared cannot also be the pairing field")
    levels = [v.strip() for v in args.levels.split(",")] if args.levels is not None else None
    contrasts = default_contrasts(values, args.by, levels)
    designs = [resolve_design(values, a, b, by=args.by, speakers=fields["speaker"], pairs=pairs,
                              paired_by=args.paired_by or "", alpha=args.alpha) for a, b in contrasts]
    return values, pairs, contrasts, designs


def _cell(v, digits=3) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return f"{v:.2g}" if 0 < abs(v) < 10 ** -digits else f"{v:.{digits}g}"
    return str(v)


def _print_rows(rows, title):
    from app.cli.clusters import format_table

    if not rows:
        return
    print(f"\n{title}")
    cols = ["measure", "target", "space", "estimate", "interval", "unit", "p", "q", "n_utterances", "n_speakers"]
    out = [{**r, "estimate": _cell(r["estimate"]), "interval": (f"[{_cell(r['ci_low'])}, {_cell(r['ci_high'])}]"
                                                                if not math.isnan(r["ci_low"]) else "-"),
            "p": _cell(r["p"], 2), "q": _cell(r["q"], 2)} for r in rows]
    print(format_table(out, cols, ["measure", "target", "space", "estimate", "interval", "unit", "p", "q",
                                   "utts", "speakers"]))


def _report(result, args):
    for i, ((a, b), design) in enumerate(zip(result.contrasts_, result.designs_)):
        print(f"\n== {args.by}: {b} against {a} ==")
        print(f"design: {design.describe()}")
        if not design.testable:
            print(f"cannot test: {design.reason}.")
        sig = result.significant(contrast=i)
        if design.testable:
            counts = {f: sum(r["family"] == f for r in sig) for f in ("cluster", "dynamics", "state")}
            print(f"differences at q < {args.alpha:g}: {counts['cluster']} cluster, {counts['dynamics']} dynamics, "
                  f"{counts['state']} state comparisons")
        for fam, title in (("cluster", "clusters"), ("dynamics", "dynamics"), ("state", "states")):
            rows = result.table(family=fam, contrast=i)
            if fam == "state":
                n_sig = sum(r["family"] == "state" for r in sig)
                over = sum(r["estimate"] > 0 for r in sig if r["family"] == "state")
                print(f"\nstates: {len(rows)} compared; {over} hold more of {b}, {n_sig - over} more of {a} "
                      f"(q < {args.alpha:g})")
                rows = [r for r in sig if r["family"] == "state"][:args.show]
            elif fam == "cluster":
                key = (lambda r: (r["p"], r["target"])) if design.testable else (lambda r: -abs(r["estimate"]))
                rows = sorted([r for r in rows if r["measure"] == "centre shift"], key=key)[:args.show]
            _print_rows(rows, f"{title} ({'smallest p first' if fam == 'cluster' and design.testable else ''})"
                        .replace(" ()", ""))
    for note in dict.fromkeys(result.notes_):
        print(f"note: {note}", file=sys.stderr)


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import command_outputs, progress_bar
    from engine.comparison.compare import COLUMNS, ConditionComparison
    from engine.comparison.fields import FieldError, level_counts, utterance_fields

    width = _check(args)
    with command_outputs(args) as outputs:
        csv_path = outputs.file(args.csv, option="--csv") if args.csv else None
        fig_path = outputs.file(args.figure, option="--figure") if args.figure else None
        with progress_bar(disable=True if args.quiet else None) as progress:
            manifold, corpus = _source(args, progress)
            fields = utterance_fields(corpus)
            try:
                values, pairs, contrasts, designs = _designs(args, fields, f"{args.input}")
            except FieldError as exc:
                raise CliError(str(exc)) from None
            counts = ", ".join(f"{k} {v}" for k, v in level_counts(values).items())
            print(f"{corpus.name}: field {args.by!r} ({counts} utterances)"
                  + (f", paired by {args.paired_by!r}" if args.paired_by else ""))
            if manifold is None:
                for d in designs:  # said now: the fit below takes a while
                    if not d.testable:
                        print(f"lipspace compare: cannot test {d.level_b} against {d.level_a}: {d.reason}.",
                              file=sys.stderr)
                from engine.manifold.model import Manifold

                try:
                    manifold = Manifold().fit(corpus, progress=progress)
                except ValueError as exc:
                    raise CliError(str(exc)) from None
            try:
                result = ConditionComparison(
                    n_permutations=args.permutations, n_bootstrap=args.bootstrap, alpha=args.alpha,
                    horizon_s=args.horizon_ms / 1000.0, labels=args.labels, random_state=args.seed,
                ).fit(manifold, values, by=args.by, contrasts=contrasts, speakers=fields["speaker"], pairs=pairs,
                      paired_by=args.paired_by or "", progress=progress)
            except ValueError as exc:
                raise CliError(str(exc)) from None
        _report(result, args)
        if csv_path is not None:
            from engine.io.writers.export import write_table_csv

            write_table_csv(csv_path, result.rows_, columns=COLUMNS)
        if fig_path is not None:
            from app.figures.comparison import make_comparison
            from app.figures.export import save_figure
            from app.models.palette import SessionPalette

            palette = SessionPalette.for_corpus(corpus, fields={args.by: values})
            if len(contrasts) > 1:
                print(f"lipspace compare: the figure shows the first contrast ({contrasts[0][1]} against "
                      f"{contrasts[0][0]}); the table holds all {len(contrasts)}", file=sys.stderr)
            save_figure(make_comparison(manifold, result, palette=palette, width=width), fig_path, dpi=args.dpi)
    for path in (args.csv, args.figure):
        if path:
            print(f"wrote {path}", file=sys.stderr)
    return 0
