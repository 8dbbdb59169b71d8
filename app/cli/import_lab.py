"""What ``lipspace import`` does for a lab's folder: folders as inputs, per-utterance metadata fields, sensor quality.

Kept apart from :mod:`app.cli.importer` (which reads and joins the inputs): these options
are read here, checked before anything is read, and applied to the inputs' corpora.
"""
from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["add_lab_arguments", "expand_folder_inputs", "check_fields", "quality_policy", "apply_quality_policy"]


def add_lab_arguments(p):
    """The options of this module on the ``import`` parser."""
    p.add_argument("-r", "--recursive", action="store_true",
                   help="read the subfolders of a folder too (its recordings then keep their folder in their id "
                        "when two share a name)")
    p.add_argument("--fields-from", default=None, metavar="re:PATTERN",
                   help="per-utterance metadata from each file name (its stem): every named group of the regular "
                        "expression is a field, e.g. 're:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})"
                        "(?P<text>[0-9]+)$'; a group named 'speaker' names the speaker")
    p.add_argument("--metadata", default=None, metavar="TABLE.csv",
                   help="per-utterance metadata from a table (CSV, ';' or tab separated), one row per recording "
                        "keyed by its file name, one column per field (speaker, sex, group ...)")
    p.add_argument("--metadata-key", default=None, metavar="COLUMN",
                   help="the --metadata column holding the file names (default: file, filename, recording, "
                        "utterance, name or id, else the first)")
    p.add_argument("--quality", choices=("keep", "mask", "drop"), default="keep",
                   help="what to do about samples whose sensor quality value (the AG500/AG501 rms, an NDI Wave "
                        "error column) is above --quality-threshold: keep them (default; reported), mask them "
                        "(interpolate runs up to --quality-max-gap; longer runs kept and named) or drop the "
                        "utterances with longer runs")
    p.add_argument("--quality-threshold", type=float, default=None, metavar="VALUE",
                   help="quality values above this are suspect (default: 3 x the median quality value of the "
                        "inputs)")
    p.add_argument("--quality-max-gap", type=float, default=50.0, metavar="MS",
                   help="longest run of suspect samples --quality mask / drop interpolates (default: %(default)g ms)")
    p.add_argument("--quality-report", default=None, metavar="REPORT.csv",
                   help="write the sensor quality per sensor and utterance (median, share above the threshold, "
                        "longest run, what was done) as a CSV table")


def expand_folder_inputs(args):
    """The inputs with every folder replaced by its recordings (:func:`engine.io.folders.expand_folders`), and
    what was found; what each folder gave and left out is said on stderr."""
    from app.cli import CliError
    from engine.io import ImportFormatError
    from engine.io.dispatch import FORMAT_ALIASES
    from engine.io.folders import expand_folders

    fmt = FORMAT_ALIASES.get(args.format, args.format) if args.format else ("matrix" if args.layout else None)
    try:
        found = expand_folders(args.inputs, format=fmt, recursive=args.recursive)
    except ImportFormatError as exc:
        raise CliError(str(exc)) from None
    for note in found.notes:
        print(f"lipspace import: folder {note}", file=sys.stderr)
    if not found.paths:
        raise CliError("no recordings found in the inputs; nothing was written")
    return found.paths, found


def check_fields(groups, args, fmt, folders, *, quiet_hint: bool) -> dict:
    """``{input: {field: value}}`` from --fields-from / --metadata, checked before anything is read; a note
    suggesting a pattern when neither is given and the names follow one scheme."""
    import warnings

    from app.cli import CliError
    from engine.recordings.metadata import MetadataWarning
    from engine.recordings.metadata_sources import assign_fields

    paths = [g[0] for g in groups]
    if not (args.fields_from or args.metadata):
        if args.metadata_key:
            raise CliError("--metadata-key names a column of the --metadata table; give --metadata TABLE.csv")
        if not quiet_hint and fmt != "npz" and len(paths) >= 3:
            from engine.recordings.speakers import suggest_fields

            hint = suggest_fields(paths)
            if hint:
                print(f"lipspace import: note: {hint}", file=sys.stderr)
        return {}
    roots = {Path(r) for r in folders.roots.values()}
    root = roots.pop() if len(roots) == 1 else None
    table = None
    if args.metadata:
        from engine.recordings.metadata_sources import read_metadata_table

        table = read_metadata_table(args.metadata, key=args.metadata_key)
    fields, notes = assign_fields(paths, pattern=args.fields_from, table=table, root=root)
    told = "--speaker" if args.speaker else "--speaker-from" if args.speaker_from else None
    if told and any(f.get("speaker") for f in fields.values()):
        raise CliError(f"{told} and a 'speaker' field ({'--fields-from' if args.fields_from else '--metadata'}) "
                       "both name the speakers; give one of them")
    for note in notes:
        warnings.warn(MetadataWarning(note), stacklevel=2)
    return {p: f for p, f in fields.items() if f}


def quality_policy(args):
    """The --quality options as a :class:`engine.recordings.signals.quality.QualityPolicy`."""
    from engine.recordings.signals.quality import QualityPolicy

    return QualityPolicy(threshold=args.quality_threshold, action=args.quality,
                         max_gap_s=float(args.quality_max_gap) / 1000.0)


def apply_quality_policy(parts, policy):
    """Each input's sensor quality reported and acted on (:mod:`engine.recordings.signals.quality`), one threshold
    for all: ``(parts kept, history lines, report rows)``."""
    from app.cli import CliError
    from engine.recordings.signals.quality import action_line, apply_quality, resolve_threshold, summary_lines

    threshold, how = resolve_threshold(parts, policy)
    if threshold is None:
        if policy.action != "keep" or policy.threshold is not None:
            raise CliError(f"--quality {policy.action} / --quality-threshold: the inputs hold no sensor quality "
                           "values (AG500/AG501 .pos rms, an NDI Wave error column, a layout's 'quality' value); "
                           "nothing was written")
        return parts, [], []
    results = [apply_quality(c, threshold, policy) for c in parts]
    rows = [r for res in results for r in res.rows]
    speakers = {u.id: u.speaker for c in parts for u in c.utterances}
    notes = summary_lines(rows, threshold, how, speakers=speakers)
    notes.append(action_line(results, threshold, policy, rate=parts[0].rate))
    kept = [res.corpus for res in results if res.corpus is not None]
    if not kept:
        dropped = [u for res in results for u in res.dropped]
        raise CliError(f"--quality drop left no utterance ({len(dropped)} dropped: {', '.join(dropped[:3])} ...); "
                       "nothing was written. Raise --quality-threshold or --quality-max-gap, or use --quality mask")
    return kept, notes, rows
