"""Joining corpora read from several files into one."""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from engine.recordings.corpus import Corpus, CorpusError

__all__ = ["concat"]


def concat(corpora, *, name: str | None = None) -> Corpus:
    """One corpus holding the utterances of several, in order.

    Parameters
    ----------
    corpora : sequence of Corpus
        All with the same rate, dims and number of points (and the same point names and
        faces when they have them). Utterance ids must be unique across them.
    name : str, optional
        Name of the result (default: the first corpus's name, ``+N`` more).

    Returns
    -------
    Corpus
        Frames stacked; utterance ranges shifted; latent signals kept when every corpus
        has them; point names / faces kept when every corpus agrees on them.

    Raises
    ------
    CorpusError
        Naming the first corpus that differs from the first one, and how.
    """
    corpora = list(corpora)
    if not corpora:
        raise CorpusError("concat: no corpora given; expected at least one")
    a = corpora[0]
    seen: dict[str, Any] = {}
    for k, c in enumerate(corpora):
        if not isinstance(c, Corpus):
            raise CorpusError(f"concat: item {k} is a {type(c).__name__}, not a Corpus")
        what = f"concat: corpus {k} ({c.name!r})"
        if abs(c.rate - a.rate) > 1e-9 * a.rate:
            raise CorpusError(f"{what} is at {c.rate:g} Hz but corpus 0 ({a.name!r}) at {a.rate:g} Hz; "
                              "corpora can be joined only at one frame rate: resample them to one first "
                              "('lipspace import --resample HZ' resamples each input before joining)")
        if c.dims != a.dims or c.n_points != a.n_points:
            raise CorpusError(f"{what} has {c.n_points} points in {c.dims}-D but corpus 0 ({a.name!r}) has "
                              f"{a.n_points} in {a.dims}-D; expected the same points (same sensors / markers / mesh)")
        if c.point_names is not None and a.point_names is not None and c.point_names != a.point_names:
            raise CorpusError(f"{what} names its points {c.point_names[:6]} but corpus 0 has {a.point_names[:6]}; "
                              "expected the same points in the same order")
        if c.faces is not None and a.faces is not None and not np.array_equal(c.faces, a.faces):
            raise CorpusError(f"{what} has other mesh faces than corpus 0; expected the same mesh topology")
        for u in c.utterances:
            if u.id in seen:
                raise CorpusError(f"{what} repeats utterance id {u.id!r} (also in corpus {seen[u.id]}); "
                                  "expected unique ids across the corpora")
            seen[u.id] = k
    utts, pos = [], 0
    for c in corpora:
        for u in c.utterances:
            utts.append(replace(u, start=u.start + pos, stop=u.stop + pos))
        pos += c.n_frames
    names = a.point_names if all(c.point_names == a.point_names for c in corpora) else None
    faces = a.faces if all(c.faces is not None for c in corpora) else None
    keys = set(a.latent)
    for c in corpora[1:]:
        keys &= set(c.latent)
    latent = {k: np.concatenate([c.latent[k] for c in corpora]) for k in sorted(keys)}
    if name is None:
        name = a.name if len(corpora) == 1 else f"{a.name}+{len(corpora) - 1}"
    roles = a.point_roles if all(c.point_roles == a.point_roles for c in corpora) else None
    regs = list(dict.fromkeys(c.registration for c in corpora))
    registration = regs[0] if len(regs) == 1 else "; ".join(r or "none" for r in regs)
    history = list(dict.fromkeys(h for c in corpora for h in c.history))
    axes = a.axes if all(c.axes == a.axes for c in corpora) else ""
    units = a.units if all(c.units == a.units for c in corpora) else ""
    return Corpus(frames=np.concatenate([c.frames for c in corpora], axis=0), rate=a.rate, utterances=utts,
                  dims=a.dims, faces=faces, point_names=names, latent=latent, name=name, point_roles=roles,
                  registration=registration, history=history, axes=axes, units=units)
