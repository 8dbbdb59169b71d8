"""The default synthetic talker's manifold, shipped fitted so that the first start builds nothing.

The explorer opens on the default synthetic talker (28,800 frames, 600 lip points). Its
frames (207 MB) are regenerated deterministically from the talker's seed in a few seconds
(:class:`engine.talker.synthetic.SyntheticTalker`); fitting the manifold to them, and
measuring the synthesis choice on them, takes a minute. So Lipspace ships what the fit
made, without what the corpus gives back: ``assets/talker-default.npz``
(:data:`PREBUILT_ASSET`, package data of ``engine.assets``), made by

.. code-block:: bash

    python -m engine.talker.prebuilt            # writes assets/talker-default.npz in the checkout

It holds :meth:`engine.manifold.model.Manifold.fitted_arrays` of the talker's manifold and its
synthesis choice (:func:`engine.synthesis.method_choice.fit_choice`) without the arrays the
corpus gives back exactly: F^x (the shape space's projection of the frames), F^x', G, the
embedding's copy of F^y and its reference points (G itself, for the exact embedding).
:func:`load_prebuilt` puts them back from the regenerated corpus, after three checks:

* the file's key (:func:`prebuilt_key`) is that of the code running: the generator's
  (:func:`engine.talker.synthetic.talker_key`), the fit's
  (:func:`engine.manifold.model.algorithm_fingerprint`) and the synthesis choice's
  (:func:`engine.synthesis.method_choice.choice_code`); code edited since the file was made
  makes it unusable, and the talker is fitted as before;
* the corpus's utterances and phones hash to the file's (:func:`corpus_key`);
* F^x of every 97th frame, projected now, equals the file's within round-off (a library that
  draws its random numbers otherwise would give other frames).

``python -m engine.talker.prebuilt --check`` fits the talker afresh and compares
(:func:`compare`); ``tests/engine/talker/test_prebuilt.py`` does the same.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

__all__ = ["PREBUILT_ASSET", "PRESET", "prebuilt_key", "corpus_key", "prebuilt_path", "write_prebuilt",
           "load_prebuilt", "make_prebuilt", "fresh", "compare", "main"]

#: the shipped file, in ``assets/`` (package data of ``engine.assets``)
PREBUILT_ASSET = "talker-default.npz"
#: the talker it is the manifold of: the default preset, classic kinematics, every other parameter at its default
PRESET = "default"
#: F^x of every this-many-th frame is stored to check the regenerated frames against
_FX_STEP = 97
#: arrays the regenerated corpus gives back, not stored
_DERIVED = ("Fx", "Fxv", "G", "embedding/embedding_", "embedding/reference_")


def prebuilt_key(preset=PRESET, **params) -> str:
    """The key of a shipped manifold the running code may use: a hash of the corpus key of the talker
    (``preset`` and ``params``: :func:`engine.talker.synthetic.talker_key`), the fitting code and
    parameters, and the synthesis choice's code."""
    from engine.manifold.model import algorithm_fingerprint
    from engine.synthesis.method_choice import choice_code
    from engine.talker.talker_cache import talker_key

    blob = json.dumps({"talker": talker_key(preset, **params), "fit": algorithm_fingerprint(),
                       "choice": choice_code()}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def corpus_key(corpus) -> str:
    """A hash of a corpus's shape, utterances and phones (not its frames)."""
    h = hashlib.sha256(json.dumps([list(corpus.frames.shape), corpus.rate, [
        [u.id, u.start, u.stop, [(p.label, round(p.start, 6), round(p.end, 6)) for p in u.phones]]
        for u in corpus.utterances]]).encode())
    return h.hexdigest()[:20]


def prebuilt_path() -> Path:
    """Where the shipped file is: ``engine.assets``'s folder (``assets/`` of a checkout)."""
    from engine.files.assets import assets_dir

    return assets_dir() / PREBUILT_ASSET


def write_prebuilt(manifold, path, *, preset=PRESET, **params) -> Path:
    """Write what ``manifold`` (fitted to the talker ``preset`` with ``params``, with its synthesis choice)
    adds to its corpus.

    The arrays the corpus gives back (F^x, F^x', G, the embedding's copies of F^y and G) are left
    out; a key, the corpus's key and a sample of F^x are added. Written compressed, atomically.
    """
    from engine.files.atomic import atomic_write

    if getattr(manifold, "synthesis_choice_", None) is None:
        raise ValueError("the manifold has no synthesis choice: run engine.synthesis.method_choice.fit_choice first")
    d = manifold.fitted_arrays()
    emb = manifold.embedding_
    if not np.array_equal(emb.embedding_, manifold.Fy_) or not np.array_equal(emb.reference_, manifold.G_):
        raise ValueError("the embedding's reference points are not G (a landmark embedding): only the exact "
                         "embedding of the default talker is shipped")
    for k in _DERIVED:
        del d[k]
    d["prebuilt_key"] = np.array(prebuilt_key(preset, **params))
    d["prebuilt_corpus"] = np.array(corpus_key(manifold.corpus_))
    d["prebuilt_fx_sample"] = np.ascontiguousarray(manifold.Fx_[::_FX_STEP])
    path = Path(path)
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **d)
    return path


def load_prebuilt(corpus, *, path=None, progress=None, preset=PRESET, **params):
    """The default talker's manifold from the shipped file and its regenerated ``corpus``.

    Parameters
    ----------
    corpus : engine.recordings.corpus.Corpus
        :func:`engine.talker.synthetic.load_synthetic` of :data:`PRESET` (speech audio or not).
    path : path, optional
        The file (default :func:`prebuilt_path`).
    progress : callable(stage, done, total), optional
    preset, **params
        The talker the file must be the manifold of (default: the shipped one's).

    Returns
    -------
    (manifold or None, reason)
        The manifold (its corpus is ``corpus``, unchanged), or None and why the file cannot be
        used (none shipped, made by other code, another corpus, other frames); the caller then
        fits the talker.

    Raises
    ------
    engine.manifold.model.ManifoldFileError
        A damaged file (every array is checked as a manifold file's).
    """
    from engine.files.persist import NpzReadError, read_npz
    from engine.manifold.model import Manifold, ManifoldFileError
    from engine.progress import report
    from engine.recordings.bounds import velocities

    path = prebuilt_path() if path is None else Path(path)
    report(progress, "loading the shipped manifold", 0, 1)
    try:
        d = read_npz(path)
    except FileNotFoundError:
        return None, f"no shipped manifold at {path}"
    except NpzReadError as exc:
        raise ManifoldFileError(f"{path}: not a readable .npz manifold file ({exc.reason})") from None
    try:
        key, ck = str(d["prebuilt_key"][()]), str(d["prebuilt_corpus"][()])
        sample = np.asarray(d["prebuilt_fx_sample"], dtype=np.float32)
    except (KeyError, IndexError, TypeError, ValueError):
        raise ManifoldFileError(f"{path}: not a shipped talker manifold (no prebuilt_key, prebuilt_corpus or "
                                "prebuilt_fx_sample)") from None
    want = prebuilt_key(preset, **params)
    if key != want:
        return None, f"{path.name} was made by other code or for another talker (key {key}, this code's {want})"
    if ck != corpus_key(corpus):
        return None, f"{path.name} is the manifold of another corpus than {corpus.name}'s"
    Fx = _estimator("shape", d, path).transform(corpus.frames)
    if Fx.shape[1] != sample.shape[1] or len(Fx[::_FX_STEP]) != len(sample):
        return None, f"{path.name}: its F^x sample has shape {sample.shape}, the frames give {Fx[::_FX_STEP].shape}"
    scale = np.sqrt(np.mean(sample.astype(np.float64) ** 2, axis=0)) + 1e-12
    err = float(np.max(np.abs(Fx[::_FX_STEP] - sample) / scale))
    if not err <= 1e-4:
        return None, (f"{path.name}: the regenerated frames differ from those it was fitted to (F^x off by "
                      f"{err:.2g} of a component's RMS)")
    arrays = dict(d)
    Fxv = velocities(Fx, corpus.bounds)
    G = _estimator("dynamics", d, path).transform_pair(Fx, Fxv)
    arrays.update({"Fx": Fx, "Fxv": Fxv, "G": G, "embedding/embedding_": d["Fy"], "embedding/reference_": G})
    m = Manifold.from_arrays(arrays, source=path, corpus=corpus)
    report(progress, "loading the shipped manifold", 1, 1)
    return m, "shipped"


def _estimator(name, d, path):
    """The fitted ``"shape"`` or ``"dynamics"`` estimator the file stores, checked as a manifold file's."""
    from engine.files.persist import load_estimator
    from engine.files.validate import FieldError
    from engine.manifold.dynamics import DynamicFeatures
    from engine.manifold.model import ManifoldFileError
    from engine.manifold.shape import ShapeSpace

    cls = {"shape": ShapeSpace, "dynamics": DynamicFeatures}[name]
    try:
        return load_estimator(cls, d, name, source=path, schema=cls._persisted_attributes, dims={})
    except FieldError as exc:
        raise ManifoldFileError(str(exc)) from None


def make_prebuilt(path=None, *, progress=None):
    """Fit the default talker afresh, measure its synthesis choice and write the shipped file.

    Returns the fitted manifold (its corpus without speech audio: the fit does not read it).
    ``path`` defaults to :func:`prebuilt_path` (``assets/`` of the checkout).
    """
    m = fresh(progress=progress)
    write_prebuilt(m, prebuilt_path() if path is None else path)
    return m


def fresh(*, progress=None):
    """The default talker's manifold and synthesis choice computed now (what the shipped file holds)."""
    from engine.manifold.model import Manifold
    from engine.synthesis.method_choice import fit_choice
    from engine.talker.talker_cache import load_synthetic

    m = Manifold().fit(load_synthetic(preset=PRESET, progress=progress), progress=progress)
    fit_choice(m, progress=progress)
    return m


def compare(fresh_manifold, shipped) -> dict:
    """How a freshly fitted talker manifold differs from the shipped one, part by part.

    Returns
    -------
    dict
        ``fy``: largest difference of F^y over F^y's RMS; ``tangent``: the same of the tangent
        frames' S and V (``s_``, ``v_``); ``classes``: fraction of frames whose tangent class
        agrees; ``labels``: fraction whose state agrees; ``centroids``: largest difference of the
        state centres over F^y's RMS; ``state_x``: of the inverse map at the states over F^x's
        RMS; ``synthesis_states``: of the synthesiser's state centres; ``choice``: the synthesis
        choices' settings and best methods agree (bool); ``n_neighbors``, ``n_states``: the
        tangent frames' and the graph's, equal (bool).
    """
    a, b = fresh_manifold, shipped

    def rel(x, y, ref):
        x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
        if x.shape != y.shape:
            return float("inf")
        return float(np.max(np.abs(x - y)) / (np.sqrt(np.mean(np.asarray(ref, np.float64) ** 2)) + 1e-12))

    ca, cb = a.synthesis_choice_ or {}, b.synthesis_choice_ or {}
    keys = ("state_dims", "n_states", "n_neighbors", "frames_per_state", "sigma", "sliding_window", "best")
    return {
        "fy": rel(a.Fy_, b.Fy_, b.Fy_),
        "tangent": max(rel(a.tangent_.s_, b.tangent_.s_, b.tangent_.s_),
                       rel(a.tangent_.v_, b.tangent_.v_, b.tangent_.v_)),
        "classes": float(np.mean(a.tangent_.classes_ == b.tangent_.classes_)),
        "labels": float(np.mean(a.states_.labels_ == b.states_.labels_)) if a.states_.labels_.shape ==
        b.states_.labels_.shape else 0.0,
        "centroids": rel(a.states_.centroids_, b.states_.centroids_, b.Fy_[:, :a.states_.centroids_.shape[1]]),
        "state_x": rel(a.state_x_, b.state_x_, b.Fx_),
        "synthesis_states": rel(a.synthesis_states_, b.synthesis_states_, b.Fy_[:, :b.synthesis_states_.shape[1]]),
        "choice": all(ca.get(k) == cb.get(k) for k in keys),
        "n_neighbors": a.tangent_.n_neighbors_ == b.tangent_.n_neighbors_,
        "n_states": a.states_.centroids_.shape == b.states_.centroids_.shape,
    }


def main(argv=None) -> int:
    """``python -m engine.talker.prebuilt [-o FILE] [--check]``: write the shipped file, or check it."""
    import argparse
    import time

    ap = argparse.ArgumentParser(prog="python -m engine.talker.prebuilt", description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=None, help=f"file to write (default: {prebuilt_path()})")
    ap.add_argument("--check", action="store_true", help="fit the talker afresh and compare it with the shipped "
                                                         "file instead of writing one")
    args = ap.parse_args(argv)
    t = time.perf_counter()
    if args.check:
        from engine.talker.talker_cache import load_synthetic

        m = fresh()
        shipped, why = load_prebuilt(load_synthetic(preset=PRESET), path=args.output)
        if shipped is None:
            print(f"the shipped manifold cannot be used: {why}")
            return 1
        print(json.dumps(compare(m, shipped), indent=1))
    else:
        out = prebuilt_path() if args.output is None else Path(args.output)
        make_prebuilt(out)
        print(f"wrote {out} ({out.stat().st_size / 2**20:.1f} MiB, key {prebuilt_key()})")
    print(f"{time.perf_counter() - t:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
