"""The manifold view on its own (needs a display): horizon, overlay, hover, standard views, legends, Esc."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def view(qapp, app_manifold):
    from app.models.state import AppState
    from app.views.manifold_view import ManifoldView

    v = ManifoldView(AppState(app_manifold))
    v.resize(1000, 750)
    v.show()
    for _ in range(5):
        qapp.processEvents()
    yield v
    v.close_view()
    v.close()


@pytest.fixture
def fresh(view, qapp):
    view.state.reset_view()
    view.renderer.flush(sync=True)
    return view


def _front_state_frame(view, m):
    cam = np.array(view.plotter.camera.position)
    return int(np.argmin(np.linalg.norm(m.Fy_[:, :3] - cam, axis=1)))


def test_horizon_slider_dims_states_beyond_it_on_an_integer_scale(fresh, qtbot, app_manifold):
    v, s, m = fresh, fresh.state, app_manifold
    i = _front_state_frame(v, m)
    s.select_frame(i)
    v.horizon_slider.setValue(2)                     # the slider moves in frame periods: 33 ms = 2 hops at 60/s
    assert s.horizon_ms == pytest.approx(2000 / m.corpus_.rate) and "33 ms = 2 hops" in v.horizon_label.text()
    vals = v.handles["points"].values
    d = m.states_.future(s.state)[m.states_.labels_]
    np.testing.assert_array_equal(np.isfinite(vals), d <= 2)            # what is drawn: hops 0..2, rest NaN
    rgb = v.handles["points"].rgb
    assert len(np.unique(rgb[d > 2], axis=0)) == 1                       # one dimmed grey outside
    bar = v._bar
    assert bar.GetVisibility() and bar.GetUseCustomLabels()
    labels = [bar.GetCustomLabels().GetValue(k) for k in range(bar.GetCustomLabels().GetNumberOfTuples())]
    assert labels == [0.0, 1.0, 2.0]                                    # ticks at whole hops only
    assert bar.GetLookupTable().GetNumberOfTableValues() == 3
    assert f"{100 * (d <= 2).mean():.1f}% of frames" in v.info.text()
    v.horizon_box.setChecked(False)                                     # no horizon: every reachable state
    assert s.horizon_ms is None and np.isfinite(v.handles["points"].values).sum() == np.isfinite(d).sum()
    v.hemi_box.setCurrentIndex(v.hemi_box.findData("both"))
    assert (v.handles["points"].values < 0).any()                       # the past side, on the same scale


def test_selection_path_and_trajectories_are_drawn_over_the_cloud(fresh, app_manifold):
    v, s, m = fresh, fresh.state, app_manifold
    overlay = v.plotter._lipspace_overlay
    assert overlay.GetLayer() == 1 and v.plotter.render_window.GetNumberOfLayers() >= 2
    assert overlay.GetActiveCamera() is v.plotter.renderer.GetActiveCamera()
    for key in ("marker", "target", "path", "original", "synthetic"):
        assert overlay.HasViewProp(v.handles[key].actor) and not v.plotter.renderer.HasViewProp(v.handles[key].actor)
    assert v.plotter.renderer.HasViewProp(v.handles["points"].actor)
    # a selected frame deep inside the cloud still shows its yellow marker on screen
    centre = m.Fy_[:, :3].mean(0)
    i = int(np.argmin(np.linalg.norm(m.Fy_[:, :3] - centre, axis=1)))
    s.select_frame(i)
    v.handles["local"].set_visible(False)  # the frame's own arrows start at the marker and may cover it
    v.renderer.flush(sync=True)
    from app.scene import pick_display_point

    x, y = pick_display_point(v.plotter, m.Fy_[i, :3])
    v.plotter.render_window.Render()  # a synchronous frame of the current scene (Qt may hold a stale one)
    img = v.plotter.screenshot()
    h = img.shape[0]
    patch = img[h - 1 - int(y) - 2:h - 1 - int(y) + 3, int(x) - 2:int(x) + 3].reshape(-1, 3).astype(int)
    yellow = (patch[:, 0] > 200) & (patch[:, 1] > 170) & (patch[:, 2] < 80)
    vis = {k: (v.handles[k].visible if hasattr(v.handles[k], "visible") else None) for k in v.OVERLAY}
    assert yellow.any(), (patch, vis, img.shape, v.plotter.render_window.GetSize(), (x, y))


def test_hover_reads_out_the_frame_under_the_pointer(fresh, qtbot, app_manifold):
    from app.models.picking import hover_text
    from app.scene import pick_display_point

    v, s, m = fresh, fresh.state, app_manifold
    i = _front_state_frame(v, m)
    x, y = pick_display_point(v.plotter, m.Fy_[i, :3])
    got = v.hover_frame((x, y))
    assert got is not None and np.linalg.norm(m.Fy_[got, :3] - m.Fy_[i, :3]) < 0.05 * np.ptp(m.Fy_[:, :3])
    assert v.hover_frame((-50, -50)) is None
    s.set_hover(got)
    text = v.hover_label.text()
    assert f"frame {got}" in text and f"state {int(m.states_.labels_[got])}" in text and "phone" in text
    assert hover_text(m, s.phones, got) in text
    assert s.frame is None                                             # hovering never selects


def test_standard_views_and_the_default_camera(fresh, app_manifold):
    v, m = fresh, app_manifold
    t = m.tangent_
    V = t.plane_normal_ / np.linalg.norm(t.plane_normal_)
    cam = v.plotter.renderer.GetActiveCamera()

    def view_dir():
        return np.subtract(cam.GetFocalPoint(), cam.GetPosition()) / cam.GetDistance()

    v.view_btns["side"].click()
    assert abs(view_dir() @ V) < 1e-6 and np.dot(cam.GetViewUp(), V) > 0.999   # the plane seen edge on
    v.view_btns["top"].click()
    assert view_dir() @ V < -0.999                                       # looking down V
    v.view_btns["default"].click()
    assert -0.6 < view_dir() @ V < -0.2                                  # from above, but both halves apart


def test_phone_colouring_has_a_legend_and_a_filter(fresh, qtbot, app_manifold):
    v, s = fresh, fresh.state
    v.color_box.setCurrentIndex(v.color_box.findData("phone"))
    assert v.phone_edit.isEnabled()
    legend = v.legend
    assert legend is not None and legend.GetNumberOfEntries() <= 17
    assert legend in list(v.plotter.actors.values())
    renders = []
    obs = v.plotter.render_window.AddObserver("EndEvent", lambda *_a: renders.append(1))
    try:
        v.phone_edit.setText("p b m")
        v.phone_edit.editingFinished.emit()
        assert renders == []  # the new legend is added without a render of its own: the scheduler renders once
    finally:
        v.plotter.render_window.RemoveObserver(obs)
    assert s.phone_filter == {"p", "b", "m"}
    assert v.legend.GetNumberOfEntries() == 4              # the same box, its rows changed in place
    assert [v.legend.GetEntryString(i) for i in range(4)] == ["b", "m", "p", "other phones (dimmed)"]
    s.set_visible_phones(["p"])                                          # ellipsoid shown: points dimmed
    from app.models.colouring import OUTSIDE_RGB

    rgb = v.handles["points"].rgb.astype(float) / 255
    assert np.abs(rgb - np.asarray(OUTSIDE_RGB)).max(axis=1).mean() < 0.2


def test_esc_clears_the_selection_and_nothing_else(fresh, qtbot, app_manifold):
    from PySide6 import QtCore, QtGui

    from app.models.colouring import DENSITY_TITLE

    v, s = fresh, fresh.state
    s.set_horizon(50)
    s.set_phone_filter(["p"])
    s.set_visible_phones(["p", "m"])
    s.set_ellipsoid_opacity(0.6)
    s.set_layer_visible("plane", False)
    s.select_frame(_front_state_frame(v, app_manifold))
    assert s.color_mode == "distance" and "hops" in v._bar.GetTitle()
    settings = s.settings_values()
    assert v.esc_shortcut.key().matches(QtGui.QKeySequence(QtCore.Qt.Key.Key_Escape)) == \
        QtGui.QKeySequence.SequenceMatch.ExactMatch
    v.esc_shortcut.activated.emit()  # Esc (no window manager under Xvfb gives the test window the focus)
    assert s.frame is None and s.state is None and s.target is None and s.path is None
    assert s.settings_values() == settings                 # colouring, horizon, filter, ellipsoids, layers stay
    assert set(v.ellipsoids) >= {"p", "m"} and v.ellipsoids["p"].visible and not v.handles["plane"].visible
    assert "Click a point" in v.info.text()
    s.reset_settings()                                      # the view's reset is its own command
    assert s.color_mode == "density" and s.visible_phones == frozenset() and s.horizon_ms == 100
    assert v._bar.GetTitle() == DENSITY_TITLE and not v._bar.GetUseCustomLabels()
    assert v.color_box.currentData() == "density" and v.handles["plane"].visible and v.plane_box.isChecked()


def test_leaving_the_component_panel_returns_the_lips_to_the_selection(qapp, app_manifold):
    from app.models.state import AppState
    from app.views.scree_panel import ScreePanel

    s = AppState(app_manifold)
    panel = ScreePanel(s)
    panel.show()
    qapp.processEvents()
    assert panel.canvas is None  # the plot waits until the panel is on screen (its dock tab raised)
    assert panel.spin.maximum() == app_manifold.shape_.n_components_
    panel.set_on_screen(True)
    lines = panel.figure.axes[0].get_lines()  # drawn then: the X and Y residual curves
    assert [ln.get_label() for ln in lines] == ["X residual (shape)", "Y residual (shape + velocity)"]
    panel.show_box.setChecked(True)
    assert s.component == 0
    panel.hide()  # another dock tab raised, or the dock closed
    qapp.processEvents()
    assert s.component is None and not panel.show_box.isChecked()
    panel.close_view()


def test_exported_view_is_vector_with_the_hop_bar_title_clear_of_its_ticks(fresh, tmp_path, app_manifold):
    import xml.etree.ElementTree as ET

    from app.figures.export import save_plotter_vector
    from app.figures.view_vector import scene_figure

    v, s = fresh, fresh.state
    s.select_frame(_front_state_frame(v, app_manifold))
    v.renderer.flush(sync=True)
    fig = scene_figure(v.plotter)
    n_shown = int(v.handles["points"].visible) * app_manifold.Fy_.shape[0]
    assert fig.lipspace["n_points"] >= n_shown                    # every frame a vector marker
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    bar = [ax for ax in fig.axes if ax.get_title(loc="right") == "future hops"]
    assert len(bar) == 1
    ticks = [t for t in bar[0].yaxis.get_ticklabels() if t.get_text()]
    assert [t.get_text() for t in ticks] == [str(k) for k in range(len(ticks))]   # whole hops 0, 1, 2, ...
    title = bar[0]._right_title  # right-aligned over the bar: it never runs off the view's right edge
    tb = title.get_window_extent(r)
    assert not any(tb.overlaps(t.get_window_extent(r)) for t in ticks)
    root = ET.fromstring(save_plotter_vector(v.plotter, tmp_path / "view.SVG").read_bytes())
    tags = [el.tag.rsplit("}", 1)[-1] for el in root.iter()]
    assert "image" not in tags and tags.count("path") + tags.count("use") > app_manifold.Fy_.shape[0]


def test_controls_wrap_so_a_narrow_dock_still_fits(fresh, qapp):
    v = fresh
    assert v.minimumSizeHint().width() <= 480        # one row of every control needed over 1,000 px
    rows = {w.parentWidget().y() for w in (v.color_box, v.hemi_box, v.path_box, v.clear_btn)}
    v.resize(440, 500)
    qapp.processEvents()
    narrow = {w.parentWidget().y() for w in (v.color_box, v.hemi_box, v.path_box, v.clear_btn)}
    assert len(narrow) > len(rows) or len(narrow) == 4   # the groups went to new rows
    for w in (v.color_box, v.hemi_box, v.path_box, v.clear_btn):
        assert w.parentWidget().geometry().right() <= v.width()   # nothing pushed out of the view
    v.resize(1000, 750)
    qapp.processEvents()


def test_window_reset_camera_and_export_dialog(qapp, qtbot, app_manifold, tmp_path, monkeypatch):
    import xml.etree.ElementTree as ET

    from PySide6 import QtWidgets

    from app.main_window import MainWindow

    w = MainWindow(app_manifold, source={"path": None, "preset": "small"})
    try:
        w.resize(1200, 800)
        w.show()
        qapp.processEvents()
        # File > Export figure > Manifold view: no suffix typed, the SVG filter chosen -> view.svg, vector,
        # written by a worker thread; the width asked: one journal column
        from app.views import export_dialog

        monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName",
                            staticmethod(lambda *a, **k: (str(tmp_path / "view"), "SVG (*.svg)")))
        asked = []

        def exec_(dlg):
            asked.append((dlg.screen.isVisibleTo(dlg), dlg.dpi.isVisibleTo(dlg)))
            dlg.one.setChecked(True)
            dlg.dpi.setValue(200)
            return QtWidgets.QDialog.DialogCode.Accepted

        monkeypatch.setattr(export_dialog.ExportOptionsDialog, "exec", exec_)
        w.export_view_dialog("manifold")
        qtbot.waitUntil(lambda: "wrote" in w.statusBar().currentMessage(), timeout=60000)
        qtbot.waitUntil(lambda: QtWidgets.QApplication.activeModalWidget() is None, timeout=10000)
        root = ET.parse(tmp_path / "view.svg").getroot()
        tags = [el.tag.rsplit("}", 1)[-1] for el in root.iter()]
        assert "image" not in tags and "path" in tags
        assert float(root.get("width").rstrip("pt")) == pytest.approx(85 / 25.4 * 72, abs=0.5)  # 85 mm wide
        assert asked[-1] == (True, False)  # a view may be written as on screen; an SVG has no resolution
        assert w.export_options.width_mm == 85
        # PNG: the DPI asked for is the DPI written, at the width asked for
        monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName",
                            staticmethod(lambda *a, **k: (str(tmp_path / "v.PNG"), "SVG (*.svg)")))
        w.statusBar().clearMessage()
        w.export_view_dialog("manifold")
        qtbot.waitUntil(lambda: "wrote" in w.statusBar().currentMessage(), timeout=60000)
        from PIL import Image

        with Image.open(tmp_path / "v.PNG") as im:
            assert im.info["dpi"] == pytest.approx((200, 200), abs=0.01)
            assert im.size[0] == pytest.approx(85 / 25.4 * 200, abs=1)
        assert asked[-1] == (True, True)
        w.show()
        qapp.processEvents()
        view = w.manifold_view
        cam = view.plotter.renderer.GetActiveCamera()
        lips = w.lip_view.plotter.renderer.GetActiveCamera()
        framed = np.array([lips.GetPosition(), lips.GetFocalPoint()])
        lips.Zoom(2.0)
        lips.Azimuth(30.0)
        view.standard_view("top")
        w.reset_cameras()
        # the lips as first framed (from the front, room for the sensors' labels), not a bare fit to their bounds
        np.testing.assert_allclose([lips.GetPosition(), lips.GetFocalPoint()], framed, rtol=1e-6, atol=1e-9)
        V = app_manifold.tangent_.plane_normal_ / np.linalg.norm(app_manifold.tangent_.plane_normal_)
        d = np.subtract(cam.GetFocalPoint(), cam.GetPosition()) / cam.GetDistance()
        assert -0.6 < d @ V < -0.2     # from slightly above the plane, not looking down on it
    finally:
        w.close()


def test_a_level_of_detail_cloud_is_coloured_from_every_frame_and_clicks_find_undrawn_frames(qapp, app_manifold,
                                                                                            monkeypatch):
    """Above the cap the view draws one point per group of frames: its hemisphere colour is its frames' (one
    state), its density that of its grid cell over every frame; a click finds the frame under the cursor among
    all frames, also one the view does not draw; the readout counts frames."""
    import app.models.lod
    from app.models.picking import frame_under_cursor
    from app.models.state import AppState
    from app.scene import pick_display_point
    from app.scene.projection import project, view_transform
    from app.views.manifold_view import ManifoldView

    m = app_manifold
    import app.models.state.derived

    monkeypatch.setattr(app.models.lod, "DEFAULT_MAX_POINTS", 800)
    # not another test's cloud
    monkeypatch.setattr(app.models.state.derived, "PREPARED", type(app.models.state.derived.PREPARED)())
    s = AppState(m)
    v = ManifoldView(s)
    try:
        v.resize(900, 650)
        v.show()
        for _ in range(5):
            qapp.processEvents()
        cd = s.cloud
        h = v.handles["points"]
        assert not cd.whole and h.mesh.n_points == cd.n_points <= 800
        np.testing.assert_array_equal(h.values, cd.density)  # density mode: every frame of the cell counted
        M, size = view_transform(v.plotter)
        xy, depth = project(np.asarray(m.Fy_[:, :3], np.float64), M, size)
        undrawn = np.setdiff1d(np.arange(len(xy)), cd.frames)
        front = undrawn[np.argsort(depth[undrawn])[:40]]
        hits = 0
        for f in front:  # clicks at frames that are not drawn
            x, y = pick_display_point(v.plotter, m.Fy_[f, :3])
            want = frame_under_cursor(xy, depth, (x, y), dot_radius=v.locator.dot_radius, radius=v.locator.radius)
            assert v.picker.pick(x, y) == want
            hits += want not in set(cd.frames.tolist())
        assert hits > 0 and s.frame is not None  # undrawn frames were selected
        s.select_frame(int(front[0]))
        future = m.states_.future(s.state)
        hops = np.where(future <= 6, future, np.nan)[cd.state]  # the default 100 ms = 6 hops at 60 Hz
        np.testing.assert_array_equal(h.values, hops.astype(np.float32))  # each point: its frames' state's hops
        inside = (future <= 6)[m.states_.labels_]
        assert f"{100 * inside.mean():.1f}% of frames ({int(inside.sum()):,}/{len(inside):,})" in v.info.text()
    finally:
        v.close_view()
        v.close()


# ------------------------------------------------------------------ a view that explains itself
def test_axes_are_named_with_their_share_of_variance_and_hidden_with_the_axes_layer(fresh, app_manifold):
    v, s = fresh, fresh.state
    ev = app_manifold.embedding_.explained_variance_ratio_
    labels = v.handles["yaxes"]["labels"]
    texts = v.handles["yaxes"]["names"]
    assert texts == [f"Y{j + 1} · {100 * ev[j]:.0f}% of variance" for j in range(3)]
    assert labels.GetVisibility() and v.handles["yaxes"]["lines"].visible
    s.set_layer_visible("axes", False)
    assert not labels.GetVisibility() and not v.handles["axes"]["S"].visible and not v.axes_box.isChecked()
    rows = [r[0] for r in v.legend_rows["glyphs"]]
    assert not any(r.startswith("S:") for r in rows)


def test_every_glyph_drawn_has_a_row_in_the_legend(fresh, app_manifold):
    v, s, m = fresh, fresh.state, app_manifold
    rows = lambda: [r[0] for r in v.legend_rows["glyphs"]]  # noqa: E731
    assert "S: global shape direction" in rows() and "zero-velocity plane (V = 0)" in rows()
    s.select_frame(_front_state_frame(v, m))
    far = int(np.flatnonzero(np.isfinite(m.states_.future(s.state)))[-1])
    s.set_target(far)
    s.set_utterance(m.corpus_.utterances[0].id)
    s.set_visible_phones(["p"])
    want = {"selected frame", "target state", f"original trajectory ({m.corpus_.utterances[0].id})",
            "s_i: local shape direction", "v_i: local velocity direction", "n_i: normal of the local plane",
            "p: 2-s.d. ellipsoid"}
    assert want <= set(rows()) and any(r.startswith("fewest-hop path") for r in rows())
    box = v.legends["glyphs"]
    assert box.GetVisibility() and box.GetNumberOfEntries() == len(rows())
    # the ellipsoid's row is in its palette colour, and a ring
    row = next(r for r in v.legend_rows["glyphs"] if r[0] == "p: 2-s.d. ellipsoid")
    assert row[1] == pytest.approx(s.palette.colour("phone", "p")) and row[2] == "ring"
    # in distance mode the point legend names the greys of "beyond the horizon" and "unreachable"
    assert [r[0] for r in v.legend_rows["points"]] == ["beyond the horizon", "unreachable"]
    s.set_layer_visible("legend", False)
    assert not v.legends["glyphs"].GetVisibility() and not v.legends["points"].GetVisibility()
    s.set_layer_visible("legend", True)
    s.set_utterance(None)


def test_trajectories_and_paths_show_their_direction(fresh, app_manifold):
    v, s, m = fresh, fresh.state, app_manifold
    s.select_frame(_front_state_frame(v, m))
    far = int(np.flatnonzero(np.isfinite(m.states_.future(s.state)))[-1])
    s.set_target(far)
    path = v.handles["path"]
    pos, u = path.arrows
    assert len(pos) == 5
    C = m.states_.centroids_[np.asarray(s.path), :3]
    np.testing.assert_allclose(pos[-1], C[-1], atol=1e-6)           # the last cone at the target
    assert np.all(np.einsum("ij,ij->i", u, np.diff(C, axis=0)[np.minimum(
        np.searchsorted(np.r_[0, np.cumsum(np.linalg.norm(np.diff(C, axis=0), axis=1))], np.linalg.norm(
            np.diff(C, axis=0), axis=1).sum() * np.arange(1, 6) / 5) - 1, len(C) - 2)]) > 0)  # pointing forward
    s.set_utterance(m.corpus_.utterances[0].id)
    assert len(v.handles["original"].arrows[0]) == 5
    s.set_utterance(None)


def test_the_hover_readout_goes_with_the_file(fresh, app_manifold):
    v, s = fresh, fresh.state
    s.set_hover(_front_state_frame(v, app_manifold))
    assert "under the pointer" in v.hover_label.text()
    s.set_manifold(app_manifold)                                       # another file opened
    assert v.hover_label.text() == ""


def test_an_ellipsoid_reads_at_a_glance_outline_and_adjustable_fill(fresh, app_manifold):
    """A ticked cluster draws an opaque outline in its colour's darker shade around a fill whose opacity
    the user sets; the outline shows even with no fill."""
    from app.scene.manifold import outline_colour

    v, s = fresh, fresh.state
    s.set_layer_visible("points", False)
    s.set_layer_visible("plane", False)
    s.set_layer_visible("axes", False)
    s.set_layer_visible("legend", False)
    s.set_visible_phones(["p"])
    v.frame_selection()
    e = v.ellipsoids["p"]
    colour = s.palette.colour("phone", "p")
    np.testing.assert_allclose(e.actor.prop.color.float_rgb, colour, atol=1e-6)
    assert e.actor.prop.opacity == pytest.approx(0.3)

    def outline_pixels():
        v.renderer.flush(sync=True)
        v.plotter.render_window.Render()
        img = v.plotter.screenshot().astype(int)
        want = np.rint(255 * np.asarray(outline_colour(colour))).astype(int)
        return int((np.abs(img - want).max(axis=-1) <= 40).sum())

    ring = outline_pixels()
    assert ring > 200                                                  # the outline is drawn
    s.set_ellipsoid_opacity(0.0)
    assert not e.actor.GetVisibility() and e.outline.GetVisibility() and outline_pixels() > 200
    s.set_ellipsoid_opacity(0.8)
    assert e.actor.prop.opacity == pytest.approx(0.8)
    s.set_visible_phones([])
    assert not e.visible


def test_frame_the_selection_brings_the_ticked_clusters_into_view(fresh, app_manifold):
    from app.scene.projection import project, view_transform

    v, s = fresh, fresh.state
    s.set_visible_phones(["p", "b"])
    cam = v.plotter.renderer.GetActiveCamera()
    cam.Zoom(0.05)                                                     # zoomed far out: the clusters a few pixels
    cam.Azimuth(30)
    direction = np.subtract(cam.GetFocalPoint(), cam.GetPosition()) / cam.GetDistance()
    assert v.frame_selection()
    d2 = np.subtract(cam.GetFocalPoint(), cam.GetPosition()) / cam.GetDistance()
    np.testing.assert_allclose(d2, direction, atol=1e-6)             # the direction of view is kept
    verts = np.vstack([np.asarray(s.clusters.ellipsoid(p)[0])[:, :3] for p in ("p", "b")])
    M, size = view_transform(v.plotter)
    xy, _ = project(verts, M, size)
    assert np.all((xy >= 0) & (xy <= np.asarray(size)))               # every ellipsoid whole on screen
    span = (xy.max(0) - xy.min(0)) / np.asarray(size)
    assert span.max() > 0.4                                           # and filling the view
    s.set_visible_phones([])
