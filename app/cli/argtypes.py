"""The command line's option types: every value is checked as it is parsed, named by its option.

:func:`apply_types` runs over a subcommand's parser once its module has added its
arguments, so every command gets the same checks without each module repeating them:

* every text value (a file, a name, a phone string, an id) must not be empty: ``--manifold ''``
  used to fit the synthetic talker as if the option were absent, ``-o ''`` wrote nothing
  and said nothing;
* every whole number and number is parsed here: bounds per option (:data:`BOUNDS`: ``--seed``
  0 to 2^32 - 1, ``--states`` at least 1, ...), never NaN or infinite;
* comma lists (``--points UL,LL``, ``--test-ids``, ...: :data:`LISTS`) must name each item
  once and hold no empty item.

argparse prints a refusal as ``argument --seed: ...`` after the usage line: the option is
named in every message. What depends on the data (``--states`` above the number of
frames) is checked by the command; :func:`plain_words` rewrites what the engine says in
its parameters' names (``n_states``) into the options' (``--states``).
"""
from __future__ import annotations

import argparse
import math
import re

__all__ = ["text", "whole", "number", "name_list", "apply_types", "plain_words", "BOUNDS", "LISTS",
           "PARAMETER_OPTIONS"]

#: seeds scikit-learn accepts
SEED_MAX = 2**32 - 1
#: the largest whole number any option takes (what a 64-bit integer holds)
INT_MAX = 2**63 - 1


def text(value: str) -> str:
    """A text value that is not empty (nor only spaces)."""
    if not str(value).strip():
        raise argparse.ArgumentTypeError(f"{value!r}: expected a value, not an empty string")
    return value


def _num(v) -> str:
    return str(v) if isinstance(v, int) else f"{v:g}"


def _describe(lo, hi, unit="") -> str:
    u = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        return f"from {_num(lo)} to {_num(hi)}{u}"
    if lo is not None:
        return f"at least {_num(lo)}{u}"
    return f"at most {_num(hi)}{u}"


def whole(lo: int | None = None, hi: int | None = None, *, what: str = "", unit: str = ""):
    """A type for a whole number from ``lo`` to ``hi`` (inclusive; None: unbounded up to 2^63 - 1)."""
    hi_eff = INT_MAX if hi is None else hi
    lo_eff = -INT_MAX if lo is None else lo

    def parse(value: str) -> int:
        s = str(value).strip()
        if not re.fullmatch(r"[+-]?\d+", s):
            raise argparse.ArgumentTypeError(f"{value!r}: expected a whole number{' (' + what + ')' if what else ''}")
        v = int(s)
        if not lo_eff <= v <= hi_eff:
            bounds = _describe(lo, hi if hi is not None else (hi_eff if v > hi_eff else None), unit) \
                if lo is not None or v > hi_eff else _describe(None, hi_eff, unit)
            raise argparse.ArgumentTypeError(f"{s}: must be {bounds}{' (' + what + ')' if what else ''}")
        return v

    parse.__name__ = "whole number"
    return parse


def number(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False, what: str = "",
           unit: str = ""):
    """A type for a finite number from ``lo`` to ``hi`` (``lo_open``: above ``lo``)."""

    def parse(value: str) -> float:
        try:
            v = float(str(value).strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"{value!r}: expected a number{' (' + what + ')' if what else ''}") \
                from None
        bounds = _describe(lo, hi, unit) if lo is not None or hi is not None else ""
        if lo_open and lo is not None:
            bounds = f"above {_num(lo)}" + (f" and at most {_num(hi)}" if hi is not None else "") + \
                (f" {unit}" if unit else "")
        why = f"{' (' + what + ')' if what else ''}"
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{value}: must be a finite number{' ' + bounds if bounds else ''}{why}")
        if (lo is not None and (v <= lo if lo_open else v < lo)) or (hi is not None and v > hi):
            raise argparse.ArgumentTypeError(f"{value}: must be {bounds}{why}")
        return v

    parse.__name__ = "number"
    return parse


def name_list(*, keywords=(), what: str = "name", unique: bool = True, fold_case: bool = False):
    """A type for a comma (or space) separated list: no empty item and (``unique``) no item twice
    (``fold_case``: ``UL`` and ``ul`` are one name); returned as given.

    ``keywords`` (e.g. ``all``, ``lips``) are accepted alone."""

    def parse(value: str) -> str:
        s = str(value).strip()
        if not s:
            raise argparse.ArgumentTypeError(f"{value!r}: expected a comma-separated list of {what}s, not an empty "
                                             "string")
        if s in keywords:
            return value
        items = [t.strip() for t in re.split(r"[,\s]+", s) if t.strip()] if "," not in s else \
            [t.strip() for t in s.split(",")]
        if any(not t for t in items):
            raise argparse.ArgumentTypeError(f"{value}: holds an empty {what} (two commas in a row, or one at an "
                                             "end)")
        seen = set()
        for t in items if unique else ():
            key = t.lower() if fold_case else t
            if key in seen:
                raise argparse.ArgumentTypeError(f"{value}: names {t} twice; give each {what} once")
            seen.add(key)
        return value

    parse.__name__ = "list"
    return parse


#: (command or "*", option dest) -> the type of an int or float option
BOUNDS = {
    ("*", "seed"): whole(0, SEED_MAX, what="the random seed"),
    ("*", "states"): whole(1, what="states in the graph"),
    ("*", "state_dims"): whole(1, 256),
    ("*", "embedding_dims"): whole(3, 256, what="dimensions of Y; the paper uses 16"),
    ("build", "neighbors"): whole(3, 10**6, what="frames per tangent frame"),
    ("*", "neighbors"): whole(1, 10**6),
    ("*", "landmarks"): whole(10, 10**7, what="landmark frames"),
    ("*", "landmarks_above"): whole(1),
    ("*", "variance"): number(0, 1, lo_open=True, what="the share of shape variance kept, e.g. 0.99"),
    ("*", "test_fraction"): number(0, 1, lo_open=True, what="the share of utterances held out"),
    ("*", "smoothing"): number(0, 3600, unit="frames"),
    ("*", "candidates"): whole(1, 1000, what="states per phone"),
    ("*", "inverse_dims"): whole(1, 5, what="a Delaunay triangulation in more dimensions needs far more time and "
                                           "memory; the paper uses 3"),
    ("*", "spacing"): number(0, 60, lo_open=True, unit="seconds"),
    ("*", "tempo"): number(0.1, 10, what="1 = the duration model's own rate"),
    ("*", "gltf_scale"): number(0, 1e6, lo_open=True, what="0.001 turns millimetres into metres"),
    ("*", "dpi"): number(10, 1200),
    ("*", "crf"): whole(0, 51, what="0 is lossless"),
    ("*", "jobs"): whole(1, 4096, what="processes"),
    ("*", "block_frames"): whole(256, what="frames per block"),
    ("*", "dims"): whole(1, 256),
    ("*", "min_count"): whole(1),
    ("*", "fx"): whole(0),
    ("*", "rate"): number(0, lo_open=True, unit="Hz"),
    ("*", "interocular_mm"): number(0, lo_open=True, unit="mm"),
    ("*", "quality_threshold"): number(0, lo_open=True, what="in the units of the file's quality values, e.g. the "
                                                            "AG501's rms"),
    ("*", "quality_max_gap"): number(0, 1000, unit="ms", what="the longest run of suspect samples interpolated"),
}

#: (command or "*", option dest) -> the type of a list-valued text option
LISTS = {
    ("import", "points"): name_list(keywords=("all", "lips"), what="point", fold_case=True),
    ("evaluate", "test_ids"): name_list(what="utterance id"),
    ("clusters", "phones"): name_list(what="phone"),
    ("synthesize", "key_frames"): name_list(keywords=("kinematic",), what="frame"),
    ("synthesize", "states"): name_list(what="state", unique=False),  # a path may come back to a state
    ("figures", "only"): name_list(what="figure"),
}


def _lookup(table, command, dest):
    return table.get((command, dest), table.get(("*", dest)))


def apply_types(parser: argparse.ArgumentParser, command: str) -> None:
    """Give every option of ``command``'s ``parser`` its checked type (see the module docstring)."""
    for action in parser._actions:
        if action.nargs == 0 or action.option_strings and action.dest in ("help",):
            continue
        if isinstance(action, (argparse._StoreConstAction, argparse._StoreTrueAction, argparse._StoreFalseAction,
                               argparse._CountAction, argparse._HelpAction, argparse._VersionAction,
                               argparse.BooleanOptionalAction)):
            continue
        if action.type in (int, float):
            t = _lookup(BOUNDS, command, action.dest)
            if t is None:
                t = whole() if action.type is int else number()
            action.type = t
        elif action.type is None:
            action.type = _lookup(LISTS, command, action.dest) or text


#: engine parameter -> the option that sets it (for messages the engine words in its parameters)
PARAMETER_OPTIONS = {
    "n_states": "--states", "n_embedding": "--embedding-dims", "n_components": "--embedding-dims",
    "random_state": "--seed", "n_neighbors": "--neighbors", "n_landmarks": "--landmarks",
    "landmarks_above": "--landmarks-above", "state_dims": "--state-dims", "n_dims": "--state-dims",
    "variance": "--variance", "dynamics_scale": "--dynamics-scale", "speaker_normalisation": "--speaker-norm",
    "inverse_dims": "--inverse-dims", "n_candidates": "--candidates", "smoothing": "--smoothing",
}

_ADVICE = ((re.compile(r"\s*or None for the default"), " or leave the option out for the default"),
           (re.compile(r",?\s*or None \((?:all|chosen)[^)]*\)"), ""),
           (re.compile(r"; or pass None"), "; or leave the option out"),
           (re.compile(r"\bpass None\b"), "leave the option out"))


def plain_words(message: str, options=PARAMETER_OPTIONS) -> str:
    """``message`` with engine parameter names replaced by the options that set them, and
    Python advice ("None for the default") by the command line's."""
    for pattern, repl in _ADVICE:
        message = pattern.sub(repl, message)
    for name, opt in options.items():
        message = re.sub(rf"\b{re.escape(name)}\b(?:=)?", opt + " ", message).replace(opt + "  ", opt + " ")
    message = re.sub(r"\b[A-Z][A-Za-z]+: (?=--)", "", message)  # the estimator's class name, before its option
    return re.sub(r" +([,;.)])", r"\1", message)
