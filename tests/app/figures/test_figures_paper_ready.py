"""Every figure, as a journal would print it, checked in the written PDF itself.

Four corpora of the kinds users bring: the synthetic talker (a lip mesh with phones), a 4-sensor
articulograph corpus of three speakers without phone labels, a 2-D midsagittal (MOCHA-style) corpus
with .lab alignments and a video corpus (FaceMesh lips), each made the way real ones are
(:mod:`engine.talker.example_corpora`). Every figure is rendered once per corpus at one and two journal
columns (85 and 180 mm) and written as PDF; the PDF's text layer (pdfminer.six) gives every glyph's box
and size and the fonts it carries, and the figure's own artists give what each axis shows:

* no text below 6 pt, no two words overlapping, all fonts embedded (no Type 3 bitmaps, no base-14);
* every axis labelled with its unit or "(arbitrary units)" (counts and fractions named as such), the
  label present in the PDF's text;
* each axis spans the data it shows: at most 1.5 times its range, unless the axis starts at zero
  on purpose (bars, percentages), and the data lie inside it.
"""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import app.figures as F

pdfminer = pytest.importorskip("pdfminer", reason="pdfminer.six (the test extra) reads the PDFs' text layer")

WIDTHS_MM = (85.0, 180.0)
#: smallest text (pt) a journal takes at final size
MIN_PT = 6.0
#: an axis may span at most this multiple of the range of the data it shows
MAX_SPAN = 1.5
#: axis labels that are counts or fractions (no unit)
COUNTS = ("number of components", "component", "% of variance", "% of frames",
          "residual variance (% of the total)")
#: lines that guide the eye without being data (they may run past the data, clipped by the axes)
GUIDES = ("zero-velocity-plane", "past-future", "scree:kept")


# ------------------------------------------------------------------------------------------ corpora
def _video_manifold(tmp):
    pytest.importorskip("mediapipe", reason="the [video] extra is not installed")
    pytest.importorskip("skimage", reason="scikit-image (the [video] extra) is not installed")
    from engine.manifold.model import Manifold
    from engine.talker.example_corpora import video_corpus

    return Manifold(n_states=24).fit(video_corpus(tmp / "video"))


def _midsagittal_manifold(tmp):
    from engine.manifold.model import Manifold
    from engine.talker.example_corpora import midsagittal_corpus

    return Manifold(n_states=24).fit(midsagittal_corpus(tmp / "mocha"))


def _labelled(m):
    """As ``lipspace figures`` takes a corpus without phone labels: its kinematic landmarks stand in."""
    if not any(u.phones for u in m.corpus_.utterances):
        from engine.recordings.kinematics import kinematic_if_unlabelled

        m.corpus_, _ = kinematic_if_unlabelled(m.corpus_)
    return m


@pytest.fixture(scope="module", params=["talker", "articulograph", "midsagittal", "video"])
def corpus_figures(request, tmp_path_factory, small_manifold, make_articulograph_manifold):
    """``{(figure, width_mm): (fig, pdf_info)}`` of one corpus: rendered once, written once."""
    tmp = tmp_path_factory.mktemp(request.param)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the generated recordings' import notes are not what this tests
        m = {"talker": lambda: small_manifold,
             "articulograph": lambda: make_articulograph_manifold(n_speakers=3, n_utterances=3,
                                                                  duration_s=(2.0, 2.5), seed=5, n_states=40),
             "midsagittal": lambda: _midsagittal_manifold(tmp),
             "video": lambda: _video_manifold(tmp)}[request.param]()
    has_phones = any(u.phones for u in m.corpus_.utterances)  # before landmarks stand in for them
    m = _labelled(m) if request.param != "talker" else m
    out = {}
    for w in WIDTHS_MM:
        for name in F.FIGURES:
            if name == "fig4" and not has_phones:
                continue  # 'lipspace figures' skips it: it needs /b/ /p/ /m/
            fig = F.make_figure(name, m, width=w / 25.4)
            path = F.save_figure(fig, tmp / f"{name}_{w:.0f}.pdf")
            out[(name, w)] = (fig, _pdf(path))
    return request.param, m, out


# ------------------------------------------------------------------------------------------ the PDF
def _pdf(path) -> dict:
    """What the PDF holds: its glyphs ``(text, box (x0, y0, x1, y1), size pt, direction in degrees, text
    object)`` (the text object: which BT ... ET block drew it, one per drawn text), its page size (pt), its
    fonts ``(subtype, embedded)`` and its text as lines (:func:`_lines`)."""
    from pdfminer.converter import PDFPageAggregator
    from pdfminer.layout import LTChar, LTContainer
    from pdfminer.pdfinterp import PDFPageInterpreter, PDFResourceManager
    from pdfminer.pdfpage import PDFPage

    class TextOnly(PDFPageAggregator):
        """The page's glyphs with their size and text object; paths and images are skipped."""

        text_object = 0

        def paint_path(self, *args, **kwargs):
            return None

        def render_image(self, *args, **kwargs):
            return None

        def render_char(self, matrix, font, fontsize, *args, **kwargs):
            adv = super().render_char(matrix, font, fontsize, *args, **kwargs)
            ch = self.cur_item._objs[-1]
            a, b, c, d, _, _ = matrix
            ch.lipspace = (float(fontsize * np.hypot(c, d)), float(np.degrees(np.arctan2(b, a))), self.text_object)
            return adv

    class Interpreter(PDFPageInterpreter):
        """Counts text objects; matplotlib writes markers and images as XObjects, text never: not read."""

        def do_BT(self):
            self.device.text_object += 1
            return super().do_BT()

        def do_Do(self, xobjid):
            return None

    chars = []

    def walk(obj):
        for o in obj:
            if isinstance(o, LTChar):
                chars.append((o.get_text(), (o.x0, o.y0, o.x1, o.y1), *o.lipspace))
            elif isinstance(o, LTContainer):
                walk(o)

    rsrc = PDFResourceManager()
    pages = []
    with open(path, "rb") as fh:
        for page in PDFPage.get_pages(fh):
            device = TextOnly(rsrc, laparams=None)
            Interpreter(rsrc, device).process_page(page)
            pages.append(device.get_result())
    assert len(pages) == 1
    walk(pages[0])
    chars = [c for c in chars if c[0].strip()]
    return {"chars": chars, "page": (pages[0].width, pages[0].height), "fonts": _fonts(path), "lines": _lines(chars)}


def _lines(chars) -> list:
    """The PDF's text as lines read in their own direction (glyphs of one size and direction on one baseline,
    in reading order), spaces left out: what a reader sees, whatever order the glyphs were written in."""
    groups = {}
    for text, box, size, angle, _ in chars:
        th = np.radians(angle)
        u, n = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
        centre = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2])
        key = (round(size, 1), round(angle), round(float(centre @ n) / (0.5 * size)))
        groups.setdefault(key, []).append((float(centre @ u), text))
    return ["".join(t for _, t in sorted(g)) for g in groups.values()]


def _collisions(chars) -> list:
    """Pairs of glyphs of different texts (text objects) whose boxes overlap, as ``(glyph, glyph, size)``."""
    if len(chars) < 2:
        return []
    box = np.array([c[1] for c in chars], float)
    size = np.array([c[2] for c in chars])
    ang = np.radians([c[3] for c in chars])
    obj = np.array([c[4] for c in chars])
    # glyph boxes run from the descender to the ascender: shrink them a little across the line, so that the
    # lines of a paragraph, or a label just above another, are not taken for colliding when they only touch
    horiz = np.abs(np.cos(ang)) >= np.abs(np.sin(ang))
    shrink = 0.12 * size
    box[horiz, 1] += shrink[horiz]
    box[horiz, 3] -= shrink[horiz]
    box[~horiz, 0] += shrink[~horiz]
    box[~horiz, 2] -= shrink[~horiz]
    w = np.minimum(box[:, None, 2], box[None, :, 2]) - np.maximum(box[:, None, 0], box[None, :, 0])
    h = np.minimum(box[:, None, 3], box[None, :, 3]) - np.maximum(box[:, None, 1], box[None, :, 1])
    area = (box[:, 2] - box[:, 0]) * (box[:, 3] - box[:, 1])
    inter = np.clip(w, 0, None) * np.clip(h, 0, None) / np.maximum(np.minimum(area[:, None], area[None, :]), 1e-9)
    bad = np.argwhere(np.triu(inter > 0.05, 1) & (obj[:, None] != obj[None, :]))
    return [(chars[i][0], chars[j][0], round(float(size[i]), 1)) for i, j in bad]


def _fonts(path) -> list:
    """``(subtype, embedded)`` of every font the PDF uses (embedded: a font file in its descriptor, or a
    CID font whose descendant carries one)."""
    from pdfminer.pdfdocument import PDFDocument
    from pdfminer.pdfparser import PDFParser
    from pdfminer.pdftypes import resolve1

    out = []
    with open(path, "rb") as fh:
        doc = PDFDocument(PDFParser(fh))
        for xref in doc.xrefs:
            for objid in xref.get_objids():
                try:
                    obj = resolve1(doc.getobj(objid))
                except Exception:  # noqa: BLE001 - free or compressed entries that hold no object
                    continue
                if not isinstance(obj, dict) or str(obj.get("Type")) != "/'Font'":
                    continue
                sub = str(obj.get("Subtype")).strip("/'")
                if sub == "Type0":
                    continue  # its descendant CID font is listed itself
                desc = resolve1(obj.get("FontDescriptor")) or {}
                embedded = any(k in desc for k in ("FontFile", "FontFile2", "FontFile3"))
                out.append((sub, embedded))
    return out


# ------------------------------------------------------------------------------------------ the checks
def test_no_text_below_six_points(corpus_figures):
    kind, _, figs = corpus_figures
    for (name, w), (_fig, pdf) in figs.items():
        assert len(pdf["chars"]) >= 20, (kind, name, w)
        small = sorted({(t, round(s, 2)) for t, _, s, _, _ in pdf["chars"] if s < MIN_PT - 0.01})
        assert small == [], (kind, name, w, small[:10])


def test_no_two_words_overlap(corpus_figures):
    kind, _, figs = corpus_figures
    for (name, w), (_fig, pdf) in figs.items():
        bad = _collisions(pdf["chars"])
        assert bad == [], (kind, name, w, bad[:8])


def test_every_text_lies_on_the_page(corpus_figures):
    kind, _, figs = corpus_figures
    for (name, w), (_fig, pdf) in figs.items():
        W, H = pdf["page"]
        assert W / 72 * 25.4 == pytest.approx(w, abs=0.5), (kind, name)
        assert H / 72 * 25.4 <= 240, (kind, name, w)  # a journal page's text block
        out = [t for t, b, *_ in pdf["chars"] if b[0] < -0.5 or b[1] < -0.5 or b[2] > W + 0.5 or b[3] > H + 0.5]
        assert out == [], (kind, name, w, "".join(out)[:60])


def test_all_fonts_are_embedded(corpus_figures):
    kind, _, figs = corpus_figures
    for (name, w), (_fig, pdf) in figs.items():
        fonts = pdf["fonts"]
        assert fonts, (kind, name, w)
        assert all(embedded for _, embedded in fonts), (kind, name, w, fonts)
        assert not any(sub in ("Type3", "Type1") for sub, _ in fonts), (kind, name, w, fonts)


def _data_axes(fig):
    """The figure's data panels: rectilinear, axes shown, with tick labels (lip-shape panels carry a scale
    bar instead, colour bars a label of their own)."""
    return [ax for ax in fig.axes if ax.name == "rectilinear" and ax.axison and ax.get_label() != "<colorbar>"
            and len(ax.get_xticks()) and len(ax.get_yticks())]


def test_every_axis_names_its_unit_and_the_pdf_shows_it(corpus_figures):
    kind, _, figs = corpus_figures
    for (name, w), (fig, pdf) in figs.items():
        text = "\n".join(pdf["lines"])
        labels = []
        for ax in _data_axes(fig):
            labels += [("x", ax.get_xlabel()), ("y", ax.get_ylabel())]
        sup = fig._supylabel.get_text() if fig._supylabel is not None else ""
        named = {axis for axis, lab in labels if lab} | ({"y"} if sup else set())
        if labels:
            assert named == {"x", "y"}, (kind, name, w, labels)
        for _, label in labels + [("y", sup)]:
            if not label:
                continue
            flat = " ".join(label.split())
            assert flat in COUNTS or re.search(r"\((?:[^()]*\b(?:mm|cm|m|s|Hz|arbitrary units)\b[^()]*)\)", flat), \
                (kind, name, w, label)
            if re.search(r"\bY\d\b|\bS:|\bV:", flat) and "mm" not in flat:
                assert "arbitrary units" in flat, (kind, name, w, label)
            # drawn as typed (line by line: a long label is wrapped)
            assert all(re.sub(r"\s+", "", line) in text for line in label.split("\n")), (kind, name, w, label)
        for ax in fig.axes:
            if ax.get_label() == "<colorbar>":
                assert ax.get_xlabel() or ax.get_ylabel(), (kind, name, w)


def _shown(ax):
    """The data an axes shows, (n, 2) in data coordinates: scatter points, data lines, bars."""
    from matplotlib.collections import PathCollection
    from matplotlib.patches import Rectangle

    pts = []
    for c in ax.collections:
        if isinstance(c, PathCollection) and c.get_transform() is not None and len(c.get_offsets()):
            if c.get_offset_transform() == ax.transData:
                pts.append(np.asarray(c.get_offsets(), float))
    for line in ax.get_lines():
        gid = line.get_gid() or ""
        if line.get_transform() != ax.transData or any(g in gid for g in GUIDES):
            continue
        xy = np.asarray(line.get_xydata(), float)
        pts.append(xy[np.isfinite(xy).all(axis=1)])
    for p in ax.patches:
        if isinstance(p, Rectangle) and p.get_transform() == ax.transData:
            x, y, wd, ht = p.get_x(), p.get_y(), p.get_width(), p.get_height()
            pts.append(np.array([[x, y], [x + wd, y + ht]]))
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def test_each_axis_spans_the_data_it_shows(corpus_figures):
    kind, _, figs = corpus_figures
    checked = 0
    for (name, w), (fig, _) in figs.items():
        for ax in _data_axes(fig):
            xy = _shown(ax)
            if len(xy) < 2:
                continue
            for j, (lim, scale) in enumerate(((ax.get_xlim(), ax.get_xscale()), (ax.get_ylim(), ax.get_yscale()))):
                lo, hi = sorted(lim)
                v = xy[:, j]
                if scale == "log":
                    v, lo, hi = np.log10(v[v > 0]), np.log10(lo), np.log10(hi)
                dlo, dhi = float(v.min()), float(v.max())
                tol = 1e-6 * max(abs(dlo), abs(dhi), 1.0)
                assert lo - tol <= dlo and dhi <= hi + tol, (kind, name, w, ax.get_title(), "xy"[j], (lo, hi),
                                                             (dlo, dhi))
                if scale != "log" and (lo == 0 or hi == 0) and (dlo >= 0 or dhi <= 0):
                    continue  # zero shown on purpose (bars, percentages)
                span, data = hi - lo, max(dhi - dlo, 1e-12)
                assert span <= MAX_SPAN * data, (kind, name, w, ax.get_title(), "xy"[j], (lo, hi), (dlo, dhi))
                checked += 1
    assert checked >= 10, (kind, checked)


# ------------------------------------------------------------------------------------------ layout
def test_legends_lie_outside_every_plotting_area(corpus_figures):
    kind, _, figs = corpus_figures
    n_legends = 0
    for (name, w), (fig, _) in figs.items():
        r = fig.canvas.get_renderer()
        legends = list(fig.legends) + [leg for ax in fig.axes if (leg := ax.get_legend()) is not None]
        for leg in legends:
            n_legends += 1
            lb = leg.get_window_extent(r)
            for ax in _data_axes(fig):
                assert not lb.overlaps(ax.get_window_extent(r)), (kind, name, w, ax.get_title())
    assert n_legends >= 5 * len(WIDTHS_MM)


def test_lip_shapes_have_a_scale_bar_in_the_corpus_unit(corpus_figures):
    kind, m, figs = corpus_figures
    for w in WIDTHS_MM:
        for name in ("fig1a", "fig2c"):
            fig = figs[(name, w)][0]
            bars = [a for a in fig.findobj(lambda a: (a.get_gid() or "").endswith(":label")
                                           and ":scale" in (a.get_gid() or ""))]
            assert bars and all(re.fullmatch(r"[0-9.]+ mm", b.get_text()) for b in bars), (kind, name, w)


def test_sensors_are_drawn_as_sensors_and_the_aperture_as_a_labelled_segment(corpus_figures):
    """Sensor data: a marker at every sensor, straight segments between lip sensors (nothing interpolated,
    nothing filled), the aperture segment labelled with the drawn shape's lip aperture in mm; a profile
    (2-D) shows which way the face looks. A measured surface stays a surface."""
    from matplotlib.collections import LineCollection, PatchCollection, PolyCollection

    kind, m, figs = corpus_figures
    c = m.corpus_
    for w in WIDTHS_MM:
        fig = figs[("fig2c", w)][0]
        shapes, apertures = fig.lipspace["shapes"], fig.lipspace["apertures"]
        for k, P in enumerate(shapes):
            gid = f"fig2c:shape{k}"
            ax = [a for a in fig.findobj(lambda a, g=gid: a.get_gid() == g)][0].axes
            label = [a for a in fig.findobj(lambda a, g=gid: a.get_gid() == f"{g}:aperture:label")]
            # the label states the shape's own lip aperture (upper- to lower-lip centroid distance, as
            # engine.recordings.kinematics.lip_aperture measures it)
            up, lo = c.role_points("upper_lip"), c.role_points("lower_lip")
            expect = float(np.linalg.norm(P[up].mean(axis=0) - P[lo].mean(axis=0)))
            assert apertures[k] == pytest.approx(expect, rel=1e-6), (kind, w, k)
            assert len(label) == 1 and label[0].get_text() == f"{expect:.1f} mm", (kind, w, k)
            if kind in ("articulograph", "midsagittal"):
                markers = np.concatenate([np.asarray(a.get_offsets()) for a in ax.collections
                                          if (a.get_gid() or "") in (gid, f"{gid}:other")])
                assert np.allclose(np.sort(markers, axis=0), np.sort(P[:, :2], axis=0)), (kind, w, k)
                # nothing filled, nothing curved: the only lines are straight segments between sensors
                assert not any(isinstance(a, (PolyCollection, PatchCollection)) for a in ax.collections)
                segs = [a for a in ax.collections if isinstance(a, LineCollection)]
                for s in segs:
                    for path in s.get_segments():
                        assert len(path) == 2 and any(np.allclose(path[0], q) for q in P[:, :2])
            else:
                assert any(isinstance(a, PolyCollection) for a in ax.collections)  # the measured surface
        if kind == "articulograph":  # UL-LC-LL-RC: four segments round the mouth, every sensor named
            segs = [a for a in fig.findobj(lambda a: a.get_gid() == "fig2c:shape0:segments")]
            assert len(segs) == 1 and len(segs[0].get_segments()) == 4
            names = {a.get_text() for a in fig.findobj(lambda a: a.get_gid() == "fig2c:shape0:label")}
            assert names == {"UL", "LL", "LC", "RC"}
        if kind == "midsagittal":  # a profile, facing right, the jaw sensor labelled too
            assert len([a for a in fig.findobj(lambda a: a.get_gid() == "fig2c:front")]) == 1
            names = {a.get_text() for a in fig.findobj(lambda a: a.get_gid() == "fig2c:shape0:label")}
            assert names == {"UL", "LL", "LI"}
    # fig 2c's shapes differ: the aperture grows with S
    assert np.all(np.diff(figs[("fig2c", 85.0)][0].lipspace["apertures"]) > 0), kind


def test_scree_kept_line_is_named_in_the_legend_not_written_over_it(corpus_figures):
    kind, m, figs = corpus_figures
    for w in WIDTHS_MM:
        fig = figs[("scree", w)][0]
        r = fig.canvas.get_renderer()
        kept = [a for a in fig.findobj(lambda a: a.get_gid() == "scree:kept")]
        n = m.shape_.n_components_
        if n > len(m.shape_.scree_[:30]):
            continue
        assert len(kept) == 1
        (leg,) = fig.legends
        assert f"{n} shape components kept" in [t.get_text() for t in leg.get_texts()]
        assert not any("kept" in t.get_text() for ax in fig.axes for t in ax.texts)
        assert not kept[0].get_window_extent(r).overlaps(leg.get_window_extent(r))


def _fill(fig):
    """How much of their layout cells the 2-D panels fill (equal-aspect panels shrink inside them)."""
    fig.canvas.draw()
    flat = [ax for ax in fig.axes if ax.name == "rectilinear" and ax.axison and ax.get_label() != "<colorbar>"]
    used = sum(ax.get_position().width * ax.get_position().height for ax in flat)
    cells = sum(ax.get_position(original=True).width * ax.get_position(original=True).height for ax in flat)
    return used / cells


def test_fig2a_colour_bar_is_labelled_and_the_panels_fill_the_figure(corpus_figures):
    import copy

    kind, m, figs = corpus_figures
    for w in WIDTHS_MM:
        fig = figs[("fig2a", w)][0]
        (cb,) = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
        label = cb.get_xlabel() or cb.get_ylabel()
        assert label.startswith("local density of the frames") and "Y" not in label.split("(")[0]
        ticks = [t.get_text() for t in cb.get_xticklabels() + cb.get_yticklabels() if t.get_text()]
        assert ticks and all(re.fullmatch(r"[0-9.]+", t) for t in ticks), ticks  # numbers, not dense/sparse
        assert _fill(fig) >= 0.7, (kind, w, _fill(fig))
        # S and V are labelled in every 2-D panel
        for lab in ("S", "V"):
            texts = [a for a in fig.findobj(lambda a, g=f"fig2a:{lab}:label": a.get_gid() == g)]
            assert len(texts) == 3 and all(t.get_text() == lab for t in texts), (kind, w, lab)
    if kind == "articulograph":  # Y dims of different extents: the figure's height follows the panels
        skewed = copy.copy(m)
        Fy = np.array(m.Fy_, copy=True)
        Fy[:, 1:3] *= (0.5, 0.25)
        skewed.Fy_ = Fy
        assert _fill(F.make_figure("fig2a", skewed, width=180 / 25.4)) >= 0.7


def test_fig2a_3d_view_draws_arrows_and_trajectory_above_the_points(corpus_figures):
    kind, _, figs = corpus_figures
    fig = figs[("fig2a", 180.0)][0]
    (ax3,) = [ax for ax in fig.axes if ax.name == "3d"]
    assert ax3.computed_zorder is False  # drawn in the order given, not buried by mplot3d's depth sort
    points = [c for c in ax3.collections if c.get_gid() == "fig2a:points:3d"][0]
    above = [a for a in ax3.get_children() if a.get_zorder() > points.get_zorder() and a.get_visible()]
    assert len(ax3.get_lines()) >= 1 and all(line.get_zorder() > points.get_zorder() for line in ax3.get_lines())
    assert {t.get_text() for t in ax3.texts} >= {"S", "V"} and len(above) >= 4
    # the axis labels and the tick labels of the 3-D view never meet (the PDF check covers every word)


def test_fig3_says_what_it_shows_and_whether_the_utterance_was_held_out(corpus_figures):
    kind, m, figs = corpus_figures
    for w in WIDTHS_MM:
        fig = figs[("fig3", w)][0]
        (ax,) = [a for a in fig.axes if a.get_xlabel()]
        title = " ".join(ax.get_title().split())
        assert "not held out" in title and fig.lipspace["held_out"] is False
        assert f"{fig.lipspace['rmse_x']:.3g} mm in X (lip shape)" in title
        assert "in this plane (arbitrary units)" in title
        if not any(u.phones for u in m.corpus_.utterances):  # landmarks: coloured by kind, named in the legend
            marks = [a for a in fig.findobj(lambda a: (a.get_gid() or "").startswith("fig3:landmark:"))]
            kinds = {a.get_gid().split(":", 2)[2] for a in marks}
            assert kinds and kinds <= {"open", "opening", "closing", "closed"}
            (leg,) = fig.legends
            assert kinds <= {t.get_text() for t in leg.get_texts()}
            assert not [t for t in ax.texts if t.get_text() in kinds]  # no text strewn over the lines


def test_svg_draws_its_text_as_outlines(corpus_figures, tmp_path):
    kind, _, figs = corpus_figures
    fig = figs[("fig1b", 85.0)][0]
    svg = F.save_figure(fig, tmp_path / "f.svg").read_text()
    assert "<text" not in svg and ("<path" in svg or "<use" in svg)


def test_lipspace_figures_takes_a_journal_width(corpus_figures, tmp_path, capsys):
    from PIL import Image

    from app.cli import main

    kind, m, _ = corpus_figures
    if kind != "articulograph":
        pytest.skip("the command line is checked on one corpus")
    path = tmp_path / "m.npz"
    m.save(path)
    assert main(["figures", str(path), "-o", str(tmp_path / "one"), "--width", "85mm", "--only", "fig1b,scree",
                 "--dpi", "100", "-q"]) == 0
    assert "85 mm wide" in capsys.readouterr().out
    for name in ("fig1b", "scree"):
        with Image.open(tmp_path / "one" / f"{name}.png") as im:
            assert abs(im.size[0] - 85 / 25.4 * 100) <= 1
    assert main(["figures", str(path), "-o", str(tmp_path / "two"), "--width", "30mm", "-q"]) == 2
    assert "expected 40 to 260 mm" in capsys.readouterr().err


def test_the_pdf_checks_catch_what_they_look_for(tmp_path):
    """The checks themselves: overlapping words, small text and an unlabelled axis are found."""
    from app.figures.style import new_figure

    fig = new_figure(3.35, 2.5)
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    ax.text(0.2, 0.5, "overlapping", fontsize=8)
    ax.text(0.25, 0.5, "words", fontsize=8)
    ax.text(0.2, 0.2, "tiny", fontsize=4)
    ax.text(0.6, 0.8, "a wrapped\nparagraph", fontsize=8)
    pdf = _pdf(F.save_figure(fig, tmp_path / "bad.pdf"))
    bad = _collisions(pdf["chars"])
    assert bad and all(size == 8.0 for *_, size in bad)
    assert {t for t, _, s, _, _ in pdf["chars"] if s < MIN_PT} == set("tiny")
    assert any("paragraph" in line for line in pdf["lines"]) and any("wrapped" in line for line in pdf["lines"])
    assert not any({"p", "w"} <= {a, b} for a, b, _ in bad)  # the paragraph's two lines do not collide
