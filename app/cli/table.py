"""``lipspace table``: a manifold's per-frame results as a tidy table and as Praat TextGrids.

``lipspace table MANIFOLD -o frames.csv``      one row per frame (:mod:`engine.frame_table`), units in
                                                ``frames.csv.json``; ``-o frames.parquet`` with pyarrow
``lipspace table MANIFOLD --textgrid DIR``     one TextGrid per utterance: phones, movement classes,
                                                kinematic landmarks

Existing files are never overwritten without ``--force``; every file is written atomically.
"""
from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["add_arguments", "run", "refuse_existing"]


def add_arguments(p):
    p.add_argument("manifold", metavar="MANIFOLD", help="manifold file from 'lipspace build'")
    p.add_argument("-o", "--output", metavar="FRAMES.csv|FRAMES.parquet",
                   help="write the per-frame table (CSV, or Parquet when pyarrow is installed); units and column "
                        "meanings go to FRAMES.csv.json beside it")
    p.add_argument("--textgrid", dest="textgrid_dir", metavar="DIR",
                   help="write one Praat TextGrid per utterance into DIR (tiers: phones, class, landmarks)")
    p.add_argument("--fx", type=int, default=None, metavar="K",
                   help="shape components written as fx_1..fx_K (default: all of the manifold's)")
    p.add_argument("--force", action="store_true", help="replace files that exist already")


def refuse_existing(paths, force: bool) -> None:
    """Refuse (naming the file) to replace an existing file unless ``force``."""
    from app.cli import CliError

    if force:
        return
    there = [Path(p) for p in paths if Path(p).exists()]
    if there:
        more = f" (and {len(there) - 1} more)" if len(there) > 1 else ""
        raise CliError(f"{there[0]} exists already{more}; give --force to replace it, or choose another name. "
                       "Nothing was written")


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import load_manifold_arg
    from engine.frame_table import frame_table, write_textgrids
    from engine.io.praat import textgrid_names
    from engine.io.tidy import TABLE_SUFFIXES, have_parquet, sidecar_path, write_frame_table

    if args.output is None and args.textgrid_dir is None:
        raise CliError("nothing to write: give -o FRAMES.csv (or .parquet) and/or --textgrid DIR")
    out = Path(args.output) if args.output else None
    if out is not None:
        if out.suffix.lower() not in TABLE_SUFFIXES:
            raise CliError(f"-o {out}: the table must end in .csv or .parquet")
        if out.suffix.lower() == ".parquet" and not have_parquet():
            raise CliError(f"-o {out}: writing Parquet needs pyarrow (pip install 'lipspace[parquet]'); "
                           "or write .csv")
    manifold = load_manifold_arg(args.manifold)
    c = manifold.corpus_
    grids = None
    if args.textgrid_dir is not None:
        grids = textgrid_names(u.id for u in c.utterances)
    refuse_existing(([out, sidecar_path(out)] if out else [])
                    + ([Path(args.textgrid_dir) / n for n in grids] if grids else []), args.force)
    try:
        table = frame_table(manifold, n_fx=args.fx, source=str(args.manifold))
    except ValueError as exc:
        raise CliError(f"--fx {args.fx}: {exc}" if args.fx is not None else str(exc)) from None
    for note in table.notes:
        if "stand" in note or "no phone" in note:
            print(f"lipspace table: note: {note}", file=sys.stderr)
    if out is not None:
        written = write_frame_table(out, table)
        print(f"wrote {out} ({table.n_rows} rows x {len(table.columns)} columns: one per frame of "
              f"{len(c.utterances)} utterances); units and column meanings in {written[1]}")
    if grids is not None:
        files = write_textgrids(manifold, table, args.textgrid_dir, names=grids)
        print(f"wrote {len(files)} TextGrids to {args.textgrid_dir} (tiers: phones, class, landmarks)")
    return 0
