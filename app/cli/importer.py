"""``lipspace import``: foreign corpus formats -> the native corpus file (.npz)."""
from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

#: which reader option ``--points`` sets, per format
_POINT_OPTION = {"ema": "sensors", "mview": "sensors", "c3d": "markers", "csv": "points"}


def add_arguments(p):
    from engine.io.dispatch import FORMAT_ALIASES, FORMATS

    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="data file(s): .ema .mat .c3d .csv .npy .npz, a directory or glob of .obj/.ply frames; "
                        "several files become one utterance each")
    p.add_argument("-o", "--output", required=True, help="native corpus file to write (.npz)")
    p.add_argument("--format", choices=sorted(FORMATS) + sorted(FORMAT_ALIASES), default=None,
                   help="input format (default: from the extension or the file's first bytes)")
    p.add_argument("--alignment", default=None, metavar="LAB_OR_TEXTGRID",
                   help="phone alignment for a single input (default: the file's own phones or <stem>.TextGrid / "
                        "<stem>.lab beside it; 'none' for no phones)")
    p.add_argument("--tier", default=None, help="TextGrid tier holding the phones (default: 'phones' or similar)")
    p.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="frame rate of inputs without timing (mesh frames, .npy, CSV without a time column)")
    p.add_argument("--resample", type=float, default=None, metavar="HZ",
                   help="resample the result to this frame rate (anti-aliased, per utterance)")
    p.add_argument("--points", default=None, metavar="LIST",
                   help="comma-separated sensors / markers / landmarks to keep, or 'all' (EMA, MVIEW) or 'lips' "
                        "(OpenFace); default: lips and jaw for EMA, every point otherwise")
    p.add_argument("--template", default=None, metavar="MESH", help="template OBJ/PLY giving faces for .npy input")
    p.add_argument("--audio-dir", default=None, metavar="DIR",
                   help="MVIEW .mat input: write each file's AUDIO to DIR/<stem>.wav and link it")
    p.add_argument("--no-fill", action="store_true",
                   help="fail on dropouts (invalid or missing samples) instead of interpolating them")
    p.add_argument("--name", default=None, help="corpus name (default: from the input)")


def _options(args, fmt):
    kw = {}
    if args.tier is not None:
        kw["tier"] = args.tier
    if args.no_fill and fmt != "npz":
        kw["fill_gaps"] = False
    if args.template is not None:
        kw["template"] = args.template
    if args.points is not None:
        opt = _POINT_OPTION.get(fmt)
        if opt is None:
            from app.cli import CliError

            raise CliError(f"--points does not apply to {fmt!r} input")
        pts = args.points.strip()
        kw[opt] = pts if pts in ("all", "lips") else [s.strip() for s in pts.split(",") if s.strip()]
    return kw


def summary(corpus) -> str:
    """One line: frames, points, rate, utterances, phones."""
    n_ph = sum(len(u.phones) for u in corpus.utterances)
    labels = {p.label for u in corpus.utterances for p in u.phones}
    return (f"{corpus.n_frames} frames, {corpus.n_points} point{'s' * (corpus.n_points != 1)} ({corpus.dims}-D), "
            f"{corpus.rate:g} Hz, "
            f"{len(corpus.utterances)} utterance{'s' * (len(corpus.utterances) != 1)}, "
            f"{n_ph} phones ({len(labels)} labels), {corpus.duration:.2f} s")


def run(args) -> int:
    from app.cli import CliError
    from engine.corpus import CorpusError
    from engine.io import ImportFormatError, concat, read_corpus, resample, write_audio
    from engine.io.dispatch import FORMAT_ALIASES, detect_format

    out = Path(args.output)
    if out.suffix != ".npz":
        raise CliError(f"{out}: the corpus file must end in .npz")
    inputs = args.inputs
    try:
        fmt = args.format or detect_format(inputs[0])
        fmt = FORMAT_ALIASES.get(fmt, fmt)
        alignment = args.alignment
        if alignment is not None and alignment.lower() == "none":
            alignment = False
        if isinstance(alignment, str) and (len(inputs) > 1 and fmt != "mesh"):
            raise CliError(f"--alignment names one file but {len(inputs)} inputs were given; put each input's "
                           "<stem>.TextGrid or <stem>.lab beside it instead")
        kw = _options(args, fmt)
        groups = [inputs] if fmt == "mesh" and len(inputs) > 1 else [[p] for p in inputs]
        parts = []
        for g in groups:
            src = g if len(g) > 1 else g[0]
            c = read_corpus(src, format=fmt, rate=args.rate, alignment=alignment, **kw)
            if args.audio_dir and fmt == "mview":
                wav = write_audio(src, Path(args.audio_dir) / (Path(src).stem + ".wav"))
                c = replace(c, utterances=[replace(u, audio=str(wav)) for u in c.utterances])
            parts.append(c)
        corpus = parts[0] if len(parts) == 1 else concat(parts)
        if args.resample is not None:
            corpus = resample(corpus, args.resample)
        if args.name:
            corpus = replace(corpus, name=args.name)
    except (ImportFormatError, CorpusError, FileNotFoundError, ValueError, TypeError) as exc:
        raise CliError(str(exc)) from None
    corpus.save(out)
    print(f"wrote {out}: {summary(corpus)}", file=sys.stdout)
    return 0
