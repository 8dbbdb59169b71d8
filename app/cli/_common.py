"""Helpers shared by subcommands: loading inputs, progress bars."""
from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

from engine.progress import Cancelled

__all__ = ["progress_bar", "load_corpus_arg", "load_manifold_arg", "command_outputs", "check_synthesis_bounds",
           "roles_text"]


def roles_text(names, roles, *, limit: int = 12) -> str:
    """The point roles in one line: ``UL=upper_lip, LL=lower_lip, ...`` for up to ``limit`` points; for more
    (a video's 80 lip landmarks) one entry per role, naming its points when there are at most 4, else
    counting them: ``80 points: upper_lip outer_0, inner_13; ...; lip 74 points``."""
    names = list(names) if names is not None else [f"p{i}" for i in range(len(roles))]
    if len(roles) <= limit:
        return ", ".join(f"{n}={r or '-'}" for n, r in zip(names, roles))
    from engine.recordings.layouts import ROLES

    by_role: dict[str, list] = {}
    for n, r in sorted(zip(names, roles), key=lambda t: ROLES.index(t[1]) if t[1] in ROLES else len(ROLES)):
        by_role.setdefault(r or "-", []).append(str(n))
    parts = [f"{r} {', '.join(ns)}" if len(ns) <= 4 else f"{r} {len(ns)} points" for r, ns in by_role.items()]
    return f"{len(roles)} points: " + "; ".join(parts)


@contextlib.contextmanager
def progress_bar(*, disable: bool | None = None):
    """Yield a ``progress(stage, done, total)`` callable drawing tqdm bars on stderr.

    One bar per stage. Ctrl-C raised inside the engine surfaces as :class:`Cancelled`
    so the command stops cleanly and writes nothing.
    """
    from tqdm.auto import tqdm

    bars = {}

    def progress(stage, done, total):
        from app.cli import stop_requested

        if stop_requested():  # a signal whose KeyboardInterrupt Python swallowed
            raise Cancelled("interrupted")
        bar = bars.get(stage)
        if bar is None:
            for b in bars.values():
                b.close()
            bar = bars[stage] = tqdm(total=max(total, 1), desc=stage, unit="", leave=True,
                                     file=sys.stderr, disable=disable, dynamic_ncols=True)
        bar.total = max(total, 1)
        bar.n = done
        bar.refresh()

    try:
        yield progress
    except KeyboardInterrupt:
        raise Cancelled("interrupted") from None
    finally:
        for b in bars.values():
            b.close()


def load_corpus_arg(path, *, synthetic_preset: str = "default", progress=None, kinematics: str = "classic",
                    audio: bool = False):
    """A corpus from a native file (frames whole or in blocks), a foreign recording (as ``lipspace
    import`` makes it by default), both read by the window's reader
    :func:`app.files.source_loading.read_corpus_file`, or the synthetic talker (with ``kinematics``)
    when ``path`` is None.

    ``audio``: give the synthetic talker its speech audio (espeak-ng; without it the corpus
    history says why), as the explorer's talker has it; ``lipspace build`` asks for it so that
    a manifold file of the talker plays and exports with sound. Ignored for a file.
    """
    from app.cli import CliError
    from engine.recordings.corpus import CorpusError

    if path is None:
        from app.files.source_loading import prune_talker_cache
        from engine.talker.talker_cache import load_synthetic

        corpus = load_synthetic(preset=synthetic_preset, progress=progress, kinematics=kinematics, audio=audio)
        prune_talker_cache(synthetic_preset, kinematics)  # the corpora older code left behind
        return corpus
    p = Path(path)
    if not p.exists():
        raise CliError(f"{p}: no such file")
    from app.files.source_loading import read_corpus_file
    from engine.io import ImportFormatError

    try:
        # a corpus .npz (frames whole, or in blocks read from there when needed) or any foreign
        # format the importers know, with import's defaults: the window's reader
        return read_corpus_file(p)
    except ImportFormatError as exc:
        raise CliError(f"{exc} (convert it first with 'lipspace import')") from None
    except CorpusError as exc:
        raise CliError(str(exc)) from None


def load_manifold_arg(path):
    """A fitted manifold from a file written by ``lipspace build``."""
    from app.cli import CliError
    from engine.manifold.model import Manifold, ManifoldFileError

    p = Path(path)
    if not p.exists():
        raise CliError(f"{p}: no such manifold file (make one with 'lipspace build')")
    try:
        return Manifold.load(p)
    except ManifoldFileError as exc:
        raise CliError(str(exc)) from None


def command_outputs(args):
    """The outputs of one command as one transaction (:class:`engine.files.staging.Outputs`): existing
    files refused unless ``--force``, everything moved into place at the end with stop signals
    deferred meanwhile, nothing left behind by an error or a signal.

    Every path-valued argument that exists and is not an output is given as an input, named
    by its option as typed: whatever file the command reserves (also one it derives, as the
    WAV beside a ``.glb``) is refused when it is one of them or another output."""
    from app.cli import OUTPUT_DIR_ARGS, OUTPUT_FILE_ARGS, signals_deferred
    from engine.files.staging import Outputs

    typed = getattr(args, "_typed", {}) or {}
    inputs = []
    for name, value in vars(args).items():
        if name.startswith("_") or name in OUTPUT_FILE_ARGS + OUTPUT_DIR_ARGS or value is None:
            continue
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, str) and v and "\x00" not in v and os.path.lexists(v):
                inputs.append((typed.get(name, "--" + name.replace("_", "-")), v))
    return Outputs(force=bool(getattr(args, "force", False)), guard=signals_deferred, inputs=inputs)


#: longest synthesis the command line runs, in seconds of speech
MAX_SYNTHESIS_SECONDS = 600.0
#: highest --inverse-dims (a Delaunay triangulation in d dimensions grows exponentially with d)
MAX_INVERSE_DIMS = 5
#: --tempo range (speaking-rate factor)
TEMPO_RANGE = (0.1, 10.0)


def check_synthesis_bounds(args, targets) -> None:
    """Refuse a synthesis that would run for hours or exhaust memory, naming the limit.

    A 1e6-second phone or ``--tempo 1e-6`` asked for tens of millions of frames, and
    ``--inverse-dims 10`` for a 10-D Delaunay triangulation (several GB).
    """
    from app.cli import CliError

    # empty or word-less --text is refused where the targets are built (engine.phonetics.phones)
    phones = getattr(args, "phones", None)
    if phones is not None and not phones.strip():
        raise CliError('--phones is empty; give labels with durations, e.g. "p 0.08 aa 0.12"')
    tempo = getattr(args, "tempo", None)
    if tempo is not None and not TEMPO_RANGE[0] <= tempo <= TEMPO_RANGE[1]:
        raise CliError(f"--tempo {tempo:g}: must be from {TEMPO_RANGE[0]:g} to {TEMPO_RANGE[1]:g} "
                       "(1 = the duration model's own rate)")
    dims = getattr(args, "inverse_dims", None)
    if dims is not None and not 1 <= dims <= MAX_INVERSE_DIMS:
        raise CliError(f"--inverse-dims {dims}: must be from 1 to {MAX_INVERSE_DIMS} (the paper uses 3; a "
                       f"Delaunay triangulation in more dimensions needs far more time and memory)")
    seconds = targets.n_frames / targets.rate
    if not seconds <= MAX_SYNTHESIS_SECONDS:
        raise CliError(f"the targets span {seconds:.6g} s ({targets.n_frames} frames at {targets.rate:g} Hz); "
                       f"at most {MAX_SYNTHESIS_SECONDS:g} s can be synthesised at once. Check the phone "
                       "durations (seconds, not milliseconds) and --tempo, or split the input")

