"""The base of the engine's estimators: scikit-learn's estimator API without importing scikit-learn.

Every engine estimator takes its parameters as keyword arguments stored unchanged under their
own names, learns in ``fit`` (which returns ``self``) and keeps what it learnt in attributes
ending in ``_``. :class:`Estimator` gives such a class what :class:`sklearn.base.BaseEstimator`
gives it — ``get_params`` / ``set_params`` (nested ``a__b`` names included), a ``repr`` naming
the parameters that differ from their defaults — so :func:`sklearn.base.clone`, grid searches
and pipelines take engine estimators as they take scikit-learn's. :func:`check_is_fitted` and
:class:`NotFittedError` follow scikit-learn's too.

Importing scikit-learn costs 1-1.5 s (it imports SciPy's statistics, and pandas when installed)
and loading a fitted manifold needs none of it: the explorer shows a manifold without it, and
the estimators that use scikit-learn's algorithms (k-means, nearest neighbours) import them
where they use them.
"""
from __future__ import annotations

import inspect
from typing import Any

__all__ = ["Estimator", "NotFittedError", "check_is_fitted", "clone"]


class NotFittedError(ValueError, AttributeError):
    """A method that needs a fit was called before ``fit`` (a ValueError and an AttributeError, as
    scikit-learn's ``NotFittedError`` is)."""


class Estimator:
    """Parameters, ``get_params`` / ``set_params`` and ``repr`` of an estimator (scikit-learn's API).

    A subclass names every parameter as a keyword of ``__init__`` (no ``*args``) and stores each
    under its own name unchanged; validation belongs in ``fit``.
    """

    @classmethod
    def _get_param_names(cls) -> list[str]:
        """The names of the parameters of ``__init__``, sorted."""
        init = cls.__init__
        if init is object.__init__:
            return []
        params = [p for p in inspect.signature(init).parameters.values()
                  if p.name != "self" and p.kind != p.VAR_KEYWORD]
        for p in params:
            if p.kind == p.VAR_POSITIONAL:
                raise RuntimeError(f"{cls.__name__}.__init__ takes *{p.name}: an estimator names every "
                                   "parameter as a keyword")
        return sorted(p.name for p in params)

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The estimator's parameters.

        Parameters
        ----------
        deep : bool, default=True
            Also the parameters of parameters that are estimators, as ``name__parameter``.

        Returns
        -------
        dict
        """
        out: dict[str, Any] = {}
        for key in self._get_param_names():
            value = getattr(self, key)
            if deep and hasattr(value, "get_params") and not isinstance(value, type):
                out.update((f"{key}__{k}", v) for k, v in value.get_params().items())
            out[key] = value
        return out

    def set_params(self, **params: Any) -> Estimator:
        """Set parameters (``name`` or, for a parameter that is an estimator, ``name__parameter``).

        Returns
        -------
        self

        Raises
        ------
        ValueError
            For a name that is no parameter; the message lists the valid ones.
        """
        if not params:
            return self
        valid = self.get_params(deep=True)
        nested: dict[str, dict[str, Any]] = {}
        for key, value in params.items():
            name, sep, sub = key.partition("__")
            if name not in valid:
                raise ValueError(f"invalid parameter {name!r} for {type(self).__name__}; valid parameters: "
                                 f"{', '.join(self._get_param_names())}")
            if sep:
                nested.setdefault(name, {})[sub] = value
            else:
                setattr(self, name, value)
                valid[name] = value
        for name, sub_params in nested.items():
            valid[name].set_params(**sub_params)
        return self

    def __repr__(self) -> str:
        sig = inspect.signature(type(self).__init__).parameters
        shown = []
        for key, value in self.get_params(deep=False).items():
            default = sig[key].default if key in sig else inspect.Parameter.empty
            if default is not inspect.Parameter.empty and _same(value, default):
                continue
            shown.append(f"{key}={value!r}")
        return f"{type(self).__name__}({', '.join(shown)})"


def _same(value: Any, default: Any) -> bool:
    """Whether a parameter's value is its default (arrays and estimators never are, unless identical)."""
    if value is default:
        return True
    if type(value) is not type(default) or hasattr(value, "get_params") or hasattr(value, "shape"):
        return False
    try:
        return bool(value == default)
    except (TypeError, ValueError):
        return False


def check_is_fitted(estimator: Any, attributes: str | list[str] | tuple[str, ...]) -> None:
    """Raise :class:`NotFittedError` unless ``estimator`` has every one of ``attributes`` (its fit's).

    Parameters
    ----------
    estimator : Estimator
    attributes : str or sequence of str
        Attributes ``fit`` sets (ending in ``_``).
    """
    names = [attributes] if isinstance(attributes, str) else list(attributes)
    missing = [a for a in names if not hasattr(estimator, a)]
    if missing:
        raise NotFittedError(f"this {type(estimator).__name__} is not fitted yet (no {', '.join(missing)}): "
                             "call 'fit' with appropriate arguments before using this estimator")


def clone(estimator: Any) -> Any:
    """A new, unfitted estimator with the same parameters (estimator parameters cloned, others
    deep-copied), as :func:`sklearn.base.clone` makes."""
    import copy

    params = {k: clone(v) if isinstance(v, Estimator) else copy.deepcopy(v)
              for k, v in estimator.get_params(deep=False).items()}
    return type(estimator)(**params)
