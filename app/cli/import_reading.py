"""Reading the inputs of ``lipspace import``: one corpus per input, in this process, a process pool or on Dask.

:func:`read_one` reads one input (a file, or the frame files of one mesh sequence) into a corpus
and gives it its id, fields and speaker, or says why it cannot be read; :func:`read_many` reads
every input with the chosen backend in input order, with a progress bar, and skips or refuses the
unreadable ones. An error writing an output (a full or read-only disk) stops the whole import.
"""
from __future__ import annotations

import errno
import sys
from dataclasses import replace
from pathlib import Path

__all__ = ["read_one", "read_many", "read_group", "has_audio", "speaker_of"]


def _input_errors():
    """Errors that make one input unreadable (reported and skipped when there are several inputs)."""
    from engine.io import ImportFormatError
    from engine.recordings.corpus import CorpusError

    return (ImportFormatError, CorpusError, OSError, ValueError, TypeError)


def has_audio(src) -> bool:
    """Whether an MVIEW file holds an ``AUDIO`` entry (a file without one imports silent, as it is)."""
    from engine.io import ImportFormatError, read_mview_audio

    try:
        read_mview_audio(src)
    except ImportFormatError as exc:
        return "has no AUDIO entry" not in str(exc)  # a damaged AUDIO entry is still said, by write_audio
    return True


def read_group(g, job):
    """The corpus of one input (a file, or the frame files of one mesh sequence)."""
    from engine.io import read_corpus, write_audio
    from engine.io.repairs import collecting_repairs

    src = g if len(g) > 1 else g[0]
    try:
        c = read_corpus(src, format=job["format"], rate=job["rate"], alignment=job["alignment"], **job["options"])
    except MemoryError as exc:  # which input did not fit is said (lipspace import: out of memory reading ...)
        raise _InputMemoryError(g[0], exc) from exc
    if job["audio_dir"] and job["format"] == "mview" and has_audio(src):
        with collecting_repairs() as notes:  # e.g. non-finite samples written as silence
            wav = write_audio(src, Path(job["audio_dir"]) / (Path(src).stem + ".wav"))
        c = replace(c, utterances=[replace(u, audio=str(wav)) for u in c.utterances],
                    history=c.history + [n for n in notes if n not in c.history])
    uid = (job.get("ids") or {}).get(str(g[0]))
    if uid and len(c.utterances) == 1:  # same stem in two subfolders: the id keeps its folder
        c = replace(c, utterances=[replace(c.utterances[0], id=uid)])
    own = (job.get("fields") or {}).get(str(g[0]))
    if own:
        from engine.recordings.metadata import with_fields

        c = replace(c, utterances=[with_fields(u, own) for u in c.utterances])
    speaker = job["speaker"] or speaker_of(g[0], job["speaker_from"])
    if speaker:
        c = replace(c, utterances=[replace(u, speaker=speaker) for u in c.utterances])
    elif job.get("name_corpora") and any(not u.speaker for u in c.utterances):
        stem = Path(str(src)).stem
        unnamed = sum(not u.speaker for u in c.utterances)
        c = replace(c, utterances=[u if u.speaker else replace(u, speaker=stem) for u in c.utterances],
                    history=list(c.history) + [f"speaker {stem!r} given to the {unnamed} utterance(s) of "
                                               f"{Path(str(src)).name} that named none (its file name)"])
    return c


class _InputMemoryError(MemoryError):
    """Memory ran out while one input was read: the message names it."""

    def __init__(self, path, exc):
        super().__init__(f"while reading {path}")
        self._total_size = getattr(exc, "_total_size", None)


#: errors writing an output (not the input's fault): they stop the whole import
_OUTPUT_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG)


def read_one(g, job):
    """``(corpus, None)`` or ``(None, reason)`` for one input; runs in a worker process or on a Dask worker.

    An error writing an output (a full or read-only disk while its audio is written) is
    not the input's: it is raised, naming the user's file, and stops the import."""
    from engine.files.staging import as_user_error, user_path

    try:
        return read_group(g, job), None
    except OSError as exc:
        if exc.errno in _OUTPUT_ERRNOS or user_path(exc.filename) != exc.filename:
            raise as_user_error(exc) from None
        return None, _plain(exc)
    except _input_errors() as exc:
        return None, _plain(exc)


def _plain(exc) -> str:
    """The reason an input could not be read, in words."""
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc) or "it could not be read"


def read_many(groups, job, args):
    """Read every input with the chosen backend, in input order, with a progress bar; skip unreadable ones.

    Backends: ``--dask`` (a Dask cluster, ``client.map``), else a process pool of
    ``--jobs`` processes (default: one per core), else (``--jobs 1``) this process.
    The skipped inputs are printed on stderr, one line each with the reason.
    """
    import os

    from app.cli import CliError
    from app.cli._common import progress_bar

    n = len(groups)
    results = [None] * n
    stage = f"reading {n} inputs"
    jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
    if jobs < 1:
        raise CliError(f"--jobs {jobs}: must be at least 1")
    jobs = min(jobs, n)
    if args.dask:
        with progress_bar(disable=True if args.quiet else None) as progress:
            progress(stage, 0, n)
            _read_on_dask(groups, job, args.dask, results, lambda done: progress(stage, done, n))
    elif jobs == 1:
        with progress_bar(disable=True if args.quiet else None) as progress:
            for i, g in enumerate(groups):
                progress(stage, i, n)
                results[i] = read_one(g, job)
            progress(stage, n, n)
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        # fork: the readers are imported already; the pool starts before the progress bar's thread
        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as pool:
            futs = {pool.submit(read_one, g, job): i for i, g in enumerate(groups)}
            try:
                with progress_bar(disable=True if args.quiet else None) as progress:
                    progress(stage, 0, n)
                    for done, f in enumerate(as_completed(futs), 1):
                        results[futs[f]] = f.result()
                        progress(stage, done, n)
            except BaseException:  # a full disk, Ctrl-C: start no more inputs
                pool.shutdown(wait=True, cancel_futures=True)
                raise
    skipped = [(g[0], reason) for g, (c, reason) in zip(groups, results) if c is None]
    for src, reason in skipped:
        print(f"lipspace import: {'skipped' if args.skip_bad else 'cannot read'} {src}: {reason}", file=sys.stderr)
    parts = [c for c, _ in results if c is not None]
    if not parts:
        raise CliError(f"none of the {n} inputs could be read (first: {skipped[0][0]}: {skipped[0][1]}); "
                       "nothing was written")
    if skipped and not args.skip_bad:
        raise CliError(f"{len(skipped)} of {n} inputs could not be read (listed above); nothing was written. "
                       "Pass --skip-bad to write the corpus of the other inputs")
    if skipped:
        print(f"lipspace import: read {len(parts)} of {n} inputs, skipped {len(skipped)} (--skip-bad; listed "
              "above)", file=sys.stderr)
    return parts


def _read_on_dask(groups, job, address, results, tick):
    from app.cli import CliError

    try:
        from distributed import as_completed

        from engine.scale.executor import DaskExecutor
    except ImportError as exc:
        raise CliError(f"--dask needs the 'scale' extra ({exc}); "
                       "install it with pip install 'lipspace[scale]'") from None
    try:
        ex = DaskExecutor.connect(address)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    with ex:
        print(f"lipspace import: Dask {ex.describe()}", file=sys.stderr)
        futs = ex.client.map(read_one, groups, job=job, pure=False)
        index = {f.key: i for i, f in enumerate(futs)}
        for done, f in enumerate(as_completed(futs), 1):
            results[index[f.key]] = f.result()
            tick(done)


def speaker_of(path, how) -> str:
    """The speaker ``--speaker-from how`` gives ``path`` (:class:`engine.recordings.speakers.SpeakerRule`);
    "" for None."""
    if how is None:
        return ""
    from engine.recordings.speakers import SpeakerRule

    return SpeakerRule(how)(path)
