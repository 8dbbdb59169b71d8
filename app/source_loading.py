"""Loading what the explorer shows: a manifold file, a corpus to fit, or the synthetic talker (Qt-free).

The window (:mod:`app.main_window`, in a worker thread) and the command line
(``lipspace explore``, ``lipspace figures``) both load through :func:`load_source`,
and check a file the user names with :func:`source_kind` before opening anything.

The synthetic talker's manifold is cached in the user cache directory
(``platformdirs.user_cache_dir("lipspace")`` or ``$LIPSPACE_CACHE_DIR``), keyed by
preset, generator, fitting code and manifold file version, so the second start is quick.
"""
from __future__ import annotations

from pathlib import Path

from app.cache import CACHE_DIR_ENV, cache_dir

__all__ = ["PRESETS", "CACHE_DIR_ENV", "cache_dir", "cached_manifold_path", "source_kind", "load_source"]

#: synthetic talker presets (engine.synthetic)
PRESETS = ("small", "default", "paper")


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
            _prune_cache(cached, preset)
            return m, src
        except (ManifoldFileError, OSError):
            pass  # stale or damaged cache: rebuild below
    from engine.synthetic import load_synthetic

    corpus = load_synthetic(preset=preset, progress=progress, audio=True)  # speech audio when espeak-ng is installed
    m = Manifold().fit(corpus, progress=progress)
    if use_cache:
        try:
            m.save(cached)
        except OSError:
            pass  # a read-only cache only costs a rebuild next time
        _prune_cache(cached, preset)
    return m, src


def _prune_cache(manifold_path, preset) -> None:
    """Delete the cache entries older code left for ``preset`` (see :func:`app.cache.prune`)."""
    from app.cache import newest, prune

    prune([manifold_path, *newest("corpus", preset)])
