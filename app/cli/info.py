"""``lipspace info``: summarise a corpus or manifold file."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def add_arguments(p):
    p.add_argument("file", help="a manifold (from 'lipspace build') or native corpus file (.npz)")


def _corpus_lines(c):
    mids, labels, *_ = c.phone_table()
    uniq, counts = np.unique(labels, return_counts=True) if len(labels) else ([], [])
    top = ", ".join(f"{u} {n}" for u, n in sorted(zip(uniq, counts), key=lambda t: -t[1])[:12])
    return [
        f"corpus      {c.name}",
        f"frames      {c.n_frames} at {c.rate:g} Hz ({c.duration:.1f} s), {len(c.utterances)} utterances",
        f"points      {c.n_points} ({c.dims}-D){', mesh with %d faces' % len(c.faces) if c.faces is not None else ''}",
        f"phones      {len(labels)} intervals, {len(uniq)} labels" + (f"; most frequent: {top}" if top else ""),
        f"latent      {', '.join(sorted(c.latent)) or '-'}",
    ]


def run(args) -> int:
    from app.cli import CliError
    from engine.corpus import Corpus, CorpusError
    from engine.manifold import Manifold, ManifoldFileError

    path = Path(args.file)
    if not path.exists():
        raise CliError(f"{path}: no such file")
    try:
        m = Manifold.load(path)
    except ManifoldFileError as exc:
        if "corpus file" not in str(exc):
            raise CliError(str(exc)) from None
        try:
            c = Corpus.load(path)
        except CorpusError as exc2:
            raise CliError(str(exc2)) from None
        print(f"{path}: Lipspace corpus")
        print("\n".join(_corpus_lines(c)))
        return 0
    print(f"{path}: Lipspace manifold")
    print("\n".join(_corpus_lines(m.corpus_)))
    sh, emb = m.shape_, m.embedding_
    k = sh.n_components_
    print(f"shape X     {k} components hold {100 * sh.recovered_ratio_[k - 1]:.2f}% of the variance of the "
          f"{len(sh.scree_)} computed ({100 * sh.explained_variance_ratio_.sum():.2f}% of the total); "
          f"scree {', '.join(f'{100 * v:.1f}' for v in sh.scree_[:5])}%")
    rr = emb.recovered_ratio_
    print(f"embedding Y {m.embedding_method}, {m.Fy_.shape[1]} dims"
          + (f", {len(emb.landmarks_)} landmarks" if emb.landmarks_ is not None else "")
          + f"; first 3 dims hold {100 * rr[min(2, len(rr) - 1)]:.1f}% of the recovered variance "
          f"(per dim {', '.join(f'{100 * v:.1f}' for v in np.diff(np.r_[0, rr])[:5])}%)")
    props = m.tangent_.class_proportions()
    print("classes     " + "; ".join(f"{name} {100 * v:.1f}%" for name, v in props.items()))
    print("state graph " + m.states_.connectivity_report().replace("\n", "\n            "))
    if m.timings_:
        print("fit time    " + ", ".join(f"{k} {v:.2f} s" for k, v in m.timings_.items()))
    return 0
