"""The tangent classes on the real sample recordings: opening >= 95 %, accelerating >= 85 %.

Each recording is read as ``lipspace import`` reads it by default and built with the
defaults (tools/real_data_report.py builds the same corpora and writes the whole
table to docs/REAL_DATA.md). Nothing here was tuned on these files: the neighbourhood
and the dims of Y are chosen per corpus by held-out validation.
"""
import os
import sys

import numpy as np
import pytest

_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(_ROOT, "tools"))

from real_data_report import CLIPS, real_corpora  # noqa: E402

from engine.manifold.class_agreement import ACCELERATING_BOUND, OPENING_BOUND, class_agreement  # noqa: E402
from engine.manifold.tangent import TangentFrames  # noqa: E402
from engine.recordings.kinematics import lip_aperture  # noqa: E402


@pytest.fixture(scope="module")
def corpora(shared_data):
    import importlib.util
    import warnings

    from engine.io.errors import ImportDataWarning

    clips = CLIPS if importlib.util.find_spec("mediapipe") is not None else ()  # the [video] extra
    with warnings.catch_warnings():  # MOCHA's .lab runs past its data: read_recording says so, as it should
        warnings.simplefilter("ignore", ImportDataWarning)
        return real_corpora(shared_data, clips=clips)


@pytest.fixture(scope="module")
def built(corpora):
    from engine.manifold.model import Manifold

    return {name: Manifold().fit(c) for name, c in corpora.items()}


NAMES = ["Haskins F01", "Haskins M01", "Haskins F01 + M01", "MOCHA fsew0_001",
         *(f"video {c}" for c in CLIPS), "video, 5 clips pooled"]


@pytest.mark.parametrize("name", NAMES)
def test_classes_follow_the_lip_aperture(name, built):
    if name not in built:
        pytest.skip(f"{name}: not readable here (video import needs the [video] extra)")
    m = built[name]
    tf = m.tangent_
    got = class_agreement(tf.opening_, tf.accelerating_, lip_aperture(m.corpus_), m.corpus_.bounds)
    msg = f"{name} ({m.corpus_.n_frames} frames, {tf.n_dims_} dims, k={tf.n_neighbors_}): {got.describe()}"
    print("\n" + msg)
    assert got.opening >= OPENING_BOUND and got.accelerating >= ACCELERATING_BOUND, msg
    # the figures' V axis: opening frames on the V > 0 side
    assert np.all(tf.sv_coordinates()[tf.opening_, 1] > 0)


def test_three_dims_of_y_do_not_hold_the_dynamics(built):
    """The three drawn dims are not enough to read the classes from on real lips."""
    m = built["Haskins F01 + M01"]
    c = m.corpus_
    ap = lip_aperture(c)
    three = TangentFrames(n_dims=3).fit(m.Fy_, c.bounds, ap, rate=c.rate)
    a3 = class_agreement(three.opening_, three.accelerating_, ap, c.bounds)
    full = class_agreement(m.tangent_.opening_, m.tangent_.accelerating_, ap, c.bounds)
    print(f"\nY1-3: {a3.describe()}\nall dims: {full.describe()}")
    assert full.opening > a3.opening + 0.03 and full.accelerating > a3.accelerating + 0.03
