"""Articulograph data shown as articulograph data in the window's lip view (needs a display: Xvfb).

After VisArtico and mview: sensors are spheres joined by straight lines and labelled, the lip aperture is a line
with its value in mm, a 2-D midsagittal recording is a profile that shows which way the face looks, and a
recording whose alignment runs past its data says so when it is opened. Checked on the screen's pixels and on
the scene; the data are made the way real recordings are (:mod:`engine.talker.example_corpora`).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def ema(make_articulograph_manifold):
    return make_articulograph_manifold(n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, n_states=16)


@pytest.fixture(scope="module")
def midsagittal(tmp_path_factory):
    from engine.manifold.model import Manifold
    from engine.talker.example_corpora import midsagittal_corpus

    folder = tmp_path_factory.mktemp("mocha")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the import notes are checked below
        return folder, Manifold(n_states=16).fit(midsagittal_corpus(folder, n_utterances=3))


def _screen(qapp, view):
    for _ in range(5):
        qapp.processEvents()
    view.renderer.flush(sync=True)
    img = view.plotter.screenshot(None, return_img=True)
    return np.asarray(img, np.int16)


def _ink(img, plotter, xyz, r=2) -> bool:
    """Whether the screen shows something dark (not the white background) around the scene point ``xyz``."""
    from app.scene import pick_display_point

    x, y = pick_display_point(plotter, np.asarray(xyz, float))
    h = img.shape[0]
    row, col = int(round(h - 1 - y)), int(round(x))
    patch = img[max(row - r, 0):row + r + 1, max(col - r, 0):col + r + 1, :3]
    return bool(patch.size) and int(patch.sum(axis=2).min()) < 3 * 200


def test_four_lip_sensors_are_spheres_joined_by_lines_with_the_aperture_in_mm(qapp, ema, main_window_factory):
    from app.scene import SensorsHandle

    with main_window_factory(qapp, ema, size=(1300, 850)) as w:
        lv = w.lip_view
        w.state.select_frame(30)
        img = _screen(qapp, lv)
        h = lv.main
        assert isinstance(h, SensorsHandle) and lv.drawing.kind == "sensors"
        assert h.label_texts[:4] == ["UL", "LL", "LC", "RC"]
        from engine.recordings.kinematics import lip_aperture

        value = float(lip_aperture(ema.corpus_)[30])
        assert h.aperture_value == pytest.approx(value, rel=1e-4)
        assert h.label_texts[4] == f"{value:.1f} mm"
        P = h.points
        # the line from the upper lip to the left corner is drawn, straight: ink half-way along it
        names = ema.corpus_.point_names
        ul, lc = P[names.index("UL")], P[names.index("LC")]
        assert _ink(img, lv.plotter, 0.5 * (ul + lc))
        # and nothing is drawn between the sensors where no line runs: no interpolated, filled mouth
        ll, rc = P[names.index("LL")], P[names.index("RC")]
        inside = 0.5 * (0.5 * (ul + lc) + 0.5 * (ll + rc))  # half-way across the mouth, off every line
        assert not _ink(img, lv.plotter, inside + 0.15 * (lc - ul), r=1)
        assert all(a.GetMapper().GetPlaceAllLabels() for a in h.label_actors)  # every label placed, none hidden
        assert "sensors as measured" in lv.caption.toolTip()


def test_a_midsagittal_recording_is_a_profile_facing_right(qapp, midsagittal, main_window_factory):
    _, m = midsagittal
    with main_window_factory(qapp, m, size=(1300, 850)) as w:
        lv = w.lip_view
        img = _screen(qapp, lv)
        h = lv.main
        assert lv.drawing.view == "profile" and lv.drawing.forward == (1.0, 0.0)
        assert h.label_texts[:3] == ["UL", "LL", "LI"] and h.label_texts[-1] == "front"
        arrow = np.asarray(h._arrow.points)
        assert np.ptp(arrow[:, 0]) > 3 * np.ptp(arrow[:, 1])  # along +x: the face looks to the right
        tip = arrow[np.argmax(arrow[:, 0])]
        assert tip[0] > h.points[:, 0].max()  # in front of the lips
        assert _ink(img, lv.plotter, arrow.mean(axis=0))
        # the lower incisor (jaw) is behind the lips: the profile's left
        P = h.points
        assert P[2, 0] < min(P[0, 0], P[1, 0])


def test_haskins_jaw_and_lower_lip_labels_do_not_hide_each_other(qapp, shared_data, main_window_factory):
    """The real Haskins sample: its JAW sensor sits just below LL; both labels are placed, apart."""
    from app.files.source_loading import read_recording
    from engine.manifold.model import Manifold

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = Manifold().fit(read_recording(shared_data / "haskins-ieee" / "F01_B01_S01_R01_N.mat"))
    with main_window_factory(qapp, m, size=(1300, 850)) as w:
        h = w.lip_view.main
        _screen(qapp, w.lip_view)
        assert {"UL", "LL", "ML", "JAW", "JAWL"} <= set(h.label_texts)
        from app.scene.sensors import GAP

        # the labels' directions keep them apart (at full spacing; the texts start GAP of it out, running away)
        anchors = np.array([np.asarray(h.points)[i, :2] + d * h._reach for i, d in zip(h._label_of, h._dirs)])
        gaps = [np.linalg.norm(a - b) for i, a in enumerate(anchors) for b in anchors[i + 1:]]
        assert min(gaps) >= 1.9 * h._reach and 0 < GAP <= 1


def test_an_alignment_running_past_the_data_is_said_when_the_recording_is_opened(midsagittal, qapp, qtbot,
                                                                                 main_window_factory):
    """MOCHA's .lab ends 0.25 s after its data (a final pause): the window's load says where it was cut."""
    from engine.io.errors import ImportDataWarning

    folder, m = midsagittal
    path = folder / "msak0_001.ema"
    from app.files.source_loading import read_recording

    with pytest.warns(ImportDataWarning, match=r"runs to [0-9.]+ s but the data last [0-9.]+ s.*'sil'"):
        read_recording(path)
    with main_window_factory(qapp, m, size=(1300, 850)) as w:
        runner = w.open_source(str(path))
        qtbot.waitUntil(lambda: runner.state != "running", timeout=120000)
        assert runner.state == "done"
        assert any("runs to" in x and "the data last" in x for x in runner.warnings), runner.warnings
        assert "warning" in w.statusBar().currentMessage()
