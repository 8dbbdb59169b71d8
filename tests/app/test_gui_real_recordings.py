"""The explorer on an unlabelled articulograph corpus: sparse markers drawn as lips, the editor's targets from
kinematic landmarks (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def ema_manifold(make_articulograph_manifold):
    return make_articulograph_manifold(n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, n_states=16)


def test_unlabelled_sparse_markers_in_the_explorer(qapp, qtbot, ema_manifold, main_window_factory):
    from app.scene import SensorsHandle

    m = ema_manifold
    with main_window_factory(qapp, m, size=(1100, 800)) as w:
        lv = w.lip_view
        assert isinstance(lv.main, SensorsHandle) and lv.main.label_texts[:4] == ["UL", "LL", "LC", "RC"]
        u = m.corpus_.utterances[1]
        s, ed = w.state, w.editor
        ed.set_source("utterance")
        ed.utt_box.setCurrentIndex(1)
        assert ed.load()  # no phones: the targets are the utterance's kinematic landmarks
        ed.set_method("linear")
        ed.synthesize()
        qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
        s.set_playback(10)
        from engine.recordings.corpus import frame_points
        from engine.recordings.orientation import anatomical_frame

        talker = anatomical_frame(m.corpus_, m.shape_.mean_)  # the lips drawn seen from the front
        np.testing.assert_allclose(lv.main.points, talker.view(frame_points(m.corpus_.frames[u.start + 10], 3)),
                                   atol=1e-4)
