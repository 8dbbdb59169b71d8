"""``lipspace explore``: open the explorer GUI (the default command).

Without a display (no DISPLAY / WAYLAND_DISPLAY on Linux) it explains how to run
under a virtual X server and which batch commands work without one, and exits 3; with
one that does not answer (no X server at DISPLAY, no compositor at WAYLAND_DISPLAY:
:func:`app.display_check.display_problem`) it says which and exits 2, where Qt would
abort the process.
Qt is imported only when the window is really opened. What is shown is loaded by
:mod:`app.files.source_loading` (Qt-free, shared with the window).
"""
from __future__ import annotations

import argparse
import os
import sys

from app.cli.options import add_talker_options
from app.files.source_loading import source_kind

__all__ = ["add_arguments", "run", "has_display", "NO_DISPLAY_MESSAGE", "EXIT_NO_DISPLAY"]

EXIT_NO_DISPLAY = 3

NO_DISPLAY_MESSAGE = """\
lipspace explore: no display found (neither DISPLAY nor WAYLAND_DISPLAY is set).
The explorer is a desktop window and needs a display. On a machine without one,
run it under a virtual X server:

    xvfb-run -a lipspace explore

These commands work without a display:

    lipspace build -o m.npz           fit a manifold (synthetic talker, or give a corpus file)
    lipspace info m.npz               summarise a manifold or corpus file
    lipspace figures m.npz -o figs/   render the paper's figures (PNG/SVG/PDF)
    lipspace clusters m.npz           phone cluster statistics table
    lipspace synthesize --manifold m.npz --text "bob meets mum" -o t.csv
                                      synthesise a lip trajectory from text, phones or a TextGrid
    lipspace evaluate [corpus.npz]    held-out synthesis error of every method (synthetic talker
                                      without a corpus)
"""


def add_arguments(p):
    p.add_argument("file", nargs="?", help="manifold (from 'lipspace build') or native corpus file (.npz); "
                                           "omit for the embedded synthetic talker")
    add_talker_options(p, when="when no file is given",
                       kinematics="opens the opt-in talker whose jaw, upper lip and corners move as real "
                                  "speakers' articulograph sensors do")
    p.add_argument("--session", default=None, help="session file to reopen (from File > Save session)")
    p.add_argument("--restore", action=argparse.BooleanOptionalAction, default=None,
                   help="after an abnormal exit, reopen (--restore) or keep for later (--no-restore) the "
                        "autosaved session without asking (default: ask)")
    p.add_argument("--camera", default=None, metavar="N|VIDEO",
                   help="live mirror: project a camera (number N, /dev/videoN) or a video file played as a stream "
                        "into the manifold given by --manifold (built from a video import)")
    p.add_argument("--manifold", default=None, metavar="M", help="with --camera: the manifold file (.npz)")
    p.add_argument("--interocular-mm", type=float, default=63.0, metavar="MM",
                   help="with --camera: assumed distance between the eye centres (default: %(default)s)")


def has_display(environ=None, platform: str | None = None) -> bool:
    """Whether a GUI can open: always on Windows/macOS; on Linux/BSD needs DISPLAY or WAYLAND_DISPLAY."""
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if platform.startswith(("win", "darwin")):
        return True
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def run(args) -> int:
    from app.cli import CliError

    if args.file is not None and args.camera is None:  # a wrong file is said before anything about the display
        if args.kinematics != "classic":
            raise CliError("--kinematics chooses the synthetic talker's; it does nothing with a file "
                           f"({args.file}): leave it out")
        try:
            source_kind(args.file)
        except ValueError as exc:
            raise CliError(str(exc)) from None
    if not has_display():
        print(NO_DISPLAY_MESSAGE, file=sys.stderr, end="")
        return EXIT_NO_DISPLAY
    from app.display_check import display_problem

    problem = display_problem()
    if problem is not None:  # Qt would abort the process with a core dump
        raise CliError(f"cannot open the window: {problem}. Start the display (or fix DISPLAY / WAYLAND_DISPLAY), "
                       "run under a virtual X server (xvfb-run -a lipspace explore), or use the batch commands "
                       "(lipspace --help)")
    if args.camera is not None:  # the live mirror (app.models.live)
        return run_live(args.manifold or args.file, args.camera, interocular_mm=args.interocular_mm)
    session, notes = None, []
    if args.session is not None:
        from app.files.session import SessionError, load_session

        try:
            session = load_session(args.session)
        except SessionError as exc:  # the user's file stays where it is; the window opens without it
            notes.append(f"--session {args.session} was not opened: {exc}")
            print(f"lipspace explore: warning: {notes[-1]}", file=sys.stderr)
    from app.launching import launch

    code = launch(args.file, preset=args.preset, session=session, restore=args.restore, kinematics=args.kinematics,
                  notes=notes)
    from app.workers import exit_if_tasks_run

    exit_if_tasks_run(code)  # closed (by the user or a stop signal) while a task was inside an engine step
    return code


def run_live(manifold_path, source, *, interocular_mm: float = 63.0) -> int:
    """``lipspace explore --manifold M --camera SOURCE``: check the inputs, then open the window."""
    from app.cli import CliError
    from app.models.live import camera_source, check_video_manifold
    from engine.manifold.model import Manifold, ManifoldFileError

    if manifold_path is None:
        raise CliError("--camera needs --manifold M: a manifold built from a video import "
                       "(lipspace import talk.mp4 -o c.npz; lipspace build c.npz -o M)")
    try:
        camera_source(source)
        manifold = Manifold.load(manifold_path)
        check_video_manifold(manifold)
        from engine.io.video.facemesh import require_mediapipe

        require_mediapipe()
    except (ValueError, ManifoldFileError, FileNotFoundError, ImportError) as exc:
        raise CliError(f"{manifold_path}: {exc}" if "manifold was built" in str(exc) else str(exc)) from None
    try:
        from app.views.live_view import launch_live

        return launch_live(manifold, source, interocular_mm=interocular_mm)
    except ValueError as exc:  # the camera / stream cannot be opened
        raise CliError(str(exc)) from None
