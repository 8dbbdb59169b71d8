"""The Qt-free model of the tracks under the timeline: channels, values per utterance, fixed axes, events."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.tracks import TrackPanel


@pytest.fixture(scope="module")
def corpus(shared_data):
    from engine.io import read_corpus

    return read_corpus(sorted((shared_data / "haskins-ieee").glob("*.mat")))


def test_channels_values_and_fixed_ranges(corpus):
    from engine.recordings.signals.tracks import derived_track

    panel = TrackPanel(corpus)
    assert panel.channels == ("lip_aperture",) and "speed_UL" in panel.available
    events = []
    panel.changed.connect(events.append)
    panel.add("lip_protrusion")
    panel.add("speed_LL", index=0)
    panel.add("speed_LL")  # shown already: nothing
    assert panel.channels == ("speed_LL", "lip_aperture", "lip_protrusion") and events == ["channels"] * 2
    u = corpus.utterances[1]
    view = panel.view(u.id)
    assert view.utterance == u.id and view.times.shape == (u.n_frames,) and view.times[1] == pytest.approx(0.01)
    ap = view.channels[1]
    want = derived_track(corpus, "lip_aperture").values[u.start:u.stop]
    np.testing.assert_allclose(ap.values, want)
    lo, hi = ap.y_range
    assert lo < np.percentile(want, 5) and hi > np.percentile(want, 95)
    assert panel.view(corpus.utterances[0].id).channels[1].y_range == ap.y_range  # the same axis for every utterance
    assert panel.value_at("lip_aperture", u.start + 3) == pytest.approx(want[3])
    panel.move("speed_LL", 5)
    panel.remove("lip_protrusion")
    assert panel.channels == ("lip_aperture", "speed_LL")


def test_the_lowpass_changes_every_value_and_is_checked(corpus):
    panel = TrackPanel(corpus, channels=["speed_UL"])
    raw = TrackPanel(corpus, channels=["speed_UL"], lowpass_hz=None)
    events = []
    panel.changed.connect(events.append)
    a = panel.view(corpus.utterances[0]).channels[0].values
    b = raw.view(corpus.utterances[0]).channels[0].values
    assert np.std(np.diff(a)) < np.std(np.diff(b))  # the raw speed is rougher
    panel.set_lowpass(None)
    np.testing.assert_allclose(panel.view(corpus.utterances[0]).channels[0].values, b)
    assert events == ["lowpass"]
    with pytest.raises(ValueError, match="below the Nyquist frequency 50 Hz"):
        panel.set_lowpass(60)
    with pytest.raises(ValueError, match="no track 'speed_TT'"):
        panel.add("speed_TT")
    with pytest.raises(ValueError, match="is not shown"):
        panel.remove("lip_protrusion")
