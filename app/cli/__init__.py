"""The ``lipspace`` command: one entry point, one module per subcommand.

Each subcommand lives in ``app/cli/<name>.py`` and defines ``add_arguments(parser)``
and ``run(args) -> int``. Modules are imported only when their subcommand runs, so
``lipspace info`` never loads Qt.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import sys
import warnings

from engine.progress import Cancelled

__all__ = ["main", "SUBCOMMANDS"]

#: name -> (module, one-line help)
SUBCOMMANDS = {
    "explore": ("app.cli.explore", "open the explorer GUI (default; the embedded synthetic corpus if no file is given)"),
    "build": ("app.cli.build", "fit a manifold from a corpus (or the synthetic talker) and save it"),
    "info": ("app.cli.info", "summarise a corpus or manifold file"),
    "synthesize": ("app.cli.synthesize", "synthesise a lip trajectory from phones, a TextGrid or text"),
    "evaluate": ("app.cli.evaluate", "held-out synthesis evaluation table, every method"),
    "clusters": ("app.cli.clusters", "phone cluster statistics table"),
    "figures": ("app.cli.figures", "render the paper's figure set in batch"),
    "import": ("app.cli.importer", "convert a foreign corpus format to the native corpus file"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="lipspace",
        description="Explore the visual speech manifold: lip shape and velocity in one space.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (modname, help_) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        mod = importlib.import_module(modname)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in SUBCOMMANDS and argv[0] not in ("-h", "--help"):
        argv = ["explore", *argv]
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with _engine_warnings_to_stderr(args.command):
            return int(args._run(args) or 0)
    except (Cancelled, KeyboardInterrupt):
        print("lipspace: interrupted; nothing was written.", file=sys.stderr)
        return 130
    except CliError as exc:
        print(f"lipspace {args.command}: error: {exc}", file=sys.stderr)
        return 2


@contextlib.contextmanager
def _engine_warnings_to_stderr(command):
    """Print the engine's own warnings (e.g. a disconnected state graph) as one clean line each.

    They tell the user something about their data, so the command goes on; other
    libraries' warnings keep Python's default handling.
    """
    from engine.corpus import CorpusWarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, CorpusWarning):
            print(f"lipspace {command}: warning: {message}", file=sys.stderr)
        else:
            _default_show(message, category, filename, lineno, file, line)

    _default_show = warnings.showwarning
    with warnings.catch_warnings():
        warnings.simplefilter("always", CorpusWarning)
        warnings.showwarning = show
        yield


class CliError(Exception):
    """A user-facing error: printed without a traceback, exit status 2."""
