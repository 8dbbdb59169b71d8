"""Loading what the explorer shows: a manifold file, a corpus to fit, or the synthetic talker (Qt-free).

The window (:mod:`app.main_window`, in a worker thread) and the command line
(``lipspace explore``, ``lipspace figures``) both load through :func:`load_source`,
and check a file the user names with :func:`source_kind` before opening anything.

The default synthetic talker's manifold is shipped fitted (:mod:`engine.talker.prebuilt`): its
corpus is generated (then cached) and the shipped fit put back on it, so even the first start
builds nothing. Any other talker's manifold (another preset or kinematics, or the default one
when the shipped file was made by other code) is fitted once and cached in the user cache
directory (``platformdirs.user_cache_dir("lipspace")`` or ``$LIPSPACE_CACHE_DIR``), keyed by
preset, generator, fitting code and manifold file version, so the second start is quick. The
talker's speech audio can be made in the background (``speech_audio="background"``, what the
window asks for): its utterances name their sound files at once and play silent until the
files are written.
The talker comes in two kinematics (:data:`engine.talker.lipmodel.KINEMATICS`): ``"classic"``
and the opt-in ``"calibrated"`` (lips that move as real articulograph sensors do); each
has its own cache entries (``synthetic-<preset>-...``, ``synthetic-<preset>_calibrated-...``),
so opening one never prunes the other's.
"""
from __future__ import annotations

from pathlib import Path

from app.files.cache import CACHE_DIR_ENV, cache_dir

__all__ = ["PRESETS", "KINEMATICS_CHOICES", "KINEMATICS_LABELS", "CACHE_DIR_ENV", "cache_dir", "cached_manifold_path",
           "check_kinematics", "talker_name", "prune_talker_cache", "source_kind", "load_source", "loading_task",
           "read_corpus_file", "read_recording", "ANALYSIS_RATE", "wait_for_background"]

#: synthetic talker presets (engine.talker.synthetic)
PRESETS = ("small", "default", "paper")

#: the synthetic talker's kinematics (the keys of engine.talker.lipmodel.KINEMATICS; checked against it)
KINEMATICS_CHOICES = ("classic", "calibrated")

#: how the window and the command line name each kinematics (a phonetician's words, not the code's)
KINEMATICS_LABELS = {"classic": "classic", "calibrated": "calibrated on articulograph lips"}


def check_kinematics(kinematics) -> str:
    """``kinematics`` if it is one of :data:`engine.talker.lipmodel.KINEMATICS`, else ValueError naming it and
    the choices."""
    from engine.talker.lipmodel import KINEMATICS

    if not isinstance(kinematics, str) or kinematics not in KINEMATICS:
        raise ValueError(f"kinematics {kinematics!r} is not one of {sorted(KINEMATICS)}: give 'classic' (the "
                         "default talker) or 'calibrated' (lips that move as real articulograph sensors do)")
    return kinematics


def talker_name(preset: str = "default", kinematics: str = "classic") -> str:
    """The synthetic talker as the window names it: ``synthetic talker (default)``,
    ``synthetic talker (default, calibrated on articulograph lips)``."""
    if kinematics == "classic":
        return f"synthetic talker ({preset})"
    return f"synthetic talker ({preset}, {KINEMATICS_LABELS.get(kinematics, kinematics)})"


def cached_manifold_path(preset: str, kinematics: str = "classic") -> Path:
    """Where the synthetic talker's manifold for ``preset`` and ``kinematics`` is cached.

    The name's preset part is :func:`engine.talker.synthetic.cache_token` (``default``,
    ``default_calibrated``), so the classic talker's name is the one it always had and
    :func:`app.files.cache.prune` keeps the two talkers' entries apart.
    """
    from engine import __version__
    from engine.manifold.model import FILE_VERSION
    from engine.talker.synthetic_talker import GENERATOR_VERSION

    if preset not in PRESETS:
        raise ValueError(f"preset must be one of {PRESETS}, got {preset!r}")
    check_kinematics(kinematics)
    from engine.manifold.model import algorithm_fingerprint
    from engine.talker.talker_cache import cache_token, generator_fingerprint

    token = cache_token(preset, kinematics=kinematics)
    # keyed on the generator's and the fitting code and parameters: never a manifold made by older code
    return cache_dir() / "manifolds" / (f"synthetic-{token}-g{GENERATOR_VERSION}-{generator_fingerprint()}-"
                                        f"m{FILE_VERSION}-{algorithm_fingerprint()}-{__version__}.npz")


def source_kind(path) -> str:
    """What ``path`` holds: ``"manifold"`` or ``"corpus"`` (Lipspace .npz) or ``"foreign"``.

    ``"foreign"`` is any format the importers read (Haskins .mat, MOCHA .ema, C3D, ...);
    it is fitted after import. ValueError naming the file for anything else.
    """
    from engine.files.persist import NpzReadError, read_npz

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


def load_source(path=None, preset: str = "default", progress=None, *, kinematics: str = "classic",
                use_cache: bool = True, prepare_views: bool = True, speech_audio: str = "now"):
    """Load or build the manifold the explorer shows (Qt-free; runs in the worker thread).

    Parameters
    ----------
    path : str or Path or None
        Manifold file (loaded), corpus file (fitted), or None (synthetic talker ``preset``,
        cached).
    preset : {"small", "default", "paper"}, default="default"
        The synthetic talker's preset when ``path`` is None.
    progress : callable(stage, done, total), optional
        Raising :class:`engine.progress.Cancelled` from it stops the build.
    kinematics : {"classic", "calibrated"}, default="classic"
        The synthetic talker's kinematics (:data:`engine.talker.lipmodel.KINEMATICS`):
        ``"calibrated"`` is the opt-in talker whose jaw, upper lip and corners move as real
        speakers' articulograph sensors do. Only with ``path`` None: a file holds its own
        frames, and anything but ``"classic"`` with a file is a ValueError.
    prepare_views : bool, default=True
        Also compute what the views derive from the manifold (density, phone of every
        frame, phone clusters: :func:`app.models.state.prepare_derived`), here in the worker, so
        that showing the manifold costs the window's thread little; the density is read from the
        cache when this cloud was shown before (:mod:`app.files.density_cache`).
    speech_audio : {"now", "background"}, default="now"
        When the synthetic talker's speech audio is made (espeak-ng; only with ``path`` None):
        before returning, or in a background thread started just before returning (the
        utterances name their files at once; each plays once written; a talker fitted anew
        is cached once its audio is named). With ``"background"`` a corpus generated here is
        also written to the cache after returning, in a thread the interpreter waits for at
        exit. :func:`wait_for_background` waits for both.

    Returns
    -------
    manifold : engine.manifold.model.Manifold
    source : dict ``{"path": str or None, "preset": str, "kind": str}``
        The synthetic talker's also holds ``"kinematics"``.
    """
    check_kinematics(kinematics)
    if path is not None and kinematics != "classic":
        raise ValueError(f"kinematics {kinematics!r} chooses the synthetic talker's; it does nothing with a file "
                         f"({path}): leave it out, or open the synthetic talker (no file)")
    if speech_audio not in ("now", "background"):
        raise ValueError(f"speech_audio must be 'now' or 'background', got {speech_audio!r}")
    later = _Later() if speech_audio == "background" else None
    m, src = _load_manifold(path, preset, progress, use_cache, kinematics, later)
    if prepare_views:
        from app.files.density_cache import cached_knn_density
        from app.models.state import prepare_derived

        prepare_derived(m, progress, density=cached_knn_density)  # the density as stored when last shown
    if later is not None:
        later.start()
    return m, src


def loading_task(path=None, preset: str = "default", kinematics: str = "classic"):
    """``(what, task)``: the window's name for the source (``m.npz``, ``the synthetic talker (default)``) and
    the worker task ``task(progress)`` that loads it (:func:`load_source` with the speech audio made in the
    background; its failures are plain-language :class:`app.user_messages.UserError`)."""
    from app.user_messages import plain_errors

    check_kinematics(kinematics)
    what = Path(path).name if path else f"the {talker_name(preset, kinematics)}"
    task = plain_errors(lambda progress: load_source(path, preset, progress, kinematics=kinematics,
                                                     speech_audio="background"), doing=f"open {what}", path=path)
    return what, task


_BACKGROUND: list = []


class _Later:
    """What the talker's load leaves for after it: ``cache`` (the corpus written to the cache, old entries
    pruned), run in a thread the interpreter waits for at exit, so that a window closed at once still leaves
    a whole cache; then ``audio`` (the speech audio, and a talker fitted anew cached once its audio is
    named), in a daemon thread: an unfinished file is made again next time."""

    def __init__(self):
        self.cache, self.audio = [], []

    def start(self) -> None:
        for jobs, daemon in ((self.cache, False), (self.audio, True)):
            if jobs:
                _start_background(jobs, daemon=daemon)


def _start_background(jobs, *, daemon: bool) -> None:
    """Run ``jobs`` one after the other in a thread."""
    import threading

    def run():
        for job in jobs:
            try:
                job()
            except Exception:  # noqa: BLE001 - a failure here costs sound or a cache entry, never the window
                pass

    t = threading.Thread(target=run, name="lipspace-talker-" + ("audio" if daemon else "cache"), daemon=daemon)
    _BACKGROUND[:] = [b for b in _BACKGROUND if b.is_alive()] + [t]
    t.start()


def wait_for_background(timeout: float | None = None) -> bool:
    """Wait for the work :func:`load_source` left running (the talker's cache file and speech audio); True when
    none is left."""
    import time

    end = None if timeout is None else time.monotonic() + timeout
    for t in list(_BACKGROUND):
        t.join(None if end is None else max(0.0, end - time.monotonic()))
    return not any(t.is_alive() for t in _BACKGROUND)


def _load_manifold(path, preset, progress, use_cache, kinematics="classic", later=None):
    from engine.manifold.model import Manifold, ManifoldFileError
    from engine.progress import report

    if path is not None:
        kind = source_kind(path)
        src = {"path": str(Path(path).resolve()), "preset": preset, "kind": kind}
        if kind == "manifold":
            report(progress, "loading manifold", 0, 1)
            m = Manifold.load(path)
            report(progress, "loading manifold", 1, 1)
            return m, src
        return Manifold().fit(read_corpus_file(path), progress=progress), src
    src = {"path": None, "preset": preset, "kind": "synthetic", "kinematics": kinematics}
    cached = cached_manifold_path(preset, kinematics)
    if use_cache and cached.exists():
        try:
            report(progress, "loading cached manifold", 0, 1)
            m = Manifold.load(cached)
            report(progress, "loading cached manifold", 1, 1)
            prune_talker_cache(preset, kinematics, keep=[cached])
            return m, src
        except (ManifoldFileError, OSError):
            pass  # stale or damaged cache: rebuild below
    from engine.talker.talker_cache import load_synthetic

    # speech audio when espeak-ng is installed: now, or (later given) named now and made in the background
    corpus = load_synthetic(preset=preset, progress=progress, audio=later is None, kinematics=kinematics,
                            save_later=None if later is None else later.cache)  # with later: written after returning
    if later is not None:
        corpus, audio = _audio_later(corpus, preset, kinematics)
        later.audio.append(audio)
    m = _shipped(corpus, preset, kinematics, progress) if use_cache else None
    if m is not None:  # the shipped fit on the regenerated corpus: nothing to cache but the corpus
        if later is None:
            prune_talker_cache(preset, kinematics)
        else:  # once the corpus is written
            later.cache.append(lambda: prune_talker_cache(preset, kinematics))
        return m, src
    m = Manifold().fit(corpus, progress=progress)
    if use_cache:
        def cache():
            try:
                m.save(cached)
                from engine.files.ownership import mark

                mark(cached, cache_dir())  # Lipspace's own: pruning and 'lipspace cache --clear' may delete it
            except OSError:
                pass  # a read-only cache only costs a rebuild next time
            prune_talker_cache(preset, kinematics, keep=[cached])

        if later is None:
            cache()
        else:  # once the audio is made, so that the cached corpus part says which
            later.audio.append(cache)
    return m, src


def _shipped(corpus, preset, kinematics, progress):
    """The shipped fit of the default talker on ``corpus`` (:mod:`engine.talker.prebuilt`), or None."""
    from engine.manifold.model import ManifoldFileError
    from engine.talker.prebuilt import PRESET, load_prebuilt

    if preset != PRESET or kinematics != "classic":
        return None
    try:
        return load_prebuilt(corpus, progress=progress)[0]
    except ManifoldFileError:
        return None  # a damaged shipped file: the talker is fitted as before


def _audio_later(corpus, preset, kinematics):
    """``(corpus whose utterances name their speech audio files, job that writes them)``.

    Without espeak-ng the corpus comes back as it was, with a history line saying why, and the job
    does nothing.
    """
    import subprocess

    from engine.phonetics.speech_audio import SpeechAudioUnavailable, add_speech_audio, planned_speech_audio
    from engine.talker.talker_cache import audio_folder, cache_path

    folder = audio_folder(cache_path(preset, kinematics=kinematics))
    try:
        planned = planned_speech_audio(corpus, folder)
    except SpeechAudioUnavailable as exc:
        corpus.history.append(f"speech audio: none; {exc}")
        return corpus, lambda: None

    def job():
        try:
            made = add_speech_audio(planned, folder)
        except (OSError, ValueError, subprocess.SubprocessError, SpeechAudioUnavailable) as exc:
            planned.history.append(f"speech audio: none; generating it failed ({exc})")
        else:
            planned.history.append(made.history[-1])

    return planned, job


#: the method's analysis rate in Hz (the paper's 60 Hz), to which 'lipspace import' and :func:`read_recording`
#: resample by default (see docs/DECISIONS.md, A6)
ANALYSIS_RATE = 60.0


def read_corpus_file(path):
    """The corpus a file holds, read as every part of Lipspace reads it: the one reader of the
    window (File › Open, a corpus named to ``lipspace explore``) and of the command line
    (``build``, ``info``, ``figures``, ``clusters``: :func:`app.cli._common.load_corpus_arg`).

    * a Lipspace corpus ``.npz`` with its frames stored whole: :meth:`engine.recordings.corpus.Corpus.load`;
    * a corpus stored in blocks (``lipspace import --block-frames``):
      :func:`engine.recordings.corpus_blocks.load_blocked`, its frames left in the block files (an
      :class:`engine.recordings.frame_blocks.BlockFrames`, never gathered);
    * any foreign recording the importers read: :func:`read_recording` (import's defaults).

    Raises
    ------
    engine.recordings.corpus.CorpusError
        A damaged corpus or block file (the message names it).
    engine.io.ImportFormatError
        A file no importer reads.
    """
    p = Path(path)
    if p.suffix.lower() == ".npz":
        from engine.recordings.corpus import Corpus
        from engine.recordings.corpus_blocks import is_blocked, load_blocked

        return load_blocked(p) if is_blocked(p) else Corpus.load(p)
    return read_recording(p)


def read_recording(path):
    """A recording in a foreign format (Haskins .mat, MOCHA .ema, C3D, CSV, ...) as ``lipspace
    import`` makes it with its defaults, so that opening the file itself in the window (or in
    ``lipspace explore FILE``) fits the same corpus as ``import`` then ``build``.

    The file's sound is kept as import keeps it (a video's audio track, a Haskins ``.mat``
    file's ``AUDIO``: :func:`app.files.sound.read_with_sound`).
    The defaults applied: registration ``"auto"`` (rigid with 3 or more reference sensors,
    else centring when there are several utterances; :func:`engine.recordings.registration.register`),
    then resampling to :data:`ANALYSIS_RATE` (:func:`engine.io.resample`), video included.
    Both are noted in the corpus history, which ``info`` and the session show; so is every
    repair of the data (dropouts interpolated, ...), which is also issued as an
    :class:`engine.io.errors.ImportDataWarning` (the window's status bar, a warning line on the
    command line).

    Parameters
    ----------
    path : str or Path
        The recording (any format :func:`engine.io.read_corpus` reads).

    Returns
    -------
    engine.recordings.corpus.Corpus
        Frames of shape (n_frames, dims * n_points) at 60 Hz.
    """
    import warnings

    from app.files.sound import read_with_sound
    from engine.io import resample
    from engine.io.errors import ImportDataWarning
    from engine.io.repairs import collecting_repairs
    from engine.recordings.registration import register

    with collecting_repairs() as repairs:
        corpus = register(read_with_sound(path), method="auto")
    for note in repairs:  # in the history too; said now, since no import step printed it
        warnings.warn(ImportDataWarning(note), stacklevel=2)
    if abs(corpus.rate - ANALYSIS_RATE) > 1e-9 * ANALYSIS_RATE:
        corpus = resample(corpus, ANALYSIS_RATE)
    return corpus


def prune_talker_cache(preset, kinematics="classic", keep=()) -> None:
    """Delete the cache entries older code left for the synthetic talker ``preset`` with
    ``kinematics``, keeping its newest corpus and the files ``keep`` (see :func:`app.files.cache.prune`);
    the other kinematics' entries have another preset token and stay."""
    from app.files.cache import newest, prune
    from engine.talker.talker_cache import cache_token

    prune([*keep, *newest("corpus", cache_token(preset, kinematics=kinematics))])
