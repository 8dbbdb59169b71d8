"""What a manifold file holds: reading the fitted manifold's arrays back, each checked.

:meth:`engine.manifold.model.Manifold.save` writes the arrays of
:meth:`~engine.manifold.model.Manifold.fitted_arrays` beside the corpus's;
:func:`read_fitted` reads them back: the format version, the parameters, F^x, F^x', G, F^y,
every estimator against its class's ``_persisted_attributes``, the relations between the parts, the
corpus (its frames whole, referenced in blocks, or reconstructed from F^x), the timings, the
inverse map at the states and the synthesis choice a build stored.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from engine.files.persist import load_estimator
from engine.manifold.dynamics import DynamicFeatures
from engine.manifold.embedding import Embedding
from engine.manifold.shape import ShapeSpace
from engine.recordings.corpus import Corpus

__all__ = ["FILE_VERSION", "read_fitted"]

#: the manifold file's format
FILE_VERSION = 2


def read_fitted(cls, d, path, corpus=None, *, parts):
    """A manifold of class ``cls`` (:class:`engine.manifold.model.Manifold`) from the arrays ``d`` of a
    manifold file, each checked.

    ``parts``: estimator name -> attribute (``Manifold._PARTS``). ``corpus``: the corpus fitted
    (the file's own corpus arrays are then not read). Raises
    :class:`engine.files.validate.FieldError` or :class:`engine.recordings.corpus.CorpusError`.
    """
    from engine.files.validate import FieldError, check_array, check_scalar, parse_params
    from engine.graph.states import StateGraph
    from engine.manifold.tangent import TangentFrames

    version = check_scalar(d, "manifold_version", source=path, kind="int")
    if version == 1:
        raise FieldError(path, "manifold_version", "format 1 was written by an older Lipspace whose tangent "
                                                   "frames and classes were read in Y1-3 only; rebuild it "
                                                   "from its corpus with 'lipspace build'")
    if version > FILE_VERSION or version < 1:
        raise FieldError(path, "manifold_version", f"format {version} is not one this Lipspace reads "
                                                   f"({FILE_VERSION}); upgrade Lipspace")
    m = parse_params(cls, check_scalar(d, "manifold_params", source=path, kind="str"),
                        source=path, field="manifold_params")
    dims = {}
    m.Fx_ = check_array(d, "Fx", source=path, shape=("N", "m"), dims=dims)
    m.Fxv_ = check_array(d, "Fxv", source=path, shape=("N", "m"), dims=dims)
    m.G_ = check_array(d, "G", source=path, shape=("N", "2m"), dims=dims)
    m.Fy_ = check_array(d, "Fy", source=path, shape=("N", "k"), dims=dims)
    classes = {"shape": ShapeSpace, "dynamics": DynamicFeatures, "embedding": Embedding,
               "tangent": TangentFrames, "states": StateGraph}
    for name, attr in parts.items():
        setattr(m, attr, load_estimator(classes[name], d, name, source=path,
                                        schema=classes[name]._persisted_attributes, dims=dims))
    _check_consistency(m, dims, path)
    if corpus is not None:
        if corpus.n_frames != dims["N"]:
            raise FieldError(path, "Fy", f"{dims['N']} frames, but the corpus given has {corpus.n_frames}")
        m.corpus_ = corpus
    else:
        m.corpus_ = _corpus_part(m, d, dims, path)
    m.timings_ = _parse_timings(check_scalar(d, "manifold_timings", source=path, kind="str"), path)
    m._inverse = None
    m.state_x_ = None  # files written before it was stored: synthesis maps the states itself
    if "state_x" in d:
        dims.setdefault("K", m.states_.centroids_.shape[0])
        m.state_x_ = check_array(d, "state_x", source=path, shape=("K", "m"), dims=dims)
    # files written before the build measured the synthesis choice have none: it is measured at the first
    # synthesis then (engine.synthesis.method_choice.choose_methods) and cached
    m.synthesis_choice_, m.synthesis_states_ = _synthesis_part(d, path, dims)
    # the stored phone models' arrays, checked where a synthesiser reads them (engine.synthesis.stored_choice)
    m.synthesis_models_ = {k[len("synthesis_models/"):]: v for k, v in d.items() if k.startswith("synthesis_models/")} \
        if m.synthesis_choice_ is not None else {}
    return m


def _corpus_part(m, d, dims, path):
    """The corpus a manifold file holds (its frames whole, referenced in blocks, or reconstructed from F^x)."""
    from engine.files.validate import check_array, check_scalar

    frames = None
    if "corpus_frames" in d:
        check_array(d, "corpus_frames", source=path, shape=("N", "C"), dims=dims, finite=False)  # see Corpus
    elif "corpus_blocks_source" in d:  # the frames stay in the blocked corpus the manifold was built from
        from engine.recordings.corpus_blocks import frames_from_reference

        check_scalar(d, "corpus_blocks_source", source=path, kind="str")
        frames = frames_from_reference(d, path, n_frames=dims["N"], n_columns=m.shape_.mean_.shape[0])
    else:
        frames = m.shape_.inverse_transform(m.Fx_)
    return Corpus.from_arrays(d, frames=frames, source=str(path), base=Path(path).resolve().parent)


def _check_consistency(m, dims, path):
    """Relations between parts that shapes alone do not express."""
    from engine.files.validate import FieldError

    if m.shape_.n_components_ != dims["m"]:
        raise FieldError(path, "shape/n_components_", f"{m.shape_.n_components_} but F^x has {dims['m']} columns")
    if m.n_embedding != dims["k"]:
        raise FieldError(path, "manifold_params.n_embedding", f"{m.n_embedding} but F^y has {dims['k']} columns")
    if m.embedding_method != m.embedding_.method or m.embedding_.method not in ("pca", "mds"):
        raise FieldError(path, "embedding/__params__.method",
                         f"{m.embedding_.method!r} (manifold says {m.embedding_method!r}); expected 'pca' or 'mds'")
    if dims["L"] < 1 or dims["K"] < 1 or dims["N"] < 2:
        raise FieldError(path, "Fy", f"{dims['N']} frames, {dims['L']} reference points, {dims['K']} states: "
                                     "too few to be a fitted manifold")
    if dims["t"] > dims["k"] or dims["d"] > dims["k"] or m.tangent_.n_dims_ != dims["t"]:
        raise FieldError(path, "tangent/s_", f"{dims['t']}-D tangent frames (n_dims_={m.tangent_.n_dims_}) / "
                                             f"{dims['d']}-D states in a {dims['k']}-D embedding")
    st = m.states_
    if st.scc_labels_.size and st.scc_labels_.max() >= st.n_scc_:
        raise FieldError(path, "states/scc_labels_", f"value {st.scc_labels_.max()} is out of range "
                                                     f"(n_scc_={st.n_scc_})")
    if st.largest_scc_ >= st.n_scc_:
        raise FieldError(path, "states/largest_scc_", f"{st.largest_scc_} is out of range (n_scc_={st.n_scc_})")


def _synthesis_part(d, path, dims):
    """(choice dict or None, state centres (K, d) or None) stored by a build that measured the synthesis choice."""
    from engine.files.validate import FieldError, check_array, check_scalar

    if "synthesis_choice" not in d:
        return None, None
    text = check_scalar(d, "synthesis_choice", source=path, kind="str")
    try:
        choice = json.loads(text)
    except ValueError as exc:
        raise FieldError(path, "synthesis_choice", f"not valid JSON ({exc})") from None
    if not isinstance(choice, dict) or not isinstance(choice.get("best"), dict) or "blend" not in choice:
        raise FieldError(path, "synthesis_choice", "expected a JSON object holding 'best' and 'blend'")
    states = None
    if "synthesis_states" in d:
        k = choice.get("state_dims")
        if not isinstance(k, int) or isinstance(k, bool) or not 1 <= k <= dims["k"]:
            raise FieldError(path, "synthesis_choice.state_dims", f"{k!r}: expected an integer in 1..{dims['k']}")
        states = check_array(d, "synthesis_states", source=path, shape=("_Ks", k), dims={})
        if not 1 <= len(states) <= dims["N"]:
            raise FieldError(path, "synthesis_states", f"{len(states)} states for {dims['N']} frames")
    return choice, states


def _parse_timings(text, path) -> dict:
    from engine.files.validate import FieldError, json_field

    t = json_field(text, source=path, field="manifold_timings")
    if not isinstance(t, dict) or not all(isinstance(k, str) and isinstance(v, (int, float))
                                          and not isinstance(v, bool) and np.isfinite(v) for k, v in t.items()):
        raise FieldError(path, "manifold_timings", "expected a JSON object of stage name -> seconds")
    return {k: float(v) for k, v in t.items()}
