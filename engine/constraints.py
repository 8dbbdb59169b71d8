"""Parameter constraints of the engine's estimators, declared as data and checked in one call.

Every estimator class declares, after scikit-learn's ``_parameter_constraints``, what each
parameter of its ``__init__`` may hold: a list of constraints, any one of which a value must
satisfy::

    _parameter_constraints = {
        "n_components": [Interval(Integral, 1, None, closed="left")],
        "method": [StrOptions({"pca", "mds"})],
        "n_landmarks": [Interval(Integral, 2, None, closed="left"), None],
        "random_state": ["random_state"],
    }

A constraint is one of

* :class:`Interval` -- integers or finite real numbers between two limits;
* :class:`Options` / :class:`StrOptions` -- one of a few values;
* ``None`` -- None itself;
* ``"boolean"`` -- True or False (numpy's too);
* ``"random_state"`` -- a seed, an integer in 0..2**32 - 1, or None (what both
  ``numpy.random.default_rng`` and scikit-learn accept);
* ``callable`` -- any callable;
* a type -- any instance of it;
* :class:`HasMethods` -- an object with these methods (an estimator);
* :class:`Condition` -- a test a type cannot express (a pattern, a pair of pairs).

:func:`validate_params` checks every parameter of an estimator against its declaration;
estimators call it first thing in ``fit`` (and wherever a parameter is used before a fit).
A value no constraint accepts raises :class:`InvalidParameterError`, whose message names
the estimator, the parameter, what it must be, the value given and the default::

    ShapeSpace: variance must be in (0, 1], got 1.5; leave it out for the default 0.99

Limits that depend on the data (``n_components`` below the number of frames, a neighbourhood
smaller than the corpus) stay in ``fit``, next to the data they compare with.

:func:`invalid_values` derives values that break a declaration from the declaration itself,
so the common estimator test refuses them for every estimator that declares its constraints.
"""
from __future__ import annotations

import inspect
import math
import numbers
from numbers import Integral, Real
from typing import Any

import numpy as np

__all__ = ["Interval", "Options", "StrOptions", "HasMethods", "Condition", "InvalidParameterError",
           "validate_params", "invalid_values", "describe"]

#: the seeds ``"random_state"`` accepts (numpy's default_rng and scikit-learn's both take these)
_SEED_MAX = 2**32 - 1


class InvalidParameterError(ValueError, TypeError):
    """An estimator parameter no declared constraint accepts.

    A ``ValueError`` (and a ``TypeError``, for a value of the wrong type) whose message
    says what the parameter must be, the value given and the default to fall back on.

    Attributes
    ----------
    estimator : str
        The estimator's class name.
    parameter : str
    value : object
    allowed : str
        What the parameter must be ("an integer >= 1 or None").
    default : object
        The parameter's default (:data:`inspect.Parameter.empty` when it has none).
    """

    def __init__(self, estimator: str, parameter: str, value, allowed: str, default=inspect.Parameter.empty):
        self.estimator, self.parameter, self.value = estimator, parameter, value
        self.allowed, self.default = allowed, default
        super().__init__(f"{estimator}: {self.describe()}")

    def describe(self, name: str | None = None, *, fix: bool = True) -> str:
        """The message without the estimator, the parameter called ``name`` (default: its own name).

        A command line that sets the parameter from an option passes the option as typed
        (``exc.describe("--states")``); ``fix=False`` leaves out the default to fall back on
        (for a value read from a file, where leaving it out is no remedy).
        """
        name = self.parameter if name is None else name
        got = _short_repr(self.value)
        if not _plain(self.value):
            got += f" (a {type(self.value).__name__})"
        text = f"{name} must be {self.allowed}, got {got}"
        if fix and self.default is not inspect.Parameter.empty:
            text += f"; leave it out for the default {_short_repr(self.default)}"
        return text

    def __reduce__(self):  # rebuilt from its fields (Dask and multiprocessing pickle exceptions)
        return type(self), (self.estimator, self.parameter, self.value, self.allowed, self.default)


def _plain(value) -> bool:
    """Whether the value's repr already says its type (numbers, strings, None, booleans)."""
    return value is None or isinstance(value, (bool, np.bool_, numbers.Number, str))


def _short_repr(value, limit: int = 80) -> str:
    text = repr(value.item() if isinstance(value, np.generic) else value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


# ------------------------------------------------------------------ constraints
class _Constraint:
    """One way a value may be valid: ``is_satisfied_by``, a description, values that break it."""

    def is_satisfied_by(self, value) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def __str__(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def bad_values(self) -> list:
        """Values close to this constraint that it refuses (the common test tries them)."""
        return []


def _num(x) -> str:
    return str(int(x)) if isinstance(x, numbers.Integral) else f"{x:g}"


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


class Interval(_Constraint):
    """Numbers of ``type`` between ``left`` and ``right`` (None: unbounded on that side).

    Parameters
    ----------
    type : numbers.Integral or numbers.Real
        Integral: integers only (numpy's too; never booleans). Real: any finite real number,
        integers included (NaN and infinities are refused).
    left, right : number or None
    closed : {"left", "right", "both", "neither"}
        Which limits belong to the interval (keyword-only, as in scikit-learn).
    """

    def __init__(self, type, left, right, *, closed):
        if type not in (Integral, Real):
            raise TypeError(f"Interval type must be numbers.Integral or numbers.Real, got {type!r}")
        if closed not in ("left", "right", "both", "neither"):
            raise ValueError(f"closed must be 'left', 'right', 'both' or 'neither', got {closed!r}")
        if left is not None and right is not None and left > right:
            raise ValueError(f"an empty interval: left {left} > right {right}")
        self.type, self.left, self.right, self.closed = type, left, right, closed

    def _in_type(self, value) -> bool:
        if _is_bool(value) or not isinstance(value, self.type):
            return False
        return self.type is Integral or math.isfinite(float(value))

    def is_satisfied_by(self, value) -> bool:
        if not self._in_type(value):
            return False
        lo_ok = self.left is None or (value >= self.left if self.closed in ("left", "both") else value > self.left)
        hi_ok = self.right is None or (value <= self.right if self.closed in ("right", "both") else value < self.right)
        return bool(lo_ok and hi_ok)

    def __str__(self) -> str:
        # integers say so ("an integer >= 1"); numbers read as a range ("in (0, 1]", ">= 0")
        what = "an integer " if self.type is Integral else ""
        left_in, right_in = self.closed in ("left", "both"), self.closed in ("right", "both")
        if self.left is None and self.right is None:
            return what.strip() or "a finite number"
        if self.right is None:
            return f"{what}{'>=' if left_in else '>'} {_num(self.left)}"
        if self.left is None:
            return f"{what}{'<=' if right_in else '<'} {_num(self.right)}"
        if self.type is Integral and left_in and right_in:
            return f"{what}in {self.left}..{self.right}"
        return f"{what}in {'[' if left_in else '('}{_num(self.left)}, {_num(self.right)}{']' if right_in else ')'}"

    def bad_values(self) -> list:
        out = []
        step = 1 if self.type is Integral else 0.5
        if self.left is not None:
            out.append(self.left - step if self.closed in ("left", "both") else self.left)
        if self.right is not None:
            out.append(self.right + step if self.closed in ("right", "both") else self.right)
        if self.type is Integral:
            mid = (self.left if self.left is not None else 0) + 0.5
            out.append(float(mid))  # a number that is not an integer
        else:
            out += [float("nan"), float("inf")]
        return out


class Options(_Constraint):
    """One of a few values of ``type`` (compared with ``==``)."""

    def __init__(self, type, options):
        self.type = type
        self.options = tuple(sorted(options, key=repr)) if isinstance(options, (set, frozenset)) else tuple(options)

    def is_satisfied_by(self, value) -> bool:
        return isinstance(value, self.type) and not (_is_bool(value) and self.type is not bool) and \
            any(value == o for o in self.options)

    def __str__(self) -> str:
        opts = ", ".join(repr(o) for o in self.options)
        return opts if len(self.options) == 1 else f"one of {opts}"

    def bad_values(self) -> list:
        if issubclass(self.type, str):
            return ["not-an-option"]
        numeric = [o for o in self.options if isinstance(o, numbers.Real)]
        return [max(numeric) + 1] if numeric else []


class StrOptions(Options):
    """One of a few strings."""

    def __init__(self, options):
        super().__init__(str, options)


class HasMethods(_Constraint):
    """An object with all of ``methods`` (e.g. an estimator with ``fit`` and ``predict``)."""

    def __init__(self, methods):
        self.methods = (methods,) if isinstance(methods, str) else tuple(methods)

    def is_satisfied_by(self, value) -> bool:
        return all(callable(getattr(value, m, None)) for m in self.methods)

    def __str__(self) -> str:
        names = [f"{m}()" for m in self.methods]
        return "an object with " + (names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1])


class Condition(_Constraint):
    """Values ``test(value)`` accepts, for what a type or an interval cannot say.

    Parameters
    ----------
    test : callable
        ``test(value) -> bool``; an exception it raises counts as False.
    description : str
        What the test accepts, read after "must be" ("a percentile 'pQ' with 50 <= Q <= 100").
    bad : sequence
        A few values the test refuses (the common estimator test tries them).
    """

    def __init__(self, test, description: str, *, bad=()):
        self.test, self.description, self.bad = test, description, list(bad)

    def is_satisfied_by(self, value) -> bool:
        try:
            return bool(self.test(value))
        except Exception:  # noqa: BLE001 - a test that cannot read the value refuses it
            return False

    def __str__(self) -> str:
        return self.description

    def bad_values(self) -> list:
        return list(self.bad)


class _NoneConstraint(_Constraint):
    def is_satisfied_by(self, value) -> bool:
        return value is None

    def __str__(self) -> str:
        return "None"


class _Boolean(_Constraint):
    def is_satisfied_by(self, value) -> bool:
        return _is_bool(value)

    def __str__(self) -> str:
        return "True or False"

    def bad_values(self) -> list:
        return [0, "yes"]


class _Callable(_Constraint):
    def is_satisfied_by(self, value) -> bool:
        return callable(value)

    def __str__(self) -> str:
        return "a callable"


class _InstanceOf(_Constraint):
    def __init__(self, type):
        self.type = type

    def is_satisfied_by(self, value) -> bool:
        return isinstance(value, self.type)

    def __str__(self) -> str:
        name = self.type.__name__
        return f"{'an' if name[:1].lower() in 'aeiou' else 'a'} {name}"


def _make(constraint) -> _Constraint:
    """The constraint object a declaration entry stands for."""
    if isinstance(constraint, _Constraint):
        return constraint
    if constraint is None:
        return _NoneConstraint()
    if constraint == "boolean":
        return _Boolean()
    if constraint == "random_state":
        return Condition(lambda v: v is None or Interval(Integral, 0, _SEED_MAX, closed="both").is_satisfied_by(v),
                         f"a seed (an integer in 0..{_SEED_MAX}) or None", bad=[-1, 0.5])
    if constraint is callable:
        return _Callable()
    if isinstance(constraint, type):
        return _InstanceOf(constraint)
    raise TypeError(f"unknown parameter constraint {constraint!r}")


def describe(constraints) -> str:
    """What a parameter declared with ``constraints`` must be: "A, B or C"."""
    parts = [str(_make(c)) for c in constraints]
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " or " + parts[-1]


# ------------------------------------------------------------------ checking
def _defaults(cls) -> dict:
    return {name: p.default for name, p in inspect.signature(cls.__init__).parameters.items()
            if p.kind == p.KEYWORD_ONLY or p.kind == p.POSITIONAL_OR_KEYWORD}


def validate_params(estimator, names=None) -> None:
    """Check the parameters of ``estimator`` against its class's ``_parameter_constraints``.

    Parameters
    ----------
    estimator : engine.estimator.Estimator
    names : iterable of str, optional
        Only these parameters (default: every declared one).

    Raises
    ------
    InvalidParameterError
        For the first parameter (in ``__init__`` order) no declared constraint accepts.
    """
    cls = type(estimator)
    declared = getattr(cls, "_parameter_constraints", {})
    params = estimator.get_params(deep=False)
    wanted = None if names is None else set(names)
    for name, value in params.items():
        if name not in declared or (wanted is not None and name not in wanted):
            continue
        allowed = [_make(c) for c in declared[name]]
        if any(c.is_satisfied_by(value) for c in allowed):
            continue
        raise InvalidParameterError(cls.__name__, name, value, describe(declared[name]),
                                    _defaults(cls).get(name, inspect.Parameter.empty))


class _Unusable:
    """A value no declared constraint should accept (except a bare ``object`` type)."""

    def __repr__(self) -> str:
        return "<unusable object>"


def invalid_values(constraints) -> list:
    """Values a parameter declared with ``constraints`` refuses, derived from the constraints.

    Each constraint's near misses (a limit crossed, NaN, a string that is no option, ...)
    and a few values of other types, less every value some constraint accepts.
    """
    made = [_make(c) for c in constraints]
    candidates = [v for c in made for v in c.bad_values()] + [True, "invalid", [1], _Unusable()]
    out: list[Any] = []
    for v in candidates:
        if not any(c.is_satisfied_by(v) for c in made) and not any(v is w or _same(v, w) for w in out):
            out.append(v)
    return out


def _same(a, b) -> bool:
    try:
        return type(a) is type(b) and bool(a == b)
    except Exception:  # noqa: BLE001 - arrays and odd objects are never "the same" candidate
        return False
