"""Write ``manifold_v2.npz``: a small manifold file as Lipspace wrote it (format 2).

The file in this folder was written by this script at commit 73b387e (the code before the
fitted attributes were declared on the estimators); ``test_manifold_files.py`` loads it with
the current code. Run from the repository root: ``.venv/bin/python tests/engine/manifold/data/make_manifold_v2.py``.
Two utterances of the small synthetic talker, 8 of its points (the four lip landmarks and
every fortieth surface point), no mesh, no audio: a file of a few hundred kB.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np

from engine.manifold.model import Manifold
from engine.talker.synthetic import load_synthetic

c = load_synthetic(preset="small", audio=False)
c = c.subset([u.id for u in c.utterances[:2]])
keep = [i for i, r in enumerate(c.point_roles) if r != "lip"] + list(range(0, c.n_points, 40))
cols = np.ravel([[3 * i, 3 * i + 1, 3 * i + 2] for i in keep])
c = replace(c, frames=np.ascontiguousarray(c.frames[:, cols]), faces=None, latent={},
            point_names=[c.point_names[i] for i in keep], point_roles=[c.point_roles[i] for i in keep],
            utterances=[replace(u, audio=None) for u in c.utterances], name="small-8")
Manifold().fit(c).save(Path(__file__).with_name("manifold_v2.npz"))
