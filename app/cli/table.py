"""``lipspace table``: a manifold's per-frame results as a tidy table and as Praat TextGrids.

``lipspace table MANIFOLD -o frames.csv``
    one row per frame (:mod:`engine.manifold.frame_table`), units in ``frames.csv.json``;
    ``-o frames.parquet`` with pyarrow
``lipspace table MANIFOLD --textgrid DIR``
    one TextGrid per utterance: phones, movement classes, kinematic landmarks (and a tier per
    --gestures track)
``--tracks lip_protrusion,speed_UL``
    derived tracks as columns (low-passed at --lowpass Hz)
``--gestures lip_aperture --gesture-table G.csv``
    one row per gesture: landmark times, durations, peak velocities, the state at each landmark

Metadata fields of the utterances (speaker, sex, emotion ...) are columns after ``speaker``.

Existing files are never overwritten without ``--force``; every output is staged and moved in
at the end, so a failure or a stop leaves all the old files or all the new ones.
"""
from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["add_arguments", "run"]


def add_arguments(p):
    p.add_argument("manifold", metavar="MANIFOLD", help="manifold file from 'lipspace build'")
    p.add_argument("-o", "--output", metavar="FRAMES.csv|FRAMES.parquet",
                   help="write the per-frame table (CSV, or Parquet when pyarrow is installed); units and column "
                        "meanings go to FRAMES.csv.json beside it")
    p.add_argument("--textgrid", dest="textgrid_dir", metavar="DIR",
                   help="write one Praat TextGrid per utterance into DIR (tiers: phones, class, landmarks)")
    p.add_argument("--fx", type=int, default=None, metavar="K",
                   help="shape components written as fx_1..fx_K (default: all of the manifold's)")
    from app.cli.table_lab import add_lab_arguments

    add_lab_arguments(p)


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import command_outputs, load_manifold_arg
    from app.cli.table_lab import lab_columns, lab_tables, list_tracks
    from engine.io.writers.praat import textgrid_names
    from engine.io.writers.tidy import TABLE_SUFFIXES, have_parquet, sidecar_path, write_frame_table
    from engine.manifold.frame_table import frame_table, write_textgrids

    if args.output is None and args.textgrid_dir is None and args.gesture_table is None and args.tracks != "list":
        raise CliError("nothing to write: give -o FRAMES.csv (or .parquet), --textgrid DIR and/or --gesture-table "
                       "GESTURES.csv")
    out = Path(args.output) if args.output else None
    if out is not None:
        if out.suffix.lower() not in TABLE_SUFFIXES:
            raise CliError(f"-o {out}: the table must end in .csv or .parquet")
        if out.suffix.lower() == ".parquet" and not have_parquet():
            raise CliError(f"-o {out}: writing Parquet needs pyarrow (pip install 'lipspace[parquet]'); "
                           "or write .csv")
    manifold = load_manifold_arg(args.manifold)
    if list_tracks(args, manifold):
        return 0
    c = manifold.corpus_
    grids = None
    if args.textgrid_dir is not None:
        grids = textgrid_names(u.id for u in c.utterances)
    with command_outputs(args) as outputs:  # the table, its sidecar and the TextGrids: all or none
        side = sidecar_path(out) if out is not None else None
        staged = (outputs.file(out, option="-o"), outputs.file(side, option="-o")) if out is not None else None
        lab = lab_tables(args, manifold, outputs)  # --tracks, --gestures: checked before the work
        folder = outputs.folder(args.textgrid_dir, names=grids, option="--textgrid") if grids is not None else None
        try:  # existing files are refused above, before this work
            table = frame_table(manifold, n_fx=args.fx, source=str(args.manifold))
        except ValueError as exc:
            raise CliError(f"--fx {args.fx}: {exc}" if args.fx is not None else str(exc)) from None
        for note in table.notes:
            if "stand" in note or "no phone" in note:
                print(f"lipspace table: note: {note}", file=sys.stderr)
        table = lab_columns(table, manifold, lab)  # metadata fields and derived tracks
        if staged is not None:
            write_frame_table(staged[0], table, sidecar=staged[1], name=out.name)
        if folder is not None and lab.gestures:
            from engine.manifold.lab_tables import write_textgrids_with_gestures

            files = write_textgrids_with_gestures(manifold, table, folder, lab.gestures, names=grids)
        elif folder is not None:
            files = write_textgrids(manifold, table, folder, names=grids)
        lab.write(manifold, source=str(args.manifold))
    if out is not None:
        print(f"wrote {out} ({table.n_rows} rows x {len(table.columns)} columns: one per frame of "
              f"{len(c.utterances)} utterances); units and column meanings in {side}")
    if grids is not None:
        extra = "".join(f", {tier}" for tier in lab.tier_names())
        print(f"wrote {len(files)} TextGrids to {args.textgrid_dir} (tiers: phones, class, landmarks{extra})")
    lab.report()
    return 0
