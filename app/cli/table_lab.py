"""What ``lipspace table`` writes for an articulograph lab: metadata fields, derived tracks, gestural landmarks.

``--tracks`` adds derived tracks (:mod:`engine.recordings.signals.tracks`) as columns of
the per-frame table, ``--gestures`` finds gestural landmarks on tracks
(:mod:`engine.recordings.signals.gestures`) for ``--gesture-table`` (one row per gesture)
and a point tier per track in the ``--textgrid`` files. Metadata fields are columns
whenever the corpus has them. Kept apart from :mod:`app.cli.table`, which writes the
per-frame table and the TextGrids.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["add_lab_arguments", "lab_tables", "lab_columns", "list_tracks", "LabOutputs"]


def add_lab_arguments(p):
    """The options of this module on the ``table`` parser."""
    p.add_argument("--tracks", default=None, metavar="NAME,NAME",
                   help="derived tracks to add as columns: lip_protrusion, speed_<SENSOR> (tangential velocity), "
                        "<SENSOR>_forward / _up / _left, rms_<SENSOR> ... ('list' lists what the manifold's corpus "
                        "has)")
    p.add_argument("--lowpass", default="15", metavar="HZ|none",
                   help="cut-off of the zero-phase Butterworth low-pass applied to the positions before tracks and "
                        "gestures are derived (default: %(default)s Hz; 'none' keeps them raw)")
    p.add_argument("--gestures", default=None, metavar="TRACK,TRACK",
                   help="find gestural landmarks (onset, peak velocities, nucleus, maximum constriction, offset) "
                        "on these tracks, e.g. lip_aperture; written by --gesture-table and as TextGrid tiers")
    p.add_argument("--gesture-table", default=None, metavar="GESTURES.csv",
                   help="write one row per gesture (landmark times, durations, peak velocities, the manifold state "
                        "at each landmark) as CSV or Parquet, units in GESTURES.csv.json")
    p.add_argument("--gesture-target", choices=("auto", "min", "max"), default="auto",
                   help="whether a gesture moves the track to a minimum or a maximum (auto: minimum for "
                        "lip_aperture, maximum for lip_protrusion)")
    p.add_argument("--gesture-threshold", type=float, default=0.2, metavar="SHARE",
                   help="share of each peak speed marking gesture and nucleus onsets and offsets (default: "
                        "%(default)g)")


@dataclass
class LabOutputs:
    """The tracks and gesture sets asked for, and the staged gesture table."""

    tracks: list = field(default_factory=list)
    gestures: list = field(default_factory=list)
    gesture_file: tuple | None = None  # (staged table, staged sidecar, the path asked for)
    written: list = field(default_factory=list)

    def tier_names(self) -> list[str]:
        from engine.manifold.lab_tables import tier_name

        return [tier_name(g) for g in self.gestures]

    def write(self, manifold, *, source: str = "") -> None:
        if self.gesture_file is None:
            return
        from engine.io.writers.tidy import write_frame_table
        from engine.manifold.lab_tables import gesture_table

        table, side, path = self.gesture_file
        t = gesture_table(manifold, self.gestures, source=source)
        write_frame_table(table, t, sidecar=side, name=Path(path).name)
        self.written.append(f"wrote {path} ({t.n_rows} rows: one per gesture of "
                            f"{', '.join(g.track for g in self.gestures)}); units and column meanings in {path}.json")

    def report(self) -> None:
        for line in self.written:
            print(line)


def _lowpass(args):
    from app.cli import CliError

    v = str(args.lowpass).strip().lower()
    if v in ("none", "0", "off"):
        return None
    try:
        return float(v)
    except ValueError:
        raise CliError(f"--lowpass {args.lowpass!r}: expected a cut-off in Hz or 'none'") from None


def _names(text) -> list[str]:
    return [n.strip() for n in str(text).split(",") if n.strip()]


def lab_tables(args, manifold, outputs) -> LabOutputs:
    """Check and compute what ``--tracks`` / ``--gestures`` ask for, staging ``--gesture-table``; CliError naming the
    option, the track and what the corpus can give."""
    from app.cli import CliError
    from engine.recordings.signals.filters import check_cutoff
    from engine.recordings.signals.gestures import find_gestures
    from engine.recordings.signals.tracks import available_tracks, derived_track

    c = manifold.corpus_
    lab = LabOutputs()
    hz = _lowpass(args)
    if args.gesture_table is not None and not args.gestures:
        raise CliError("--gesture-table needs --gestures TRACK (e.g. --gestures lip_aperture)")
    if args.gestures and args.gesture_table is None and args.textgrid_dir is None:
        raise CliError("--gestures: give --gesture-table GESTURES.csv and/or --textgrid DIR to write them")
    if not 0 < args.gesture_threshold < 1:
        raise CliError(f"--gesture-threshold {args.gesture_threshold:g}: a share of the peak speed, above 0 and "
                       "below 1 (0.2 is usual)")
    try:
        if hz is not None:
            check_cutoff(hz, c.rate)
    except ValueError as exc:
        raise CliError(f"--lowpass: {exc}") from None
    have = available_tracks(c)
    for opt, names in (("--tracks", _names(args.tracks or "")), ("--gestures", _names(args.gestures or ""))):
        for n in names:
            if n not in have:
                raise CliError(f"{opt} {n}: {c.name} has no such track; it has {', '.join(have[:14])}"
                               f"{' ...' if len(have) > 14 else ''} ('--tracks list' lists them all)")
    if args.gesture_table is not None:
        from engine.io.writers.tidy import TABLE_SUFFIXES, sidecar_path

        g = Path(args.gesture_table)
        if g.suffix.lower() not in TABLE_SUFFIXES:
            raise CliError(f"--gesture-table {g}: the table must end in .csv or .parquet")
        lab.gesture_file = (outputs.file(g, option="--gesture-table"),
                            outputs.file(sidecar_path(g), option="--gesture-table"), str(g))
    if "lip_aperture" in _names(args.tracks or ""):
        print("lipspace table: note: lip_aperture is a column already (unfiltered); --gestures lip_aperture uses "
              "it low-passed", file=sys.stderr)
    try:
        lab.tracks = [derived_track(c, n, lowpass_hz=hz) for n in _names(args.tracks or "")
                      if n != "lip_aperture"]
        lab.gestures = [find_gestures(c, n, target=args.gesture_target, threshold=args.gesture_threshold,
                                      lowpass_hz=hz) for n in _names(args.gestures or "")]
    except ValueError as exc:
        raise CliError(str(exc)) from None
    for g in lab.gestures:
        print(f"lipspace table: {len(g)} gestures of {g.track} (to a {'minimum' if g.target == 'min' else 'maximum'}"
              f", landmarks at {100 * g.threshold:g} % of the peak speeds)", file=sys.stderr)
    return lab


def list_tracks(args, manifold) -> bool:
    """``--tracks list``: print the tracks the manifold's corpus can give, one per line; True when it did."""
    if not (args.tracks and args.tracks.strip() == "list"):
        return False
    from engine.recordings.signals.tracks import available_tracks

    print("\n".join(available_tracks(manifold.corpus_)))
    return True


def lab_columns(table, manifold, lab: LabOutputs):
    """The per-frame table with the metadata fields after ``speaker`` and the derived tracks appended."""
    from app.cli import CliError
    from engine.manifold.lab_tables import with_field_columns, with_track_columns

    try:
        table = with_field_columns(table, manifold.corpus_)
        return with_track_columns(table, lab.tracks) if lab.tracks else table
    except ValueError as exc:
        raise CliError(str(exc)) from None
