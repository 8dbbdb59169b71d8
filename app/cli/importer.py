"""``lipspace import``: foreign corpus formats -> the native corpus file (.npz).

The command: its options, checks and the corpus it writes; reading the inputs (one process, a pool
or Dask) is :mod:`app.cli.import_reading`.
"""
from __future__ import annotations

import contextlib
import sys
from dataclasses import replace
from pathlib import Path

from app.cli.import_lab import (
    add_lab_arguments,
    apply_quality_policy,
    check_fields,
    expand_folder_inputs,
    quality_policy,
)
from app.cli.import_reading import has_audio, read_group, read_many
from app.cli.options import add_quiet_option
from app.files.source_loading import ANALYSIS_RATE

#: which reader option ``--points`` sets, per format
_POINT_OPTION = {"ema": "sensors", "mview": "sensors", "c3d": "markers", "csv": "points", "matrix": "points",
                 "pos": "points", "wave": "points"}


#: highest --resample rate in Hz
MAX_RATE = 2000.0


def add_arguments(p):
    from engine.io.dispatch import FORMAT_ALIASES, FORMATS

    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="data file(s) or folder(s): .ema .mat .c3d .csv .npy .npz .pos ...; a folder's recordings "
                        "are read in natural order, one utterance each (a folder or glob of .obj/.ply frames is one "
                        "utterance, a folder of videos one clip each)")
    p.add_argument("-o", "--output", required=True, help="native corpus file to write (.npz)")
    p.add_argument("--format", choices=sorted(FORMATS) + sorted(FORMAT_ALIASES), default=None,
                   help="input format (default: from the extension or the file's first bytes)")
    p.add_argument("--alignment", default=None, metavar="LAB_OR_TEXTGRID",
                   help="phone alignment for a single input (default: the file's own phones or <stem>.TextGrid / "
                        "<stem>.lab beside it; 'none' for no phones)")
    p.add_argument("--tier", default=None, help="TextGrid tier holding the phones (default: 'phones' or similar)")
    p.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="frame rate of inputs without timing (mesh frames, .npy, CSV without a time column)")
    p.add_argument("--resample", "--analysis-rate", dest="resample", default=None, metavar="HZ",
                   help="analysis frame rate: the result is resampled to it with an anti-aliasing filter, per "
                        f"utterance (default: {ANALYSIS_RATE:g} Hz, the paper's rate, the rate the manifold's "
                        "velocities and classes are read at; 'native' keeps the file's rate)")
    p.add_argument("--points", default=None, metavar="LIST",
                   help="comma-separated sensors / markers / landmarks to keep, or 'all' (EMA, MVIEW, layouts) or "
                        "'lips' (OpenFace, layouts); default: lips and jaw for EMA, lip, jaw and reference "
                        "sensors with a layout, every point otherwise")
    p.add_argument("--layout", default=None, metavar="NAME_OR_FILE",
                   help="read a plain numeric matrix (.mat variable, .npy, CSV/TSV without names, .pos, NDI Wave "
                        "TSV) through a sensor layout: ema7x6, ema7x7, ag500, ag501, wave, or a layout file "
                        "(see docs/USER_GUIDE.md, 'Real recordings')")
    p.add_argument("--variable", default=None, metavar="NAME", help="with --layout: the .mat variable to read")
    p.add_argument("--roles", default=None, metavar="ROLE=P,P;...",
                   help="set point roles by name or 0-based index, e.g. 'upper_lip=UL;lower_lip=LL' or, for a mesh's "
                        "lip contours, 'upper_lip=812,813;lower_lip=1402' (roles: upper_lip, lower_lip, left_corner, "
                        "right_corner, lip, jaw, reference, tongue, other)")
    p.add_argument("--register", default="auto", choices=("auto", "rigid", "utterance", "speaker", "none"),
                   help="remove head motion / recording offsets: rigid (Procrustes to the layout's reference "
                        "sensors), utterance or speaker centring, none; auto = rigid with 3+ reference sensors, "
                        "else utterance centring for several inputs (default: %(default)s)")
    p.add_argument("--axes", default=None, metavar="x=DIR,y=DIR,z=DIR",
                   help="the talker's direction of each coordinate axis (DIR: forward/back, left/right, up/down), "
                        "e.g. 'x=forward,y=left,z=up' (2-D: 'x=forward,y=up'), for the lip view, the lip-shape "
                        "figures and the MP4 / glTF exports; default: derived from the point roles (upper lip "
                        "above lower lip, corners left and right); 'lipspace info' says which")
    spk = p.add_mutually_exclusive_group()
    spk.add_argument("--speaker", default=None, metavar="NAME", help="speaker of every input")
    spk.add_argument("--speaker-from", default=None, metavar="dir|prefix|re:PATTERN",
                     help="speaker of each input: 'dir' its folder's name (as given, symlinks not followed), "
                          "'prefix' its file name up to the first '_', or 're:PATTERN' the one group of a regular "
                          "expression searched in the file name, e.g. 're:^(spk[0-9]+)' or 're:^([A-Z]{3})'; "
                          "corpus files (.npz) joined keep their own speakers")
    add_lab_arguments(p)  # --recursive, --fields-from, --metadata, --quality ... (app.cli.import_lab)
    p.add_argument("--template", default=None, metavar="MESH", help="template OBJ/PLY giving faces for .npy input")
    p.add_argument("--audio-dir", default=None, metavar="DIR",
                   help="MVIEW .mat input: where each file's AUDIO goes as <stem>.wav, linked to its utterance; "
                        "video input: where each utterance's audio track goes (default for both: <output "
                        "stem>_audio/ beside the output)")
    p.add_argument("--interocular-mm", type=float, default=None, metavar="MM",
                   help="video input: assumed distance between the eye centres, which sets the mm scale "
                        "(default: 63, the mean adult interpupillary distance)")
    p.add_argument("--no-fill", action="store_true",
                   help="fail on dropouts (invalid or missing samples) instead of interpolating them (every "
                        "interpolation is listed in the corpus history: lipspace info)")
    p.add_argument("--skip-bad", action="store_true",
                   help="with several inputs: write the corpus without the inputs that cannot be read, saying how "
                        "many (default: an unreadable input stops the import and nothing is written)")
    p.add_argument("--name", default=None, help="corpus name (default: from the input)")
    p.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help="with several inputs: read them in N processes (default: one per core; 1 reads them here)")
    p.add_argument("--dask", metavar="local|ADDRESS", default=None,
                   help="with several inputs: read them on Dask workers, 'local' (one per core) or a running "
                        "scheduler's address; the files must be readable by every worker")
    add_quiet_option(p, what="no progress bar")
    p.add_argument("--block-frames", type=int, default=None, metavar="N",
                   help="store the frames in blocks of N frames (.npy files in OUT.blocks/ beside OUT.npz) that "
                        "Dask workers read in place during 'lipspace build --dask' (default: inside OUT.npz)")


def _options(args, fmt):
    kw = {}
    if args.tier is not None:
        kw["tier"] = args.tier
    if args.no_fill and fmt != "npz":
        kw["fill_gaps"] = False
    if args.template is not None:
        kw["template"] = args.template
    if args.layout is not None:
        kw["layout"] = args.layout
    if args.variable is not None:
        if args.layout is None:
            from app.cli import CliError

            raise CliError("--variable needs --layout (it names the .mat variable holding a plain matrix)")
        kw["variable"] = args.variable
    if fmt == "video":  # FaceMesh tracking (engine.io.video.clips); audio beside the output
        if args.interocular_mm is not None:
            kw["interocular_mm"] = args.interocular_mm
        out = Path(args.output)
        kw["audio_dir"] = args.audio_dir or str(out.with_name(out.stem + "_audio"))
        if args.skip_bad:  # a folder's damaged video is left out and said, as an unreadable input is
            kw["skip_bad"] = True
    elif args.interocular_mm is not None:
        from app.cli import CliError

        raise CliError(f"--interocular-mm applies to video input only, not to {fmt!r} input")
    if args.points is not None:
        opt = _POINT_OPTION.get(fmt)
        if opt is None:
            from app.cli import CliError

            raise CliError(f"--points does not apply to {fmt!r} input")
        pts = args.points.strip()
        kw[opt] = pts if pts in ("all", "lips") else [s.strip() for s in pts.split(",") if s.strip()]
    return kw


def summary(corpus) -> str:
    """One line: frames, points, rate, utterances, speakers, phones."""
    n_ph = sum(len(u.phones) for u in corpus.utterances)
    spk = [s for s in corpus.speakers if s]
    spk_txt = f"{len(spk)} speaker{'s' * (len(spk) != 1)}, " if spk else ""
    labels = {p.label for u in corpus.utterances for p in u.phones}
    return (f"{corpus.n_frames} frames, {corpus.n_points} point{'s' * (corpus.n_points != 1)} ({corpus.dims}-D), "
            f"{corpus.rate:g} Hz, "
            f"{len(corpus.utterances)} utterance{'s' * (len(corpus.utterances) != 1)}, {spk_txt}"
            f"{n_ph} phones ({len(labels)} labels), {corpus.duration:.2f} s")


def run(args) -> int:
    from app.cli import CliError
    from engine.io import ImportFormatError, concat, resample
    from engine.io.dispatch import FORMAT_ALIASES, detect_format
    from engine.recordings.corpus import CorpusError
    from engine.recordings.registration import register

    out = Path(args.output)
    if out.suffix != ".npz":
        raise CliError(f"{out}: the corpus file must end in .npz")
    if args.block_frames is not None and args.block_frames < 256:
        raise CliError(f"--block-frames {args.block_frames}: must be at least 256 frames per block")
    _check_numbers(args)
    inputs, folders = expand_folder_inputs(args)
    args.inputs = inputs
    rate_out = None
    video = _is_video(args)
    if args.resample is None:  # every input, video too, goes to the paper's 60 Hz (docs/DECISIONS.md)
        args.resample = f"{ANALYSIS_RATE:g}"
    if str(args.resample).lower() not in ("native", "none"):
        try:
            rate_out = float(args.resample)
        except ValueError:
            raise CliError(f"--resample {args.resample!r}: expected a rate in Hz or 'native'") from None
        if not 0 < rate_out <= MAX_RATE:  # 1e9 Hz asked for a 14 GiB index array
            raise CliError(f"--resample {args.resample}: must be above 0 and at most {MAX_RATE:g} Hz "
                           "(the fastest articulographs record at 1250 Hz)")
    if video and rate_out is None:  # --resample native: videos at different rates cannot be joined
        rates = _video_rates(inputs)
        if len({round(r, 6) for _, r in rates}) > 1:
            desc = ", ".join(f"{Path(p).name} {r:.4g} Hz" for p, r in rates)
            raise CliError(f"the videos have different frame rates ({desc}); they can be joined only at one "
                           f"rate: give --resample {ANALYSIS_RATE:g} (the analysis rate, the default without "
                           "--resample) or another rate")
    try:
        fmt = args.format or ("matrix" if args.layout is not None else detect_format(inputs[0]))
        fmt = FORMAT_ALIASES.get(fmt, fmt)
        if args.layout is not None and fmt not in ("matrix", "pos", "wave"):
            raise CliError(f"--layout applies to plain matrices, .pos and NDI Wave files, not to {fmt!r} input")
        alignment = args.alignment
        if alignment is not None and alignment.lower() == "none":
            alignment = False
        if isinstance(alignment, str) and (len(inputs) > 1 and fmt != "mesh"):
            raise CliError(f"--alignment names one file but {len(inputs)} inputs were given; put each input's "
                           "<stem>.TextGrid or <stem>.lab beside it instead")
        kw = _options(args, fmt)
        if fmt == "video" and rate_out is not None:  # each video (of a folder too) at that rate before joining
            kw["resample"] = rate_out
        sequences = fmt == "mesh" and len(inputs) > 1 and not all(Path(p).is_dir() for p in inputs)
        groups = [inputs] if sequences else [[p] for p in inputs]  # frame files: one sequence; folders: one each
        warned = _check_speakers(groups, args, fmt)
        fields = check_fields(groups, args, fmt, folders, quiet_hint=warned)
        policy = quality_policy(args)
    except (ImportFormatError, CorpusError, FileNotFoundError, ValueError, TypeError) as exc:
        raise CliError(str(exc)) from None
    from app.cli._common import command_outputs

    with command_outputs(args) as outputs:  # the corpus, its blocks and its audio: all or none
        staged = outputs.file(out, option="-o")
        report = outputs.file(args.quality_report, option="--quality-report") if args.quality_report else None
        blocks = None
        if args.block_frames is not None:
            from engine.recordings.corpus_blocks import blocks_folder

            blocks = outputs.folder(blocks_folder(out), pattern="block_*.npy", exclusive=True, option="-o")
        audio_dir, audio_stage = _stage_audio(args, fmt, kw, outputs)
        job = {"format": fmt, "rate": args.rate, "alignment": alignment, "options": kw,
               "audio_dir": None if audio_stage is None else str(audio_stage), "speaker": args.speaker,
               "speaker_from": args.speaker_from, "fields": fields, "ids": folders.ids,
               # corpus files joined: each one's unnamed utterances are its own speaker, named after the file
               "name_corpora": fmt == "npz" and len(groups) > 1 and not (args.speaker or args.speaker_from)}
        try:
            if len(groups) == 1 and fmt == "video":  # tracking a face takes a while: show it
                from app.cli._common import progress_bar

                with progress_bar(disable=True if args.quiet else None) as progress:
                    parts = [read_group(groups[0], {**job, "options": {**kw, "progress": progress}})]
            elif len(groups) == 1:
                parts = [read_group(groups[0], job)]
            else:
                parts = read_many(groups, job, args)
            parts, quality_notes, quality_rows = apply_quality_policy(parts, policy)
            parts = _one_rate(parts, rate_out)
            corpus = parts[0] if len(parts) == 1 else concat(parts)
            corpus.history = list(corpus.history) + [n for n in quality_notes if n not in corpus.history]
            if audio_stage is not None:  # the audio goes where the corpus says it is once moved in
                corpus = _moved_audio(corpus, audio_stage, audio_dir)
            if args.roles is not None:
                from engine.recordings.layouts import roles_from_spec

                corpus = replace(corpus, point_roles=roles_from_spec(args.roles, corpus.n_points,
                                                                     corpus.point_names, corpus.point_roles))
            if args.axes is not None:
                from engine.recordings.orientation import AxesError, parse_axes

                try:
                    corpus = replace(corpus, axes=parse_axes(args.axes, corpus.dims).spec())
                except AxesError as exc:
                    raise CliError(str(exc)) from None
            corpus = register(corpus, method=args.register)
            if rate_out is not None and abs(rate_out - corpus.rate) > 1e-9 * corpus.rate:
                corpus = resample(corpus, rate_out)
            if args.name:
                corpus = replace(corpus, name=args.name)
        except (ImportFormatError, CorpusError, FileNotFoundError, ValueError, TypeError) as exc:
            raise CliError(str(exc)) from None
        if report is not None:
            from engine.io.writers.export import write_table_csv
            from engine.recordings.signals.quality import QUALITY_COLUMNS

            write_table_csv(report, quality_rows, columns=QUALITY_COLUMNS)
        if blocks is None:
            corpus.save(staged)
        else:
            from engine.recordings.corpus_blocks import save_blocked

            try:
                block_files = save_blocked(corpus, staged, block_frames=args.block_frames, folder=blocks)
            except ValueError as exc:
                raise CliError(f"--block-frames {args.block_frames}: {exc}") from None
    if blocks is not None:
        from engine.recordings.corpus_blocks import blocks_folder

        print(f"lipspace import: frames in {len(block_files)} blocks in {blocks_folder(out)}", file=sys.stderr)
    # what was done to the data, on stderr (stdout keeps the one summary line)
    for note in corpus.history:
        if not note.startswith("read "):
            print(f"lipspace import: {note}", file=sys.stderr)
    if corpus.point_roles is not None:
        from app.cli._common import roles_text

        print("lipspace import: roles " + roles_text(corpus.point_names, corpus.point_roles), file=sys.stderr)
    from engine.recordings.orientation import anatomical_frame

    print(f"lipspace import: orientation {anatomical_frame(corpus).describe()}", file=sys.stderr)
    if not corpus.registration:
        print("lipspace import: registration: none (no reference sensors and one utterance, or --register none)",
              file=sys.stderr)
    print(f"wrote {out}: {summary(corpus)}", file=sys.stdout)
    return 0


def _check_numbers(args) -> None:
    """Refuse --rate and --interocular-mm values no recording can have, naming the option."""
    import math

    from app.cli import CliError
    from engine.io import MOTION_RATE_RANGE

    lo, hi = MOTION_RATE_RANGE
    if args.rate is not None and not (math.isfinite(args.rate) and lo <= args.rate <= hi):
        raise CliError(f"--rate {args.rate:g}: a frame rate of lip motion is from {lo:g} to {hi:g} Hz")
    mm = args.interocular_mm
    if mm is not None and not (math.isfinite(mm) and 20 <= mm <= 150):
        raise CliError(f"--interocular-mm {mm:g}: an adult's distance between the eye centres is 50-75 mm; give "
                       "one from 20 to 150")


def _stage_audio(args, fmt, kw, outputs):
    """(the audio folder the corpus will name, the staging folder the readers write to) or (None, None).

    MVIEW .mat input writes each file's AUDIO, video input each utterance's audio track, into
    ``--audio-dir`` (default ``<output stem>_audio/``). A WAV already there is refused unless
    ``--force`` (before anything is read when the names are known)."""
    if fmt == "mview" and (args.audio_dir or any(has_audio(p) for p in args.inputs if Path(p).is_file())):
        out = Path(args.output)
        final = Path(args.audio_dir or out.with_name(out.stem + "_audio"))
        names = [Path(p).stem + ".wav" for p in args.inputs]
    elif fmt == "video":
        final, names = Path(kw["audio_dir"]), None
    else:
        return None, None
    stage = outputs.folder(final, pattern="*.wav", names=names, option="--audio-dir")
    if fmt == "video":
        kw["audio_dir"] = str(stage)
    return final, stage


def _moved_audio(corpus, stage: Path, final: Path):
    """``corpus`` with audio paths in the staging folder pointing where the files will be."""
    def moved(a):
        if not a:
            return a
        p = Path(a)
        for q in (stage, stage.resolve()):
            with contextlib.suppress(ValueError):
                return str((final.resolve() if p.is_absolute() else final) / p.relative_to(q))
        return a

    return replace(corpus, utterances=[replace(u, audio=moved(u.audio)) for u in corpus.utterances])


def _is_video(args) -> bool:
    from engine.io.dispatch import FORMAT_ALIASES, detect_format

    if args.format is not None or args.layout is not None:
        return FORMAT_ALIASES.get(args.format, args.format) == "video"
    try:
        return detect_format(args.inputs[0]) == "video"
    except (ValueError, OSError):
        return False


def _video_rates(inputs) -> list:
    """``(path, rate)`` of every video the inputs name (a folder's videos in order); unreadable ones left out
    (their reader reports them)."""
    from engine.io.dispatch import _videos_in
    from engine.io.video.clips import video_info

    out = []
    for p in inputs:
        for v in (_videos_in(p) if Path(p).is_dir() else [Path(p)]):
            try:
                out.append((str(v), video_info(v)[0]))
            except (ValueError, OSError, ImportError):
                continue
    return out


def _one_rate(parts, rate_out):
    """The inputs' corpora at one frame rate: each resampled to ``rate_out`` when their rates differ
    (resampling is per utterance, so nothing crosses two inputs); different rates and no ``rate_out``
    is an error naming them."""
    from app.cli import CliError
    from engine.io import resample

    rates = {}
    for c in parts:
        rates.setdefault(round(c.rate, 6), []).append(c.name)
    if len(rates) < 2:
        return parts
    desc = ", ".join(f"{r:.4g} Hz ({len(names)} input{'s' * (len(names) != 1)}, e.g. {names[0]})"
                     for r, names in rates.items())
    if rate_out is None:
        raise CliError(f"the inputs have different frame rates: {desc}; they can be joined only at one rate: give "
                       f"--resample {ANALYSIS_RATE:g} (the analysis rate) or another rate")
    return [resample(c, rate_out) for c in parts]



def _check_speakers(groups, args, fmt) -> bool:
    """Refuse a speaker rule that does not apply to every input, before any is read; warn when the
    speakers it gives (or the lack of one) do not fit the file names
    (:func:`engine.recordings.speakers.check_assignment`)."""
    import warnings

    from app.cli import CliError
    from engine.recordings.speakers import SpeakerRule, SpeakerRuleError, SpeakerWarning, check_assignment

    if fmt == "npz" and not args.speaker_from:
        return False  # corpus files carry their own speakers
    try:
        rule = SpeakerRule(args.speaker_from) if args.speaker_from else None
        speakers = [rule(g[0]) if rule else (args.speaker or "") for g in groups]
    except SpeakerRuleError as exc:
        raise CliError(str(exc)) from None
    if args.speaker or args.fields_from or args.metadata:
        return False  # told, or the fields name the speaker (checked with them)
    msgs = check_assignment([g[0] for g in groups], speakers, rule=args.speaker_from)
    for msg in msgs:
        warnings.warn(SpeakerWarning(msg), stacklevel=2)
    return bool(msgs)

