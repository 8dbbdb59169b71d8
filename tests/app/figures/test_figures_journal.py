"""Figures a journal takes, for a real-style 4-sensor articulograph build (no phone labels) and the synthetic
talker (a mesh with phones), at one and two journal columns: the requested width, axis labels with units (or
"(arbitrary units)"), legends clear of the data, no text cut at the figure's edge, fonts of 6 pt or more and
embedded in PDF/SVG; the scree, fig2a and fig2c fixes; the manifold view's S and V labels inside the view."""
from __future__ import annotations

import contextlib
import re

import numpy as np
import pytest

import app.figures as F

WIDTHS_MM = (85.0, 180.0)
#: axis labels that are counts or fractions (no unit)
COUNTS = ("number of components", "component", "% of variance", "% of frames",
          "residual variance (fraction of the total)")


@pytest.fixture(scope="module")
def lab_manifold(make_articulograph_manifold):
    """A 4-sensor (UL, LL, LC, RC) build of three speakers as 'lipspace import' + 'build' make it."""
    from engine.recordings.kinematics import kinematic_if_unlabelled

    m = make_articulograph_manifold(n_speakers=3, n_utterances=3, duration_s=(2.0, 2.5), seed=5, n_states=40,
                                    name="lab")
    m.corpus_, _ = kinematic_if_unlabelled(m.corpus_)  # as 'lipspace figures' labels it
    return m


@contextlib.contextmanager
def _recorded_texts():
    """Every text the Agg renderer draws: (string, (x0, y0), (x1, y1), size in pt, canvas width, height)."""
    from matplotlib.backends.backend_agg import RendererAgg

    rec, orig = [], RendererAgg.draw_text

    def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
        w, h, d = self.get_text_width_height_descent(s, prop, ismath)
        a = np.radians(angle)
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        c = np.array([[0, -d], [w, -d], [w, h - d], [0, h - d]]) @ R.T + [x, self.height - y]
        rec.append((s, c.min(axis=0), c.max(axis=0), prop.get_size_in_points(), self.width, self.height))
        return orig(self, gc, x, y, s, prop, angle, ismath, mtext)

    RendererAgg.draw_text = draw_text
    try:
        yield rec
    finally:
        RendererAgg.draw_text = orig


def _render_all(m, widths=WIDTHS_MM):
    out = {}
    for w in widths:
        for name in F.FIGURES:
            fig = F.make_figure(name, m, width=w / 25.4)
            with _recorded_texts() as rec:
                fig.canvas.draw()
            out[(name, w)] = (fig, rec)
    return out


@pytest.fixture(scope="module")
def lab_figs(lab_manifold):
    return _render_all(lab_manifold)


@pytest.fixture(scope="module")
def talker_figs(small_manifold):
    return _render_all(small_manifold, widths=(85.0,))  # one column, the tighter layout (fig4: phones)


def _data_axes(fig):
    return [ax for ax in fig.axes if ax.axison and ax.get_label() != "<colorbar>"]


@pytest.mark.parametrize("which", ["lab_figs", "talker_figs"])
def test_every_figure_fits_the_page_with_no_text_cut_and_readable_fonts(which, request):
    figs = request.getfixturevalue(which)
    for (name, w), (fig, rec) in figs.items():
        assert fig.get_figwidth() * 25.4 == pytest.approx(w, abs=0.5), name
        assert fig.get_figheight() * 25.4 <= 240, (name, w)  # a journal page's text block
        assert len(rec) >= 5, name
        cut = [(s, lo.round(), hi.round()) for s, lo, hi, _, W, H in rec
               if lo[0] < -0.5 or lo[1] < -0.5 or hi[0] > W + 0.5 or hi[1] > H + 0.5]
        assert cut == [], (name, w, cut)
        small = [(s, size) for s, *_, size, _W, _H in [(r[0], r[1], r[2], r[3], r[4], r[5]) for r in rec]
                 if size < 6.0 - 1e-9]
        assert small == [], (name, w, small)


@pytest.mark.parametrize("which", ["lab_figs", "talker_figs"])
def test_legends_lie_outside_every_plotting_area(which, request):
    figs = request.getfixturevalue(which)
    n_legends = 0
    for (name, w), (fig, _) in figs.items():
        r = fig.canvas.get_renderer()
        legends = list(fig.legends) + [leg for ax in fig.axes if (leg := ax.get_legend()) is not None]
        for leg in legends:
            n_legends += 1
            lb = leg.get_window_extent(r)
            for ax in _data_axes(fig):
                assert not lb.overlaps(ax.get_window_extent(r)), (name, w, ax.get_title(), ax.get_xlabel())
    assert n_legends >= 5 * len({w for _, w in figs})


@pytest.mark.parametrize("which", ["lab_figs", "talker_figs"])
def test_axes_carry_units_and_manifold_coordinates_say_arbitrary(which, request):
    figs = request.getfixturevalue(which)
    for (name, w), (fig, _) in figs.items():
        axes = [ax for ax in _data_axes(fig) if len(ax.get_xticks()) and ax.name != "3d"]  # not lip-shape panels
        labels = [ax.get_xlabel() for ax in axes] + [ax.get_ylabel() for ax in axes]
        if fig._supylabel is not None:
            labels.append(fig._supylabel.get_text())
        if axes:  # stacked panels share one label; every figure with axes names both of them
            assert any(ax.get_xlabel() for ax in axes) and (any(ax.get_ylabel() for ax in axes)
                                                            or fig._supylabel is not None), (name, w)
        for label in filter(None, labels):
            flat = label.replace("\n", " ")
            assert flat in COUNTS or "(" in flat, (name, w, label)
            if re.search(r"\$Y_\d\$|shape S|velocity V", flat):
                assert "arbitrary units" in flat, (name, w, label)
        for ax in fig.axes:
            if ax.get_label() == "<colorbar>":
                assert ax.get_xlabel() or ax.get_ylabel(), (name, w)


def test_lip_shapes_have_a_scale_bar_in_the_corpus_unit(lab_figs, talker_figs):
    for figs in (lab_figs, talker_figs):
        for w in {w for _, w in figs}:
            for name in ("fig1a", "fig2c"):
                fig = figs[(name, w)][0]
                bars = [a for a in fig.findobj(lambda a: (a.get_gid() or "").endswith(":label")
                                               and ":scale" in (a.get_gid() or ""))]
                assert bars and all(re.fullmatch(r"[0-9.]+ mm", b.get_text()) for b in bars), (name, w)


def test_scree_kept_line_is_named_in_the_legend_not_written_over_it(lab_figs, lab_manifold):
    for w in WIDTHS_MM:
        fig = lab_figs[("scree", w)][0]
        r = fig.canvas.get_renderer()
        kept = [a for a in fig.findobj(lambda a: a.get_gid() == "scree:kept")]
        assert len(kept) == 1
        m = lab_manifold.shape_.n_components_
        (leg,) = fig.legends
        assert f"{m} shape components kept" in [t.get_text() for t in leg.get_texts()]
        assert not any("kept" in t.get_text() for ax in fig.axes for t in ax.texts)
        line_box = kept[0].get_window_extent(r)
        assert not line_box.overlaps(leg.get_window_extent(r))


def _fill(fig):
    """How much of their layout cells the 2-D panels fill (equal-aspect panels shrink inside them)."""
    fig.canvas.draw()
    flat = [ax for ax in fig.axes if ax.name == "rectilinear" and ax.axison and ax.get_label() != "<colorbar>"]
    used = sum(ax.get_position().width * ax.get_position().height for ax in flat)
    cells = sum(ax.get_position(original=True).width * ax.get_position(original=True).height for ax in flat)
    return used / cells


def test_fig2a_colour_bar_is_labelled_and_the_panels_fill_the_figure(lab_figs, lab_manifold):
    import copy

    for w in WIDTHS_MM:
        fig = lab_figs[("fig2a", w)][0]
        (cb,) = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
        label = cb.get_xlabel() or cb.get_ylabel()
        assert label.startswith("local density of the frames") and "Y" not in label.split("(")[0]
        ticks = [t.get_text() for t in cb.get_xticklabels() + cb.get_yticklabels() if t.get_text()]
        assert ticks and all(re.fullmatch(r"[0-9.]+", t) for t in ticks), ticks  # numbers, not dense/sparse
        assert _fill(fig) >= 0.7, (w, _fill(fig))
    # a corpus whose Y dims differ in extent (a real 4-sensor build): the figure's height follows the panels
    skewed = copy.copy(lab_manifold)
    Fy = np.array(lab_manifold.Fy_, copy=True)
    Fy[:, 1:3] *= (0.5, 0.25)
    skewed.Fy_ = Fy
    assert _fill(F.make_figure("fig2a", skewed, width=180 / 25.4)) >= 0.7


def test_fig2c_of_four_sensors_is_a_contour_clear_of_the_panel_edges(lab_figs):
    for w in WIDTHS_MM:
        fig = lab_figs[("fig2c", w)][0]
        shapes = fig.lipspace["shapes"]
        assert len(shapes) == 7
        for k, P in enumerate(shapes):
            (outline,) = [a for a in fig.findobj(lambda a, k=k: a.get_gid() == f"fig2c:shape{k}:contour")]
            ax = outline.axes
            xy = np.vstack([outline.get_xydata(), P[:, :2]])
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            span = max(np.ptp(xy[:, 0]), np.ptp(xy[:, 1]))
            margin = min(xy[:, 0].min() - x0, x1 - xy[:, 0].max(), xy[:, 1].min() - y0, y1 - xy[:, 1].max())
            assert margin >= 0.1 * span, (w, k, margin / span)


def _pdf_fonts(data: bytes):
    return re.findall(rb"/Subtype\s*/(Type3|TrueType|Type1|Type0|CIDFontType2)", data)


def test_pdf_and_svg_carry_their_fonts(lab_manifold, tmp_path):
    for name in ("fig1b", "fig2b", "fig3"):
        fig = F.make_figure(name, lab_manifold, width=85 / 25.4)
        pdf = F.save_figure(fig, tmp_path / f"{name}.pdf").read_bytes()
        fonts = _pdf_fonts(pdf)
        assert fonts and b"Type3" not in fonts and b"Type1" not in fonts, fonts  # no bitmap or base-14 fonts
        truetype = fonts.count(b"TrueType") + fonts.count(b"CIDFontType2")
        assert truetype >= 1 and pdf.count(b"/FontFile2") >= truetype, fonts  # each TrueType font embedded
        svg = F.save_figure(fig, tmp_path / f"{name}.svg").read_text()
        assert "<text" not in svg and ("<path" in svg or "<use" in svg)  # glyphs as outlines


def test_lipspace_figures_takes_a_journal_width(lab_manifold, tmp_path, capsys):
    from PIL import Image

    from app.cli import main

    path = tmp_path / "m.npz"
    lab_manifold.save(path)
    assert main(["figures", str(path), "-o", str(tmp_path / "one"), "--width", "85mm", "--only", "fig1b,scree",
                 "--dpi", "100", "-q"]) == 0
    assert "85 mm wide" in capsys.readouterr().out
    for name in ("fig1b", "scree"):
        with Image.open(tmp_path / "one" / f"{name}.png") as im:
            assert abs(im.size[0] - 85 / 25.4 * 100) <= 1
    assert main(["figures", str(path), "-o", str(tmp_path / "two"), "--width", "30mm", "-q"]) == 2
    assert "expected 40 to 260 mm" in capsys.readouterr().err


@pytest.mark.gui
@pytest.mark.parametrize("size", [(900, 300), (640, 480), (360, 600)])
def test_the_manifold_views_s_and_v_labels_stay_inside_the_view(qapp, lab_manifold, size):
    from app.models.state import AppState
    from app.scene.manifold import AXES_LABEL_PX
    from app.scene.projection import project, view_transform
    from app.views.manifold_view import ManifoldView

    v = ManifoldView(AppState(lab_manifold))
    v.resize(*size)
    v.show()
    for _ in range(5):
        qapp.processEvents()
    try:
        for name in ("default", "side", "top"):
            v.standard_view(name, render=False)
            M, (W, H) = view_transform(v.plotter)
            xy, _ = project(v.handles["axes"]["tips"], M, (W, H))
            inside = (xy[:, 0] >= AXES_LABEL_PX) & (xy[:, 0] <= W - AXES_LABEL_PX) & \
                (xy[:, 1] >= AXES_LABEL_PX) & (xy[:, 1] <= H - AXES_LABEL_PX)
            assert inside.all(), (size, name, xy.round(1), (W, H))
        from app.figures.view_vector import scene_figure

        fig = scene_figure(v.plotter)
        with _recorded_texts() as rec:
            fig.canvas.draw()
        cut = [s for s, lo, hi, _, Wc, Hc in rec if lo[0] < -0.5 or lo[1] < -0.5 or hi[0] > Wc + 0.5 or
               hi[1] > Hc + 0.5]
        assert {"S", "V"} <= {s for s, *_ in rec} and cut == []
    finally:
        v.close_view()
        v.deleteLater()
        qapp.processEvents()
