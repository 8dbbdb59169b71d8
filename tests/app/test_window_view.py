"""The window's 3-D view in daily use: one colour per category everywhere, Esc and the view's undo history,
frame the selection from the View menu (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def shared_window(qapp, app_manifold, main_window_factory):
    with main_window_factory(qapp, app_manifold, size=(1600, 1000)) as w:
        yield w


@pytest.fixture
def fresh(fresh_window):
    """The shared window, reset for each test (conftest's ``fresh_window``)."""
    return fresh_window


def test_ticked_phones_have_one_colour_in_view_legends_table_and_phone_colouring(fresh, qtbot):
    """/p b m/ ticked in the clusters table: the same colour for each in the table's swatch, its ellipsoid and
    member points, the glyph legend, and the phone colouring's legend and points."""
    from PySide6 import QtCore, QtGui

    from app.views.clusters_panel import _SWATCH_ROLE

    w = fresh
    s, view, panel = w.state, w.manifold_view, w.clusters
    items = {panel.table.item(i, 0).text(): panel.table.item(i, 0) for i in range(panel.table.rowCount())}
    for ph in ("p", "b", "m"):
        items[ph].setCheckState(QtCore.Qt.CheckState.Checked)         # the user ticks the phones
    assert s.visible_phones == {"p", "b", "m"}
    s.set_color_mode("phone")
    s.set_phone_filter(["p", "b", "m"])
    point_rows = {r[0]: r[1] for r in view.legend_rows["points"]}
    glyph_rows = {r[0].split(":")[0]: r[1] for r in view.legend_rows["glyphs"] if r[2] == "ring"}
    hexes = set()
    for ph in ("p", "b", "m"):
        want = QtGui.QColor.fromRgbF(*s.palette.colour("phone", ph)).name()
        hexes.add(want)
        assert items[ph].data(_SWATCH_ROLE) == want                                      # the table's swatch
        assert QtGui.QColor.fromRgbF(*view.ellipsoids[ph].actor.prop.color.float_rgb).name() == want  # ellipsoid
        assert QtGui.QColor.fromRgbF(*view.members[ph].actor.prop.color.float_rgb).name() == want     # its points
        assert QtGui.QColor.fromRgbF(*glyph_rows[ph]).name() == want                     # the glyph legend
        assert QtGui.QColor.fromRgbF(*point_rows[ph]).name() == want                     # the phone legend
        f = int(np.flatnonzero(s.phones == ph)[0])                                       # a point of the phone
        s.set_visible_phones(set())                                                      # (undimmed)
        assert QtGui.QColor(*map(int, view.handles["points"].rgb[f])).name() == want     # the point itself
        s.set_visible_phones({"p", "b", "m"})
    assert len(hexes) == 3                                             # three phones, three colours
    # the colours are the session's: kept in the session file
    d = w.state.palette.to_dict()
    assert d["ranking"]["phone"][:3] == s.palette.levels("phone")[:3]


def test_a_new_palette_recolours_the_cluster_swatches(fresh):
    """A palette set on its own (a session's, restored) gives every swatch its label's new colour."""
    from PySide6 import QtGui

    from app.models.palette import SessionPalette
    from app.views.clusters_panel import _SWATCH_ROLE

    w = fresh
    s, panel = w.state, w.clusters
    items = {panel.table.item(i, 0).text(): panel.table.item(i, 0) for i in range(panel.table.rowCount())}
    d = s.palette.to_dict()
    ranking = d["ranking"]["phone"]
    i, j = [k for k, ph in enumerate(ranking) if ph in items][:2]     # two phones the table shows
    first, second = ranking[i], ranking[j]
    ranking[i], ranking[j] = second, first                             # their colours swapped
    old = {ph: QtGui.QColor.fromRgbF(*s.palette.colour("phone", ph)).name() for ph in (first, second)}
    before = s.palette
    s.set_palette(SessionPalette.from_dict(d))
    try:
        assert items[first].data(_SWATCH_ROLE) == old[second] and items[second].data(_SWATCH_ROLE) == old[first]
        assert panel.table.rowCount() == len(panel.rows) > 2           # the rows stayed
    finally:
        s.set_palette(before)                                          # the shared window's own palette back


def test_view_settings_join_undo_and_esc_touches_none_of_them(fresh, qtbot, app_manifold):
    from PySide6 import QtCore, QtGui

    w = fresh
    s, view = w.state, w.manifold_view
    view.color_box.setCurrentIndex(view.color_box.findData("class"))
    view.horizon_slider.setValue(3)                                   # a drag: several values, one command
    view.horizon_slider.setValue(4)
    s.set_visible_phones({"p"})
    w.clusters.opacity_slider.setValue(70)
    view.plane_box.setChecked(False)
    assert s.color_mode == "class" and s.ellipsoid_opacity == pytest.approx(0.7) and "plane" in s.hidden_layers
    s.select_frame(40)                                                 # a click: colours by hop distance
    assert s.color_mode == "distance"
    settings = s.settings_values()
    view.esc_shortcut.activated.emit()                                 # Esc: the selection only
    assert s.frame is None and s.state is None and s.settings_values() == settings
    assert w.undo_action.shortcut().toString() == "Ctrl+Z" and w.undo_action.isEnabled()
    assert "layers" in w.undo_action.text()
    w.undo_action.trigger()                                            # the plane back
    assert "plane" not in s.hidden_layers and view.plane_box.isChecked()
    w.undo_action.trigger()
    assert s.ellipsoid_opacity == pytest.approx(0.3)
    w.undo_action.trigger()
    assert s.visible_phones == frozenset()
    w.undo_action.trigger()                                            # the whole slider drag at once
    assert s.horizon_ms == pytest.approx(100)
    w.redo_action.trigger()
    assert s.horizon_ms == pytest.approx(4 * 1000 / app_manifold.corpus_.rate)
    # View › Reset view settings: one command, undone as one
    reset = w.reset_settings_action
    assert reset in w.menuBar().actions()[2].menu().actions()
    reset.trigger()
    assert s.color_mode == "density" and s.horizon_ms == pytest.approx(100)
    w.undo_action.trigger()
    assert s.horizon_ms == pytest.approx(4 * 1000 / app_manifold.corpus_.rate) and s.color_mode == "distance"
    # the editor's edits and the view's settings share the one history, newest first
    ed = w.editor
    assert ed.set_text("m 0.2 aa 0.3 p 0.2", source="phones")
    s.set_color_mode("phone")
    ed.timeline.select(0)
    assert ed.remove_selected()
    w.undo_action.trigger()                                            # the target edit, the newest
    assert len(ed.targets.targets) == 3 and s.color_mode == "phone"
    w.undo_action.trigger()                                            # then the colouring
    assert s.color_mode != "phone"
    assert QtGui.QKeySequence(QtCore.Qt.Key.Key_Escape).matches(view.esc_shortcut.key()) == \
        QtGui.QKeySequence.SequenceMatch.ExactMatch


def test_frame_the_selection_is_in_the_view_menu_on_f(fresh, qtbot):
    from app.scene.projection import project, view_transform

    w = fresh
    s, view = w.state, w.manifold_view
    a = w.frame_action
    assert a.shortcut().toString() == "F" and a in w.menuBar().actions()[2].menu().actions()
    s.set_visible_phones({"m"})
    view.plotter.renderer.GetActiveCamera().Zoom(0.05)
    a.trigger()
    verts = np.asarray(s.clusters.ellipsoid("m")[0])[:, :3]
    M, size = view_transform(view.plotter)
    xy, _ = project(verts, M, size)
    assert np.all((xy >= 0) & (xy <= np.asarray(size))) and ((xy.max(0) - xy.min(0)) / size).max() > 0.4
