"""``lipspace figures``: render the paper's figure set in batch (no display needed)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from app.cli.options import add_quiet_option, add_talker_options

FORMATS = ("png", "svg", "pdf")


#: highest --dpi: a full-page figure at 1200 dpi is already ~60 megapixels
MAX_DPI = 1200


def add_arguments(p):
    p.add_argument("manifold", nargs="?",
                   help="manifold file from 'lipspace build' (a corpus file is fitted first); "
                        "omit to build on the synthetic talker")
    p.add_argument("-o", "--outdir", required=True, help="directory to write the figures into")
    p.add_argument("--format", dest="formats", action="append", choices=FORMATS,
                   help="output format, repeatable (default: png)")
    p.add_argument("--only", default=None,
                   help="comma-separated figure names (default: all): " + ",".join(_names()))
    p.add_argument("--utterance", default=None,
                   help="utterance id for the example trajectory (fig2a) and regenerated utterance (fig3)")
    add_talker_options(p, when="when no file is given")
    p.add_argument("--width", default="180mm", metavar="85mm|180mm",
                   help="figure width for a journal page: 85mm (one column) or 180mm (two columns; default), or "
                        "another length from 40mm to 260mm (also cm or in); each figure lays itself out for it, "
                        "fonts 7-8 pt")
    p.add_argument("--dpi", type=float, default=200, help="PNG resolution (default: %(default)s)")
    p.add_argument("--skip-bad", action="store_true",
                   help="write the figures that could be drawn when others fail, saying how many failed "
                        "(default: a failed figure stops the command and nothing is written)")
    add_quiet_option(p)


def _names():
    from app.figures import FIGURES

    return list(FIGURES)


def _parse_only(only):
    from app.cli import CliError
    from app.figures import FIGURES

    if only is None:
        return list(FIGURES)
    names = [n.strip() for n in only.split(",") if n.strip()]
    bad = [n for n in names if n not in FIGURES]
    if bad or not names:
        raise CliError(f"--only {only!r}: unknown figure(s) {', '.join(bad) or '(none given)'}; "
                       f"choose from {', '.join(FIGURES)}")
    return list(dict.fromkeys(names))


def _load(path, preset, progress):
    """A fitted manifold from a manifold file, a corpus file (fitted here) or the synthetic talker."""
    from app.cli import CliError
    from app.cli._common import load_corpus_arg, load_manifold_arg
    from engine.manifold.model import Manifold

    if path is not None:
        from app.files.source_loading import source_kind

        try:
            kind = source_kind(path)
        except ValueError as exc:
            raise CliError(str(exc)) from None
        if kind == "manifold":
            return load_manifold_arg(path)
    corpus = load_corpus_arg(path, synthetic_preset=preset, progress=progress)
    try:
        return Manifold().fit(corpus, progress=progress)
    except ValueError as exc:
        raise CliError(str(exc)) from None


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import command_outputs, progress_bar
    from app.figures import UTTERANCE_FIGURES, make_figure, save_figure

    names = _parse_only(args.only)
    formats = list(dict.fromkeys(args.formats or ["png"]))
    outdir = Path(args.outdir)
    if not (10 <= args.dpi <= MAX_DPI):  # 100000 dpi asked for terabytes of pixels (and NaN for nothing)
        raise CliError(f"--dpi {args.dpi:g}: must be from 10 to at most {MAX_DPI} (print quality is 300-600)")
    if outdir.exists() and not outdir.is_dir():
        raise CliError(f"{outdir}: exists and is not a directory")
    from app.figures.style import parse_width

    try:
        width = parse_width(args.width)
    except ValueError as exc:
        raise CliError(f"--width: {exc}") from None
    t0 = time.perf_counter()
    written, failed = [], []
    with command_outputs(args) as outputs:  # the whole set or, on any failure or stop, none of it
        staged = outputs.folder(outdir, names=[f"{n}.{fmt}" for n in names for fmt in formats], option="-o")
        with progress_bar(disable=True if args.quiet else None) as progress:
            manifold = _load(args.manifold, args.preset, progress)
            if args.utterance is not None:
                ids = [u.id for u in manifold.corpus_.utterances]
                if args.utterance not in ids:
                    raise CliError(f"--utterance {args.utterance!r}: no such utterance in {manifold.corpus_.name} "
                                   f"(e.g. {', '.join(ids[:5])})")
            skip = _phone_figures_to_skip(manifold)
            total = len(names)
            progress("figures", 0, total)
            for k, name in enumerate(names):
                if name in skip:
                    print(f"lipspace figures: {name} skipped: {skip[name]}", file=sys.stderr)
                    progress("figures", k + 1, total)
                    continue
                opts = {"utterance": args.utterance} if name in UTTERANCE_FIGURES and args.utterance else {}
                opts["width"] = width
                try:
                    fig = make_figure(name, manifold, **opts)
                    done_here = [save_figure(fig, staged / f"{name}.{fmt}", dpi=args.dpi) for fmt in formats]
                    written += [outdir / p.name for p in done_here]
                except (ValueError, ImportError, RuntimeError, LookupError) as exc:
                    failed.append((name, str(exc)))
                    for fmt in formats:  # no half of a figure's formats
                        (staged / f"{name}.{fmt}").unlink(missing_ok=True)
                progress("figures", k + 1, total)
        for name, msg in failed:
            print(f"lipspace figures: {name} failed: {msg}", file=sys.stderr)
        if failed and not args.skip_bad:
            raise CliError(f"{len(failed)} of {len(names)} figures failed (listed above); nothing was written. "
                           "Pass --skip-bad to write the others")
    done = len(names) - len(failed) - len([n for n in names if n in skip])
    skipped = f"; {len(failed)} failed, skipped (--skip-bad)" if failed else ""
    print(f"wrote {len(written)} file(s) to {outdir} ({', '.join(formats)}; {width * 25.4:.0f} mm wide; "
          f"{done}/{len(names)} figures{skipped}) in {time.perf_counter() - t0:.1f} s")
    return 0 if done else 1


def _phone_figures_to_skip(manifold) -> dict:
    """Figures that cannot be drawn without phone labels -> why; an unlabelled corpus with lip roles gets
    kinematic landmark labels (fig3 regenerates an utterance through them)."""
    c = manifold.corpus_
    if any(u.phones for u in c.utterances):
        return {}
    from engine.recordings.kinematics import kinematic_if_unlabelled, lip_aperture

    skip = {"fig4": f"it needs the phone labels /b/ /p/ /m/ and {c.name} has no phone labels"}
    if lip_aperture(c) is not None:
        manifold.corpus_, note = kinematic_if_unlabelled(c)
        print(f"lipspace figures: {note}", file=sys.stderr)
    else:
        skip["fig3"] = (f"it regenerates an utterance through its phone mid-points and {c.name} has no phone "
                        "labels (nor upper/lower lip roles for kinematic landmarks: import with --layout)")
    return skip
