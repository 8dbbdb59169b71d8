"""``lipspace render``: a synthesised (or captured) utterance as an MP4 video with its audio.

The lips are rendered off-screen frame by frame at the corpus rate with the explorer's
own scene builders, optionally beside the original utterance (``--side-by-side``) and
with a manifold panel showing the trajectory through F^y (``--trajectory``), and muxed
with the audio (the utterance's own with ``--utterance``, typed ``--text`` spoken by espeak-ng
on the synthesis's phone times, or ``--audio FILE``) by PyAV.
Targets come from the same sources as ``lipspace synthesize``. No display is needed
(VTK renders through EGL when there is no X server); the file is written atomically,
so Ctrl-C leaves no half video.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from app.cli.options import add_quiet_option, add_talker_options
from app.cli.synthesis_steps import (
    BEST,
    METHODS,
    add_synthesis_options,
    check_synthesis_options,
    load_manifold,
    make_synthesizer,
    make_targets,
)

__all__ = ["add_arguments", "run"]


def _size(text):
    import argparse

    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x480") from None
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise argparse.ArgumentTypeError(f"{text!r}: width and height must be 16..4096 pixels")
    return w, h


def add_arguments(p):
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--phones", metavar='"P DUR ..."',
                     help='phone labels with durations in seconds, e.g. "p 0.08 ax 0.1"')
    src.add_argument("--textgrid", metavar="FILE", help="Praat TextGrid (or .lab) phone alignment")
    src.add_argument("--text", metavar='"TEXT"', help="English text (words; [p h o n e s] in brackets for others)")
    src.add_argument("--utterance", metavar="ID", help="a corpus utterance: its own phone mid-points as targets "
                                                       "(its audio is muxed in when it has any)")
    p.add_argument("-o", "--output", metavar="TALK.mp4", required=True, help="the video file to write (.mp4)")
    p.add_argument("--manifold", metavar="FILE", help="manifold file from 'lipspace build' (default: fit the "
                                                     "synthetic talker)")
    add_talker_options(p, when="without --manifold")
    p.add_argument("--method", choices=(BEST,) + METHODS + ("original",), default=BEST,
                   help="synthesis method ('best': the one measured best on the corpus's validation split for "
                        "these targets), or 'original' to render the --utterance as captured (default: %(default)s)")
    add_synthesis_options(p)
    p.add_argument("--side-by-side", action="store_true",
                   help="with --utterance: the original (left) beside the synthesis (right, red)")
    p.add_argument("--trajectory", action="store_true",
                   help="add a panel with the manifold and the trajectory through it")
    p.add_argument("--audio", metavar="FILE", help="audio to mux in (default: the --utterance's own, if any)")
    p.add_argument("--no-audio", action="store_true", help="a silent video")
    p.add_argument("--size", type=_size, default=(640, 480), metavar="WxH",
                   help="pixels of one panel (default: 640x480)")
    p.add_argument("--crf", type=int, default=20, help="H.264 quality, 0 (lossless) .. 51 (default: %(default)s)")
    add_quiet_option(p)


def _trajectory(args, manifold):
    """(frames, F^y path or None, label) of what is rendered."""
    from app.cli import CliError
    from engine.evaluation.measures import trajectory_y

    c = manifold.corpus_
    if args.method == "original":
        if args.utterance is None:
            raise CliError("--method original renders a captured utterance: give --utterance ID")
        u = _utterance(manifold, args.utterance)
        return c.frames[u.start:u.stop], manifold.Fy_[u.start:u.stop, :3] if args.trajectory else None, u.id
    try:
        targets = make_targets(args, manifold)
        args.rendered_targets = targets  # typed text is spoken on these times (_audio)
        traj = make_synthesizer(args, manifold, targets).synthesize(targets)
    except (ValueError, FileNotFoundError) as exc:
        raise CliError(str(exc)) from None
    for w in traj.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if getattr(args, "method_note", None):
        print(args.method_note)
    Y = trajectory_y(manifold, traj) if args.trajectory else None
    return traj.frames(manifold), Y, f"{traj.method}: {targets.source}"


def _utterance(manifold, uid):
    from app.cli import CliError

    try:
        return manifold.corpus_.utterance(uid)
    except KeyError as exc:
        raise CliError(str(exc.args[0])) from None


def _audio(args, manifold):
    from app.cli import CliError
    from app.export.animation import utterance_audio

    if args.no_audio:
        return None
    if args.audio is not None:
        if not Path(args.audio).is_file():
            raise CliError(f"--audio {args.audio}: no such file")
        return Path(args.audio)
    if getattr(args, "text", None) and getattr(args, "rendered_targets", None) is not None:
        from app.files.sound import SoundNote, speech_for_targets

        try:  # typed text speaks when espeak-ng is installed
            return speech_for_targets(args.rendered_targets, args.text)
        except SoundNote as exc:
            print(f"lipspace render: note: {exc}; the video is silent", file=sys.stderr)
            return None
    if args.utterance is None:
        return None
    path, why = utterance_audio(manifold, args.utterance, args.manifold)
    if path is None:
        print(f"lipspace render: note: {why}; the video is silent", file=sys.stderr)
    return path


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import progress_bar
    from app.export.video import render_video

    out = Path(args.output)
    if out.suffix.lower() != ".mp4":
        raise CliError(f"{out}: the video file must end in .mp4")
    if args.side_by_side and args.utterance is None:
        raise CliError("--side-by-side shows the original utterance: give --utterance ID")
    if args.side_by_side and args.method == "original":
        raise CliError("--side-by-side with --method original would show the utterance twice; choose a method")
    if args.audio is not None and args.no_audio:
        raise CliError("--audio and --no-audio contradict each other; give one")
    check_synthesis_options(args)
    if not 0 <= args.crf <= 51:
        raise CliError(f"--crf {args.crf}: must be from 0 (lossless) to 51")
    manifold = load_manifold(args)
    c = manifold.corpus_
    frames, Y, label = _trajectory(args, manifold)
    original = Y_original = None
    if args.side_by_side or (args.trajectory and args.utterance is not None and args.method != "original"):
        u = _utterance(manifold, args.utterance)
        if args.side_by_side:
            original = c.frames[u.start:u.stop]
        Y_original = manifold.Fy_[u.start:u.stop, :3]
    audio = _audio(args, manifold)
    title = label.split(":")[0]
    if original is not None:
        title = f"{args.utterance}: original (left), {title} (right)"
    t0 = time.perf_counter()
    from app.cli._common import command_outputs
    from engine.recordings.orientation import anatomical_frame

    with progress_bar(disable=True if args.quiet else None) as progress, command_outputs(args) as outputs:
        try:
            render_video(outputs.file(out, option="-o"), frames, rate=c.rate, faces=c.faces, dims=c.dims,
                         roles=c.point_roles or None, orientation=anatomical_frame(c, manifold.shape_.mean_),
                         unit=c.unit_label,
                         names=c.point_names or None, original=original, Y=Y,
                         Y_original=Y_original, cloud=manifold.Fy_[:, :3] if Y is not None else None, audio=audio,
                         size=args.size, crf=args.crf, title=title, progress=progress)
        except ValueError as exc:
            raise CliError(str(exc)) from None
    n = max(len(frames), 0 if original is None else len(original))
    dt = time.perf_counter() - t0
    print(f"wrote {out} ({n} frames, {n / c.rate:.2f} s at {c.rate:g} Hz{', with audio' if audio else ', silent'}; "
          f"{label}; rendered in {dt:.1f} s)")
    return 0
