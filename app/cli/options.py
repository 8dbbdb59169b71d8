"""The command line's shared option groups, declared once for every subcommand.

``--preset`` / ``--kinematics`` (the synthetic talker), ``--seed``, ``-q`` and the manifold's
parameters (``lipspace build``) are added by the functions here, never by a subcommand's own
``add_argument``: one name, one set of choices and one default each. The manifold's defaults
come from :class:`engine.manifold.model.Manifold` itself (``Manifold().get_params()``) and its
choices and lower bounds from the estimator's ``_parameter_constraints``, so a change of the
estimator's default is the command line's default too.

This module is imported only when a subcommand's parser is built (``lipspace --help`` lists
the subcommands without importing any of them); the estimator is imported only by
:func:`add_manifold_options`.
"""
from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_talker_options", "add_seed_option", "add_quiet_option",
           "add_manifold_options", "manifold_defaults", "manifold_choices", "manifold_lower_bound"]

from app.files.source_loading import KINEMATICS_CHOICES, PRESETS


def add_talker_options(p: argparse.ArgumentParser, *, default: str = "default",
                       when: str = "when no corpus is given", kinematics: str | None = None) -> None:
    """``--preset`` (the synthetic talker used ``when`` no input is given) and, when ``kinematics``
    describes what the calibrated talker does here, ``--kinematics``."""
    p.add_argument("--preset", choices=PRESETS, default=default,
                   help=f"synthetic talker preset {when} (default: %(default)s)")
    if kinematics is not None:
        p.add_argument("--kinematics", choices=KINEMATICS_CHOICES, default=KINEMATICS_CHOICES[0],
                       help=f"the synthetic talker's kinematics {when}: 'calibrated' {kinematics} "
                            "(default: %(default)s)")


def add_seed_option(p: argparse.ArgumentParser, *, what: str | None = None) -> None:
    """``--seed``, at the manifold's default ``random_state``; ``what`` says what it seeds."""
    default = manifold_defaults()["random_state"]
    p.add_argument("--seed", type=int, default=default,
                   help=f"seed of {what or 'the manifold'} (default: %(default)s)")


def add_quiet_option(p: argparse.ArgumentParser, *, what: str = "no progress bars") -> None:
    """``-q`` / ``--quiet``: no progress bars on stderr."""
    p.add_argument("-q", "--quiet", action="store_true", help=what)


# --------------------------------------------------------------------------- the manifold's parameters
def manifold_defaults() -> dict[str, Any]:
    """:class:`~engine.manifold.model.Manifold`'s parameters at their defaults (``get_params()``)."""
    from engine.manifold.model import Manifold

    return Manifold().get_params()


def manifold_choices(param: str) -> tuple:
    """The strings ``param`` of the manifold accepts (its ``StrOptions`` constraint)."""
    from engine.constraints import StrOptions
    from engine.manifold.model import Manifold

    for c in Manifold._parameter_constraints[param]:
        if isinstance(c, StrOptions):
            return tuple(c.options)
    raise KeyError(f"Manifold's {param!r} is not one of a few strings")


def manifold_lower_bound(param: str) -> int | float | None:
    """The least value ``param`` of the manifold accepts (its ``Interval`` constraint), None when unbounded."""
    from engine.constraints import Interval
    from engine.manifold.model import Manifold

    for c in Manifold._parameter_constraints[param]:
        if isinstance(c, Interval):
            return c.left
    return None


def add_manifold_options(p: argparse.ArgumentParser) -> None:
    """The parameters of the manifold a build fits, at :class:`~engine.manifold.model.Manifold`'s defaults.

    ``args`` then holds them under the options' names; :func:`manifold_params` turns them into the
    estimator's keyword arguments.
    """
    d = manifold_defaults()
    p.add_argument("--variance", type=float, default=d["variance"],
                   help="shape variance kept (default: %(default)s)")
    p.add_argument("--embedding-dims", type=int, default=d["n_embedding"],
                   help="dimensions of Y (default: %(default)s)")
    p.add_argument("--method", choices=manifold_choices("embedding_method"), default=d["embedding_method"],
                   help="embedding method (default: %(default)s)")
    p.add_argument("--landmarks", type=int, default=d["n_landmarks"],
                   help="force the landmark embedding with this many landmarks (default: exact up to "
                        "--landmarks-above frames, 2000 landmarks above)")
    p.add_argument("--landmarks-above", type=int, default=d["landmarks_above"], metavar="N",
                   help="frames above which the landmark embedding is chosen (default: %(default)s)")
    p.add_argument("--states", type=int, default=d["n_states"], help="K, the number of states (default: about N/30)")
    p.add_argument("--neighbors", type=int, default=d["n_neighbors"],
                   help="frames each local tangent frame is fitted to (at least "
                        f"{manifold_lower_bound('n_neighbors')}; default: chosen for the corpus by held-out "
                        "validation, which 'lipspace info' reports)")
    p.add_argument("--speaker-norm", choices=manifold_choices("speaker_normalisation"),
                   default=d["speaker_normalisation"],
                   help="per-speaker normalisation before the shape space: each speaker's mean frame removed "
                        "(and spread scaled); auto = mean when utterances name 2+ speakers (default: %(default)s)")
    p.add_argument("--dynamics-scale", default=d["dynamics_scale"], metavar="max|pQ",
                   help="scale of each block of the dynamic features G: the largest entry (the paper's) or the "
                        "Q-th percentile of absolute values, e.g. p99, robust to outlying frames "
                        "(default: %(default)s)")
    add_seed_option(p)


#: Manifold parameter -> the ``args`` attribute :func:`add_manifold_options` stores it under
MANIFOLD_ARGS = {"variance": "variance", "n_embedding": "embedding_dims", "embedding_method": "method",
                 "n_landmarks": "landmarks", "n_states": "states", "n_neighbors": "neighbors",
                 "random_state": "seed", "speaker_normalisation": "speaker_norm",
                 "landmarks_above": "landmarks_above", "dynamics_scale": "dynamics_scale"}


def manifold_params(args: argparse.Namespace) -> dict[str, Any]:
    """The :class:`~engine.manifold.model.Manifold` keyword arguments the parsed ``args`` give."""
    return {param: getattr(args, dest) for param, dest in MANIFOLD_ARGS.items()}
