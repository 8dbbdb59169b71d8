"""The ``lipspace`` command: one entry point, one module per subcommand.

Each subcommand lives in ``app/cli/<name>.py`` and defines ``add_arguments(parser)``
and ``run(args) -> int``. Modules are imported only when their subcommand runs, so
``lipspace info`` never loads Qt.
"""
from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import os
import re
import signal
import stat
import sys
import threading
import warnings
from pathlib import Path

from engine.progress import Cancelled

__all__ = ["main", "SUBCOMMANDS"]

#: name -> (module, one-line help)
SUBCOMMANDS = {
    "explore": ("app.cli.explore",
                "open the explorer GUI (default; the embedded synthetic corpus if no file is given)"),
    "build": ("app.cli.build", "fit a manifold from a corpus (or the synthetic talker) and save it"),
    "info": ("app.cli.info", "summarise a corpus or manifold file"),
    "synthesize": ("app.cli.synthesize", "synthesise a lip trajectory from phones, a TextGrid or text"),
    "evaluate": ("app.cli.evaluate", "held-out synthesis evaluation table, every method"),
    "clusters": ("app.cli.clusters", "phone cluster statistics table"),
    "table": ("app.cli.table", "per-frame table (CSV, Parquet) and Praat TextGrids of a manifold"),
    "figures": ("app.cli.figures", "render the paper's figure set in batch"),
    "import": ("app.cli.importer", "convert a foreign corpus format to the native corpus file"),
    "render": ("app.cli.render", "render a synthesised utterance as an MP4 video with its audio"),
    "cache": ("app.cli.cache", "show the cache folder and its size; --clear empties it"),
    "compare": ("app.cli.compare", "compare levels of a field (speakers, emotions, groups) on one manifold"),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``lipspace`` parser. Only ``command``'s module is imported (the others, and
    all of them for ``lipspace --help``, are listed with their help line): ``lipspace
    synthesize`` does not pay for the figure modules' imports."""
    parser = _Parser(
        prog="lipspace",
        description="Explore the visual speech manifold: lip shape and velocity in one space.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (modname, help_) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        if name != command:  # `lipspace --help` lists the commands without importing any of them
            continue
        mod = importlib.import_module(modname)
        mod.add_arguments(p)
        if any(a.dest in OUTPUT_FILE_ARGS + OUTPUT_DIR_ARGS for a in p._actions):
            p.add_argument("--force", action="store_true",
                           help="replace output files that already exist (default: refuse, naming them, and "
                                "write nothing)")
        from app.cli.argtypes import apply_types

        apply_types(p, name)  # every value checked as it is parsed, its option named in the message
        p.set_defaults(_run=mod.run)
    return parser


class _Parser(argparse.ArgumentParser):
    """argparse's parser with its refusals on one line: what is wrong, the option, where the options are
    listed (the usage block above every error buried the one line that mattered)."""

    def error(self, message):
        message = re.sub(r"^argument ([^:]+): ", r"\1 ", message)  # '--seed -1: must be ...'
        self.exit(2, f"{self.prog}: error: {printable(message)} ('{self.prog} --help' lists the options)\n")


#: arguments naming files a command writes / directories it writes into
OUTPUT_FILE_ARGS = ("output", "csv", "markdown", "praat", "figure", "quality_report")
OUTPUT_DIR_ARGS = ("outdir", "mesh_dir", "audio_dir", "textgrid_dir")


def main(argv=None) -> int:
    """Run one subcommand; the exit status (0 ok, 1 nothing succeeded, 2 error, 128 + signal)."""
    from engine.files.staging import committed

    caught = _CAUGHT
    caught.clear()
    before = len(committed())
    with _guarded_streams() as streams:
        _tolerant_streams()
        rc = _main(argv, caught)
        if caught and rc < 128:
            # the signal came while the outputs were moved into place (deferred), or its
            # KeyboardInterrupt was swallowed where Python ignores exceptions (a weakref callback
            # during an import): the command did not stop, say so
            print(f"lipspace: {caught[-1]} arrived when the command could no longer stop; "
                  "it ran to its end (its output is complete).", file=sys.stderr)
        rc = streams.finish(rc, committed()[before:])
    return rc


class _GuardedStream:
    """A text stream whose write errors never stop the command: the first is kept (``failed``), the
    rest of the text is dropped. A full disk or a closed descriptor behind stdout must not throw a
    finished result away (``build ... > /dev/full``), nor a closed stderr fail a command that
    worked (``import ... 2>&-``)."""

    def __init__(self, stream, closed: bool = False):
        self._stream = stream
        self.failed: OSError | None = OSError(errno.EBADF, "it is closed") if closed else None

    def write(self, text):
        if self.failed is None:
            try:
                return self._stream.write(text)
            except (OSError, ValueError) as exc:  # ValueError: a closed file object
                self.failed = exc if isinstance(exc, OSError) else OSError(errno.EBADF, "it is closed")
        return len(text)

    def flush(self):
        if self.failed is None:
            try:
                self._stream.flush()
            except (OSError, ValueError) as exc:
                self.failed = exc if isinstance(exc, OSError) else OSError(errno.EBADF, "it is closed")

    def __getattr__(self, name):
        return getattr(self._stream, name)


class _StreamGuard:
    """What :func:`_guarded_streams` yields: :meth:`finish` turns a lost stdout into one line and an exit status."""

    def __init__(self, out: _GuardedStream, err: _GuardedStream):
        self.out, self.err = out, err

    def finish(self, rc: int, written) -> int:
        """The exit status once the command ended with ``rc`` having written ``written``.

        Standard output that could not be written (a full disk, a closed descriptor) is said on
        stderr; the status stays the command's when it wrote its files (the report was what was
        lost), else 1 (the report was the result). A reader that went away (``info | head``)
        is not an error."""
        self.out.flush()
        exc = self.out.failed
        if exc is None or isinstance(exc, BrokenPipeError) or rc != 0:
            return rc
        why = exc.strerror or str(exc)
        files = f"; {', '.join(written[:3])}{' ...' if len(written) > 3 else ''} written" if written else ""
        print(f"lipspace: standard output could not be written ({why}){files}; what the command reports there "
              "was lost", file=sys.stderr)
        return rc if written else 1


@contextlib.contextmanager
def _guarded_streams():
    """stdout and stderr wrapped in :class:`_GuardedStream` for the command, restored afterwards. A
    standard descriptor closed by the caller (``>&-``) gets /dev/null first, so that no file the
    command opens takes its number (its bytes would go to the terminal's stream)."""
    closed = []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            with contextlib.suppress(OSError):
                null = os.open(os.devnull, os.O_RDWR)
                if null != fd:
                    os.dup2(null, fd)
                    os.close(null)
                closed.append(fd)
    old_out, old_err = sys.stdout, sys.stderr
    out = _GuardedStream(old_out if old_out is not None else open(os.devnull, "w"), closed=1 in closed)  # noqa: SIM115
    err = _GuardedStream(old_err if old_err is not None else open(os.devnull, "w"), closed=2 in closed)  # noqa: SIM115
    sys.stdout, sys.stderr = out, err
    try:
        yield _StreamGuard(out, err)
    finally:
        sys.stdout, sys.stderr = old_out, old_err
        if out.failed is not None and old_out is not None:
            with contextlib.suppress(OSError):  # keep Python from failing to flush it again at exit
                sys.stdout = open(os.devnull, "w")  # noqa: SIM115


#: names of the signals that asked this command to stop (the handler appends; progress checks)
_CAUGHT: list = []


def stop_requested() -> bool:
    """True once SIGINT, SIGTERM or SIGHUP asked the running command to stop."""
    return bool(_CAUGHT)


def _tolerant_streams() -> None:
    """A terminal that cannot show every character (PYTHONIOENCODING=ascii, a C locale) gets
    ``\\xe9``-style escapes instead of an error after the work is done."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(AttributeError, ValueError, OSError):
            if (stream.encoding or "").lower().replace("-", "") not in ("utf8", "utf16", "utf32"):
                stream.reconfigure(errors="backslashreplace")


def _main(argv, caught) -> int:
    from engine.files.staging import committed

    before = len(committed())
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and _unknown_command(argv[0]):
        print(f"lipspace: error: {_unknown_command(argv[0])}", file=sys.stderr)
        return 2
    if not argv or argv[0] not in SUBCOMMANDS and argv[0] not in ("-h", "--help"):
        argv = ["explore", *argv]
    with _signals_as_interrupt(caught):
        try:
            args = argparse.Namespace(command=argv[0])
            parser = build_parser(argv[0] if argv[0] in SUBCOMMANDS else None)
            try:
                args = parser.parse_args(argv)
            except SystemExit as exc:  # --help (0) or a refused argument (2, said on stderr)
                return exc.code if isinstance(exc.code, int) else 2
            args._typed = _typed_options(parser, argv)
            _check_paths(args, args._typed)
            with _engine_warnings_to_stderr(args.command):
                with _printable_stdout():
                    return int(args._run(args) or 0)
        except (Cancelled, KeyboardInterrupt):
            what = f"stopped by {caught[-1]}" if caught and caught[-1] != "SIGINT" else "interrupted"
            done = committed()[before:]
            wrote = (f"{len(done)} file(s) had been written already ({', '.join(done[:3])}"
                     f"{', ...' if len(done) > 3 else ''})" if done else "nothing was written")
            print(f"lipspace: {what}; {wrote}.", file=sys.stderr)
            return 128 + (caught_signum(caught) or 2)
        except CliError as exc:
            print(f"lipspace {args.command}: error: {printable(str(exc))}", file=sys.stderr)
            return 2
        except MemoryError as exc:
            size = _memory_size(exc)
            where = f" {exc}" if str(exc).startswith("while reading ") else ""  # the input that did not fit
            print(f"lipspace {args.command}: error: out of memory{where}{size}. "
                  f"{MEMORY_HINTS.get(args.command, MEMORY_HINTS['build'])}", file=sys.stderr)
            return 2
        except BrokenPipeError:  # the reader went away (lipspace info | head): not an error
            with contextlib.suppress(OSError):
                sys.stdout = open(os.devnull, "w")  # noqa: SIM115 (keep Python from failing at exit)
            return 0
        except OSError as exc:  # disk full, permission denied, a directory where a file was expected ...
            print(f"lipspace {args.command}: error: {_os_error_text(exc)}", file=sys.stderr)
            return 2


MEMORY_HINTS = {
    "build": "Use a landmark embedding (--landmarks 2000) or a corpus imported at a lower rate "
             "('lipspace import --resample 30').",
    "import": "Split a long recording into several files, import fewer files at once, or use a lower "
              "--resample rate.",
    "figures": "Use a lower --dpi or fewer figures (--only).",
    "synthesize": "Use fewer inverse-map dimensions (--inverse-dims 3) or shorter input.",
}


def _memory_size(exc) -> str:
    """' (needed 15.6 GB more at once; this computer has 8.0 GB)', or '' when the error does not say."""
    from app.out_of_memory import format_bytes, installed_bytes, requested_bytes

    need, have = requested_bytes(exc), installed_bytes()
    if not need:
        return ""
    ram = f"; this computer has {format_bytes(have)}" if have else ""
    return f" (needed {format_bytes(need)} more at once{ram})"


#: control characters that could drive the terminal (escape sequences in a corpus name, ...)
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def printable(text: str) -> str:
    """``text`` with terminal control characters shown as ``\\xNN`` (newlines and tabs kept)."""
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", text)


#: on stderr a carriage return is kept: progress bars redraw their line with it
_CONTROL_STDERR = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]")


class _PrintableWriter:
    """A text stream wrapper that passes :func:`printable` text to ``stream``."""

    def __init__(self, stream, pattern=_CONTROL):
        self._stream = stream
        self._pattern = pattern

    def write(self, text):
        text = self._pattern.sub(lambda m: f"\\x{ord(m.group()):02x}", text)
        try:
            return self._stream.write(text)
        except UnicodeEncodeError:  # a terminal that cannot show a character: its escape instead
            enc = getattr(self._stream, "encoding", None) or "ascii"
            return self._stream.write(text.encode(enc, "backslashreplace").decode(enc))

    def __getattr__(self, name):
        return getattr(self._stream, name)


@contextlib.contextmanager
def _printable_stdout():
    """Commands print names and labels from the user's files (on stdout, and in notes
    and warnings on stderr): never raw escape codes."""
    old, old_err = sys.stdout, sys.stderr
    sys.stdout = _PrintableWriter(old)
    sys.stderr = _PrintableWriter(old_err, _CONTROL_STDERR)
    try:
        yield
    finally:
        sys.stdout, sys.stderr = old, old_err


def _os_error_text(exc: OSError) -> str:
    from engine.files.staging import OutputRefusedError, user_path

    if isinstance(exc, OutputRefusedError):
        return str(exc)
    text = exc.strerror or str(exc)
    name = user_path(exc.filename) if exc.filename is not None else ""  # never a temporary file's name
    if not exc.strerror:
        return str(exc)
    hint = {errno.ENOSPC: " (the disk is full: free space or write elsewhere); nothing was written",
            errno.EDQUOT: " (the disk quota is used up); nothing was written",
            errno.EROFS: " (a read-only file system: write elsewhere); nothing was written",
            errno.EACCES: " (no permission: write elsewhere)"}.get(exc.errno, "")
    return f"{name}: {text}{hint}" if name else f"{text}{hint}"


#: non-empty while the outputs of a command are moved into place (a stop signal waits for the end)
_DEFERRED: list = []


@contextlib.contextmanager
def signals_deferred():
    """Stop signals arriving inside the block are noted, not raised: the block (moving a command's
    finished outputs into place) completes, so that what is on disk is all new or all old; the
    command then ends normally and :func:`main` says the signal came too late to stop it."""
    _DEFERRED.append(True)
    try:
        yield
    finally:
        _DEFERRED.pop()


def caught_signum(caught) -> int | None:
    if not caught:
        return None
    return {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM, "SIGHUP": signal.SIGHUP}.get(caught[-1])


@contextlib.contextmanager
def _signals_as_interrupt(caught: list):
    """SIGTERM and SIGHUP stop a command the way Ctrl-C does: temp files are removed,
    nothing half-written stays, one line is printed. Only in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        caught.append(signal.Signals(signum).name)
        if not _DEFERRED:  # outputs being moved into place: finish that, then end normally
            raise KeyboardInterrupt

    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        if sig is not None:
            old[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def _unknown_command(word: str) -> str | None:
    """Why ``word`` (the first argument) cannot be run, when it looks like a mistyped command rather than a
    file for the explorer: a plain word naming no command and no file. None otherwise."""
    import difflib

    if word in SUBCOMMANDS or word.startswith("-") or os.path.lexists(word):
        return None
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", word):
        return None  # a path or a file name: the explorer says whether it exists
    close = difflib.get_close_matches(word, SUBCOMMANDS, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else "."
    return (f"unknown command '{word}'{hint} The commands are {', '.join(SUBCOMMANDS)} ('lipspace --help' says what "
            "each does); a file to open in the explorer must exist")


def _typed_options(parser, argv) -> dict:
    """``{dest: the option string the user typed}`` (``-o`` or ``--output``; a positional argument by its
    name in the usage line, e.g. ``CORPUS``), for messages."""
    typed = {}
    sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    p = sub.choices.get(argv[0]) if sub is not None and argv else None
    for action in p._actions if p is not None else []:
        if not action.option_strings:
            typed[action.dest] = str(action.metavar or action.dest).upper()
        for opt in action.option_strings:
            if any(a == opt or a.startswith(opt + "=") for a in argv[1:]):
                typed[action.dest] = opt
    return typed


def _check_paths(args, typed=None) -> None:
    """Refuse before any work: an output that is one of the command's inputs (it would be
    destroyed), two outputs naming one file, an output file that exists (without ``--force``;
    a dangling symbolic link exists too), an output that is a pipe, socket or device (never
    replaced, ``--force`` or not), a file output naming a directory (or the reverse), and
    inputs that are not regular files or directories (a FIFO would block forever). Options are
    named as typed (``typed``: dest -> option). Outputs a command derives (the WAV beside a
    ``.glb``, the table beside a ``--praat`` TextGrid) are checked the same way when the
    command reserves them (:class:`engine.files.staging.Outputs`)."""
    from engine.files.placing import output_kind

    typed = typed or {}
    outputs, inputs = [], []
    for name, value in vars(args).items():
        if name.startswith("_") or value is None or isinstance(value, bool):
            continue
        values = value if isinstance(value, list) else [value]
        if not all(isinstance(v, str) for v in values):
            continue
        if name in OUTPUT_FILE_ARGS or name in OUTPUT_DIR_ARGS:
            outputs += [(name, Path(v)) for v in values]
        else:
            inputs += [(name, Path(v)) for v in values]

    def opt(name):
        return typed.get(name, "--" + name.replace("_", "-"))

    for _name, p in inputs:
        try:
            st = os.stat(p)
        except (OSError, ValueError):
            continue  # not a path (a phone string, a preset) or missing: the command says so
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
            raise CliError(f"{p}: not a regular file (a pipe, socket or device); give a file on disk")
    force = bool(getattr(args, "force", False))
    real = {}
    for name, p in outputs:
        with contextlib.suppress(OSError, ValueError):
            r = os.path.realpath(p)
            if r in real:
                raise CliError(f"{opt(real[r])} and {opt(name)} both name {p}; it would be written twice (the second "
                               "over the first). Give each output its own name")
            real[r] = name
    for name, p in outputs:
        kind = output_kind(p)
        if name in OUTPUT_FILE_ARGS and kind == "directory":
            raise CliError(f"{opt(name)} {p}: is a directory; give a file name")
        if kind not in (None, "file", "link", "directory"):
            raise CliError(f"{opt(name)} {p}: is {kind}, not a regular file; Lipspace writes only regular files "
                           "(--force replaces only those). Choose a file name")
        for iname, q in inputs:
            with contextlib.suppress(OSError, ValueError):
                if os.path.lexists(q) and (os.path.realpath(p) == os.path.realpath(q) or
                                           p.exists() and os.path.samefile(p, q)):
                    raise CliError(f"{opt(name)} {p} is also an input ({opt(iname)}); writing it would destroy the "
                                   "input. Choose another output name")
        if name in OUTPUT_FILE_ARGS and kind is not None and not force:
            what = "already exists" if kind == "file" else "already exists (a symbolic link)"
            raise CliError(f"{opt(name)} {p}: {what}; nothing was written. Pass --force to replace it, or choose "
                           "another name")
        if name in OUTPUT_DIR_ARGS and kind is not None and kind != "directory" and p.exists() and not p.is_dir():
            raise CliError(f"{opt(name)} {p}: exists and is not a directory")


@contextlib.contextmanager
def _engine_warnings_to_stderr(command):
    """Print warnings as one clean line each: the engine's own (e.g. a disconnected state graph)
    tell the user something about their data, so the command goes on; a numerical warning
    (overflow in a product, ...) says so, without the source file and line that mean
    nothing to the user."""
    from engine.recordings.corpus import CorpusWarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, CorpusWarning):
            print(f"lipspace {command}: warning: {printable(str(message))}", file=sys.stderr)
        elif issubclass(category, RuntimeWarning):
            print(f"lipspace {command}: warning: numerical trouble ({printable(str(message))}); the data may hold "
                  "values far outside the range of the others", file=sys.stderr)
        else:
            print(f"lipspace {command}: warning: {printable(str(message))}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", CorpusWarning)
        warnings.showwarning = show
        yield


class CliError(Exception):
    """A user-facing error: printed without a traceback, exit status 2."""
