"""Every subcommand's options as the user sees them: names, defaults, choices, requiredness.

``data/parser_defaults.json`` was written from the parsers as they were before the shared
option groups (:mod:`app.cli.options`) replaced each subcommand's own declarations; a change
of an option's name, default or choices fails here. Regenerate it deliberately with
``python tests/cli/test_cli_parser_defaults.py`` when an option is meant to change.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from app.cli import SUBCOMMANDS

SNAPSHOT = Path(__file__).with_name("data") / "parser_defaults.json"


def _described(value):
    """A default or choice as JSON keeps it (tuples as lists, numbers and strings as they are)."""
    if isinstance(value, dict):
        return {str(k): _described(v) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return [_described(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return repr(value)


def parser_options() -> dict:
    """{subcommand: {dest: {options, default, choices, required, nargs, metavar}}} from the live parsers."""
    from app.cli import build_parser

    out = {}
    for name in SUBCOMMANDS:
        parser = build_parser(name)
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
        options = {}
        for a in sub._actions:
            if a.dest in (argparse.SUPPRESS, "help"):
                continue
            options[a.dest] = {"options": list(a.option_strings), "default": _described(a.default),
                               "choices": _described(list(a.choices)) if a.choices is not None else None,
                               "required": bool(a.required), "nargs": _described(a.nargs),
                               "metavar": _described(a.metavar), "action": type(a).__name__}
        groups = [sorted(x.dest for x in g._group_actions) for g in sub._mutually_exclusive_groups]
        out[name] = {"options": options, "exclusive": sorted(groups), "defaults": _described(
            {k: v for k, v in sorted(sub._defaults.items()) if not k.startswith("_")})}
    return out


@pytest.mark.parametrize("command", sorted(SUBCOMMANDS))
def test_subcommand_options_and_defaults_unchanged(command):
    want = json.loads(SNAPSHOT.read_text(encoding="utf-8"))[command]
    got = json.loads(json.dumps(parser_options()[command]))
    assert got["defaults"] == want["defaults"]
    assert got["exclusive"] == want["exclusive"]
    assert sorted(got["options"]) == sorted(want["options"])
    for dest, spec in want["options"].items():
        assert got["options"][dest] == spec, dest


def test_every_subcommand_is_in_the_snapshot():
    assert sorted(SUBCOMMANDS) == sorted(json.loads(SNAPSHOT.read_text(encoding="utf-8")))


if __name__ == "__main__":
    SNAPSHOT.write_text(json.dumps(parser_options(), indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {SNAPSHOT}")


def test_build_defaults_are_the_manifolds():
    """`lipspace build`'s manifold options are declared from the estimator: its defaults and choices."""
    from app.cli.options import MANIFOLD_ARGS, manifold_choices
    from engine.manifold.model import Manifold

    build = parser_options()["build"]["options"]
    params = Manifold().get_params()
    for param, dest in MANIFOLD_ARGS.items():
        assert build[dest]["default"] == params[param], dest
    assert build["method"]["choices"] == list(manifold_choices("embedding_method"))
    assert build["speaker_norm"]["choices"] == list(manifold_choices("speaker_normalisation"))


def test_no_subcommand_imports_another_ones_private_names():
    """Steps two commands share live in a module of their own (app/cli/synthesis_steps.py), not behind
    an underscore in one of them."""
    import ast

    import app.cli

    for path in sorted(Path(app.cli.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("app.cli."):
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports {private} from {node.module}"


def test_build_makes_its_plan_once(tiny_manifold_file, tmp_path, monkeypatch):
    from app.cli import main
    from engine.manifold import buildplan

    calls = []
    real = buildplan.plan_build

    def counted(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(buildplan, "plan_build", counted)
    corpus = tiny_manifold_file.parent / "corpus.npz"
    assert main(["build", str(corpus), "-o", str(tmp_path / "m.npz"), "--states", "20", "-q",
                 "--no-method-choice"]) == 0
    assert len(calls) == 1
