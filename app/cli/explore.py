"""``lipspace explore``: open the explorer GUI (the default command).

Without a display (no DISPLAY / WAYLAND_DISPLAY on Linux) it explains how to run
under a virtual X server and which batch commands work without one, and exits 3.
Qt is imported only when the window is really opened.

The synthetic talker's manifold is cached in the user cache directory
(``platformdirs.user_cache_dir("lipspace")`` or ``$LIPSPACE_CACHE_DIR``), keyed by
preset and manifold file version, so the second start is quick.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

__all__ = ["add_arguments", "run", "has_display", "NO_DISPLAY_MESSAGE", "cache_dir", "cached_manifold_path",
           "load_source", "source_kind", "EXIT_NO_DISPLAY"]

PRESETS = ("small", "default", "paper")
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
    p.add_argument("--preset", choices=PRESETS, default="default",
                   help="synthetic talker preset when no file is given (default: %(default)s)")
    p.add_argument("--session", default=None, help="session file to reopen (from File > Save session)")
    p.add_argument("--restore", action=argparse.BooleanOptionalAction, default=None,
                   help="after an abnormal exit, reopen (--restore) or keep for later (--no-restore) the "
                        "autosaved session without asking (default: ask)")


def has_display(environ=None, platform: str | None = None) -> bool:
    """Whether a GUI can open: always on Windows/macOS; on Linux/BSD needs DISPLAY or WAYLAND_DISPLAY."""
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if platform.startswith(("win", "darwin")):
        return True
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def cache_dir() -> Path:
    """Lipspace's cache directory (``$LIPSPACE_CACHE_DIR`` or the platform user cache dir)."""
    env = os.environ.get("LIPSPACE_CACHE_DIR")
    if env:
        return Path(env)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("lipspace"))


def cached_manifold_path(preset: str) -> Path:
    """Where the synthetic talker's manifold for ``preset`` is cached."""
    from engine import __version__
    from engine.manifold import FILE_VERSION
    from engine.synthetic import GENERATOR_VERSION

    if preset not in PRESETS:
        raise ValueError(f"preset must be one of {PRESETS}, got {preset!r}")
    from engine.manifold import algorithm_fingerprint
    from engine.synthetic import generator_fingerprint

    # keyed on the generator's and the fitting code and parameters: never a manifold made by older code
    return cache_dir() / "manifolds" / (f"synthetic-{preset}-g{GENERATOR_VERSION}-{generator_fingerprint()}-"
                                        f"m{FILE_VERSION}-{algorithm_fingerprint()}-{__version__}.npz")


def source_kind(path) -> str:
    """What ``path`` holds: ``"manifold"`` or ``"corpus"`` (Lipspace .npz) or ``"foreign"``.

    ``"foreign"`` is any format the importers read (Haskins .mat, MOCHA .ema, C3D, ...);
    it is fitted after import. ValueError naming the file for anything else.
    """
    from engine._persist import NpzReadError, read_npz

    p = Path(path)
    if not p.exists():
        raise ValueError(f"{p}: no such file (give a manifold from 'lipspace build', a corpus .npz "
                         "or a data file 'lipspace import' reads)")
    if p.suffix.lower() != ".npz":
        from engine.io import ImportFormatError, detect_format

        try:
            detect_format(p)
        except ImportFormatError as exc:
            raise ValueError(str(exc)) from None
        return "foreign"
    try:
        files = read_npz(p, keys_only=True)
    except NpzReadError as exc:
        raise ValueError(f"{exc}: not a Lipspace manifold or corpus; give a manifold from 'lipspace build' "
                         "or a corpus .npz") from None
    if "manifold_version" in files:
        return "manifold"
    if "corpus_version" in files:
        return "corpus"
    raise ValueError(f"{p}: neither a Lipspace manifold nor a corpus file (no manifold_version / corpus_version)")


def load_source(path=None, preset: str = "default", progress=None, *, use_cache: bool = True,
                prepare_views: bool = True):
    """Load or build the manifold the explorer shows (Qt-free; runs in the worker thread).

    Parameters
    ----------
    path : str or Path or None
        Manifold file (loaded), corpus file (fitted), or None (synthetic talker ``preset``,
        cached).
    progress : callable(stage, done, total), optional
        Raising :class:`engine.progress.Cancelled` from it stops the build.
    prepare_views : bool, default=True
        Also compute what the views derive from the manifold (density, phone of every
        frame, phone clusters: :func:`app.state.prepare_derived`), here in the worker, so
        that showing the manifold costs the window's thread little.

    Returns
    -------
    manifold : engine.manifold.Manifold
    source : dict ``{"path": str or None, "preset": str, "kind": str}``
    """
    m, src = _load_manifold(path, preset, progress, use_cache)
    if prepare_views:
        from app.state import prepare_derived

        prepare_derived(m, progress)
    return m, src


def _load_manifold(path, preset, progress, use_cache):
    from engine.manifold import Manifold, ManifoldFileError
    from engine.progress import report

    if path is not None:
        kind = source_kind(path)
        src = {"path": str(Path(path).resolve()), "preset": preset, "kind": kind}
        if kind == "manifold":
            report(progress, "loading manifold", 0, 1)
            m = Manifold.load(path)
            report(progress, "loading manifold", 1, 1)
            return m, src
        if kind == "foreign":
            from engine.io import read_corpus

            corpus = read_corpus(path)
        else:
            from engine.corpus import Corpus

            corpus = Corpus.load(path)
        return Manifold().fit(corpus, progress=progress), src
    src = {"path": None, "preset": preset, "kind": "synthetic"}
    cached = cached_manifold_path(preset)
    if use_cache and cached.exists():
        try:
            report(progress, "loading cached manifold", 0, 1)
            m = Manifold.load(cached)
            report(progress, "loading cached manifold", 1, 1)
            return m, src
        except ManifoldFileError:
            pass  # stale or damaged cache: rebuild below
    from engine.synthetic import load_synthetic

    corpus = load_synthetic(preset=preset, progress=progress)
    m = Manifold().fit(corpus, progress=progress)
    if use_cache:
        try:
            m.save(cached)
        except OSError:
            pass  # a read-only cache only costs a rebuild next time
    return m, src


def run(args) -> int:
    if not has_display():
        print(NO_DISPLAY_MESSAGE, file=sys.stderr, end="")
        return EXIT_NO_DISPLAY
    from app.cli import CliError

    if args.file is not None:
        try:
            source_kind(args.file)
        except ValueError as exc:
            raise CliError(str(exc)) from None
    session = None
    if args.session is not None:
        from app.session import SessionError, load_session

        try:
            session = load_session(args.session)
        except SessionError as exc:
            raise CliError(str(exc)) from None
    from app.main_window import launch

    return launch(args.file, preset=args.preset, session=session, restore=args.restore)
