"""Checks every engine estimator passes (after scikit-learn's common estimator checks).

The estimators are found in the source: every class under ``engine/`` deriving from
``engine.estimator.Estimator``, directly or through another engine estimator. For each:
a keyword-only ``__init__``; ``_parameter_constraints`` naming exactly its parameters and
accepting the defaults; a ``get_params`` / ``clone`` round trip; ``fit`` returning self; a
``NotFittedError`` from every method that needs a fit, before one; and every bad value
derived from the declared constraints (:func:`engine.constraints.invalid_values`) refused by
the first call, naming the estimator and the parameter. A new estimator is covered by
declaring its constraints and, when its ``fit`` takes data, one line in :data:`FIT_ARGS`.
"""
from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import clone as sklearn_clone

from engine.constraints import InvalidParameterError, invalid_values
from engine.estimator import Estimator, NotFittedError, clone

ENGINE = Path(__file__).resolve().parents[2] / "engine"

#: public methods usable before a fit (besides fit, fit_*, get_params and set_params)
BEFORE_FIT = {"ShapeSpace": {"validate_frames"}, "SyntheticTalker": {"generate"}}


def _estimator_classes() -> dict[str, tuple[str, str]]:
    """``{class name: (module, class name)}`` of every estimator class defined under engine/ (read from the
    source, so no module is imported only to be searched), private base classes included."""
    bases, where = {}, {}
    for path in sorted(ENGINE.rglob("*.py")):
        module = ".".join(path.relative_to(ENGINE.parent).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                bases[node.name] = {b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in node.bases}
                where[node.name] = module
    found = {"Estimator"}
    while True:
        more = {name for name, b in bases.items() if b & found} - found
        if not more:
            break
        found |= more
    found.discard("Estimator")
    return {name: (where[name], name) for name in sorted(found)}


CLASSES = _estimator_classes()
PUBLIC = sorted(name for name in CLASSES if not name.startswith("_"))


def _cls(name):
    module, attr = CLASSES[name]
    cls = getattr(importlib.import_module(module), attr)
    assert issubclass(cls, Estimator), f"{module}.{attr} is no engine Estimator"
    return cls


def test_the_estimators_are_found():
    """The source scan finds the known estimators (a scan that found none would pass every test below)."""
    assert {"Manifold", "ShapeSpace", "StateGraph", "LearntPathSynthesizer", "SyntheticTalker",
            "HeadPose"} <= set(PUBLIC)
    assert len(PUBLIC) >= 21


# ------------------------------------------------------------------ instances and their data
#: constructor arguments of estimators with required parameters or costly defaults
CONSTRUCT = {
    "PhoneModelSynthesizer": lambda: {"model": _cls("DominanceModel")(), "method": "dominance"},
    "LearntPathSynthesizer": lambda: {"choice": {"state_dims": 3}},
    "StateHermiteSynthesizer": lambda: {"choice": {"state_dims": 3}},
    "SyntheticTalker": lambda: {"preset": "small", "n_sentences": 2},
    "ConditionComparison": lambda: {"n_permutations": 19, "n_bootstrap": 0},
}


def _make(name):
    return _cls(name)(**CONSTRUCT.get(name, lambda: {})())


@pytest.fixture(scope="module")
def tiny(small_corpus):
    """A manifold of three utterances of the small talker (a few hundred frames: every fit below is quick)."""
    from engine.manifold.model import Manifold

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances[:3]])
    return Manifold().fit(corpus)


def _sequences(m):
    from engine.synthesis.trajectory import phone_sequences

    return phone_sequences(m.corpus_.utterances, m.Fx_)


def _head_reference():
    rng = np.random.default_rng(0)
    base = rng.normal(size=(17, 3)) * 30
    return base[None] + rng.normal(scale=0.1, size=(5, 17, 3))


def _lip_frame(m):
    """Sparse markers: the talker's four lip landmarks and four other lip points of its mean frame."""
    from engine.recordings.corpus import frame_points

    c = m.corpus_
    keep = [i for i, r in enumerate(c.point_roles) if r != "lip"] + list(range(0, c.n_points, 40))
    return frame_points(np.asarray(c.frames).mean(axis=0), c.dims)[keep], [c.point_roles[i] for i in keep]


#: the first call of each estimator that takes data: ``(method, args, kwargs)`` from the tiny manifold
FIT_ARGS = {
    "Manifold": lambda m: ("fit", (m.corpus_,), {}),
    "ShapeSpace": lambda m: ("fit", (m.corpus_.frames,), {}),
    "DynamicFeatures": lambda m: ("fit", (m.Fx_, m.corpus_.bounds), {}),
    "Embedding": lambda m: ("fit", (m.G_,), {}),
    "TangentFrames": lambda m: ("fit", (m.Fy_, m.corpus_.bounds, m.tangent_.shape_coordinate_),
                                {"rate": m.corpus_.rate}),
    "StateGraph": lambda m: ("fit", (m.Fy_, m.corpus_.bounds), {}),
    "PhoneClusters": lambda m: ("fit", (m,), {}),
    "InverseMap": lambda m: ("fit", (m.Fy_, m.Fx_), {}),
    "StateMeanInverse": lambda m: ("fit", (m.states_.labels_, m.Fx_), {}),
    "LocalLinearInverse": lambda m: ("fit", (m.Fy_, m.Fx_), {}),
    "HeadPose": lambda m: ("fit", (_head_reference(),), {}),
    "LipContour": lambda m: ("fit", _lip_frame(m), {}),
    "DominanceModel": lambda m: ("fit", (_sequences(m), m.corpus_.rate), {}),
    "SlidingWindowRegressor": lambda m: ("fit", (_sequences(m), m.corpus_.rate), {}),
    "LearntPaths": lambda m: ("fit", (m.Fy_, m.Fx_, m.corpus_.bounds, m.states_.labels_, m.states_.centroids_), {}),
    "ViterbiSynthesizer": lambda m: ("fit", (m,), {}),
    "InterpolationSynthesizer": lambda m: ("fit", (m,), {}),
    "UnitSelectionSynthesizer": lambda m: ("fit", (m,), {}),
    "PhoneModelSynthesizer": lambda m: ("fit", (m,), {}),
    "LearntPathSynthesizer": lambda m: ("fit", (m,), {}),
    "StateHermiteSynthesizer": lambda m: ("fit", (m,), {}),
    "ConditionComparison": lambda m: ("fit", (m, ["a", "b", "a"][: len(m.corpus_.utterances)]), {}),
    "SyntheticTalker": lambda m: ("generate", (), {}),  # no fit: generate is its first call
}


def test_every_estimator_has_its_first_call_listed():
    assert sorted(FIT_ARGS) == PUBLIC


# ------------------------------------------------------------------ the checks
def _init_params(cls):
    if cls.__init__ is object.__init__:
        return []  # no parameters
    return [p for name, p in inspect.signature(cls.__init__).parameters.items() if name != "self"]


@pytest.mark.parametrize("name", PUBLIC)
def test_init_is_keyword_only(name):
    for p in _init_params(_cls(name)):
        assert p.kind == p.KEYWORD_ONLY, f"{name}.__init__: {p.name} must be keyword-only (after *)"


@pytest.mark.parametrize("name", sorted(CLASSES))
def test_constraints_cover_exactly_the_init_parameters(name):
    cls = _cls(name)
    assert hasattr(cls, "_parameter_constraints"), f"{name} declares no _parameter_constraints"
    declared = set(cls._parameter_constraints)
    assert declared == {p.name for p in _init_params(cls)}, f"{name}: constraints for {sorted(declared)}"


@pytest.mark.parametrize("name", PUBLIC)
def test_defaults_satisfy_the_constraints_and_clone_round_trips(name):
    from engine.constraints import validate_params

    est = _make(name)
    validate_params(est)  # the defaults (and CONSTRUCT's values) are valid
    params = est.get_params(deep=False)
    for copier in (clone, sklearn_clone):  # the engine's own, and scikit-learn's (which takes them as its own)
        copy = copier(est)
        assert copy is not est and type(copy) is type(est)
        again = copy.get_params(deep=False)
        assert again.keys() == params.keys()
        for k, v in params.items():
            if isinstance(v, Estimator):
                assert again[k] is not v and again[k].get_params() == v.get_params(), k
            else:
                assert again[k] == v, k
        assert copy.set_params(**params) is copy and copy.get_params(deep=False) == params


@pytest.mark.parametrize("name", PUBLIC)
def test_bad_parameters_are_refused_naming_the_parameter(name, tiny):
    cls, est = _cls(name), _make(name)
    method, args, kwargs = FIT_ARGS[name](tiny)
    for param, constraints in cls._parameter_constraints.items():
        bad = invalid_values(constraints)
        assert bad, f"{name}.{param}: its constraints accept anything; declare what it must be"
        for value in bad:
            trial = clone(est).set_params(**{param: value})
            with pytest.raises(InvalidParameterError) as err:
                getattr(trial, method)(*args, **kwargs)
            e = err.value
            assert (e.estimator, e.parameter) == (name, param), str(e)
            msg = str(e)
            assert msg.startswith(f"{name}: {param} must be ") and "got " in msg, msg
            if param not in CONSTRUCT.get(name, lambda: {})():
                assert "leave it out for the default" in msg, msg


@pytest.mark.parametrize("name", [n for n in PUBLIC if hasattr(_cls(n), "fit")])
def test_fit_returns_self(name, tiny):
    est = _make(name)
    method, args, kwargs = FIT_ARGS[name](tiny)
    assert getattr(est, method)(*args, **kwargs) is est


def _needs_fit(cls, name):
    """Public methods of ``cls`` (its own and its engine bases') that need a fit."""
    skip = {"get_params", "set_params"} | BEFORE_FIT.get(name, set())
    out = []
    for klass in cls.__mro__:
        if not klass.__module__.startswith("engine."):
            continue
        for attr, obj in vars(klass).items():
            if attr.startswith("_") or attr.startswith("fit") or attr in skip or attr in out:
                continue
            if isinstance(obj, (classmethod, staticmethod, property)) or not callable(obj):
                continue
            out.append(attr)
    return out


@pytest.mark.parametrize("name", PUBLIC)
def test_methods_need_a_fit_first(name):
    est = _make(name)
    methods = _needs_fit(type(est), name)
    if name != "SyntheticTalker":
        assert methods, f"{name} has no method that needs a fit"
    for attr in methods:
        fn = getattr(est, attr)
        sig = inspect.signature(fn)
        args = [None for p in sig.parameters.values() if p.kind == p.POSITIONAL_OR_KEYWORD and p.default is p.empty]
        kwargs = {p.name: None for p in sig.parameters.values() if p.kind == p.KEYWORD_ONLY and p.default is p.empty}
        with pytest.raises(NotFittedError):
            fn(*args, **kwargs)


def test_a_refusal_names_value_limit_and_fix():
    from engine.manifold.shape import ShapeSpace

    with pytest.raises(InvalidParameterError) as err:
        ShapeSpace(variance=1.5).fit(np.zeros((5, 3)))
    assert str(err.value) == "ShapeSpace: variance must be in (0, 1], got 1.5; leave it out for the default 0.99"
    assert isinstance(err.value, ValueError) and isinstance(err.value, TypeError)
    assert err.value.describe("--variance") == \
        "--variance must be in (0, 1], got 1.5; leave it out for the default 0.99"
    with pytest.raises(InvalidParameterError, match=r"StateGraph: n_states must be an integer >= 1 or None, "
                                                    r"got 'ten'; leave it out for the default None"):
        _cls("StateGraph")(n_states="ten").fit(np.zeros((5, 3)), [[0, 5]])


def test_a_refusal_pickles():
    import pickle

    err = InvalidParameterError("Embedding", "method", "tsne", "one of 'mds', 'pca'", "pca")
    back = pickle.loads(pickle.dumps(err))
    assert str(back) == str(err) and back.parameter == "method"


def test_data_limits_still_name_the_data(tiny):
    """What depends on the data stays in fit, with the limit from the data."""
    from engine.manifold.embedding import Embedding

    G = tiny.G_
    with pytest.raises(ValueError, match=rf"n_components={len(G)} must be at most {len(G) - 1}"):
        Embedding(n_components=len(G)).fit(G)
    with pytest.raises(ValueError, match=r"n_states must be an integer in 1..N = 1..6"):
        _cls("StateGraph")(n_states=7).fit(np.zeros((6, 3)) + np.arange(6)[:, None], [[0, 6]])
