"""The window's figure exports go through the command line's functions, at a journal width, with the labels of the
screen in PNG, PDF and SVG alike (needs a display: Xvfb)."""
from __future__ import annotations

import re

import numpy as np
import pytest

pytestmark = pytest.mark.gui
pdfminer = pytest.importorskip("pdfminer", reason="pdfminer.six (the test extra) reads the PDFs' text layer")


@pytest.fixture(scope="module")
def ema(make_articulograph_manifold):
    return make_articulograph_manifold(n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, n_states=16)


def _pdf_text(path) -> tuple[str, float]:
    """The PDF's text (whitespace removed) and its page width in mm."""
    from pdfminer.high_level import extract_pages
    from pdfminer.layout import LTChar, LTContainer

    chars = []

    def walk(obj):
        for o in obj:
            if isinstance(o, LTChar):
                chars.append(o.get_text())
            elif isinstance(o, LTContainer):
                walk(o)

    (page,) = list(extract_pages(str(path)))
    walk(page)
    return "".join(chars).replace(" ", ""), page.width / 72 * 25.4


def _vtk_labels(plotter) -> set:
    """Every label the view's VTK scene shows (point labels and text actors), as on screen."""
    import pyvista as pv

    out = set()
    props = plotter.renderer.GetViewProps()
    props.InitTraversal()
    for _ in range(props.GetNumberOfItems()):
        a = props.GetNextProp()
        if not a.GetVisibility() or not a.IsA("vtkActor2D"):
            continue
        mapper = a.GetMapper()
        if mapper is not None and type(mapper).__name__ == "vtkLabelPlacementMapper":
            alg = mapper.GetInputAlgorithm()
            src = pv.wrap(alg.GetInputDataObject(0, 0))
            out |= {str(t) for t in src.point_data[alg.GetLabelArrayName()]}
    return {t for t in out if t.strip()}


def test_a_paper_figure_from_the_window_is_the_command_lines(qapp, qtbot, ema, main_window_factory, tmp_path):
    from app.cli import main
    from app.views.export_dialog import ExportOptions, write_figure

    path = ema.save(tmp_path / "m.npz")
    assert main(["figures", str(path), "-o", str(tmp_path / "cli"), "--width", "85mm", "--only", "fig1b",
                 "--format", "pdf", "-q"]) == 0
    with main_window_factory(qapp, ema, size=(1300, 850)) as w:
        write_figure(w, "fig1b", tmp_path / "win.pdf", ExportOptions(width_mm=85.0))
        qtbot.waitUntil(lambda: (tmp_path / "win.pdf").exists(), timeout=60000)
    cli, cli_mm = _pdf_text(tmp_path / "cli" / "fig1b.pdf")
    win, win_mm = _pdf_text(tmp_path / "win.pdf")
    assert win_mm == pytest.approx(85, abs=0.5) and cli_mm == pytest.approx(85, abs=0.5)
    assert win == cli  # the same function, the same width: the same words


@pytest.mark.parametrize("which", ["manifold", "lips"])
def test_a_view_is_written_at_a_journal_width_with_the_screens_labels(qapp, ema, main_window_factory, tmp_path,
                                                                      which):
    from PIL import Image

    with main_window_factory(qapp, ema, size=(1300, 850)) as w:
        w.state.select_frame(20)
        for _ in range(10):
            qapp.processEvents()
        plotter = w._view_plotter(which)
        w.lip_view.renderer.flush(sync=True)
        on_screen = _vtk_labels(plotter)
        for suffix in ("png", "pdf", "svg"):
            w.export_view(which, tmp_path / f"v.{suffix}", width=85 / 25.4, dpi=300)
    if which == "manifold":
        assert {"S", "V"} <= on_screen
    else:
        assert {"UL", "LL", "LC", "RC"} <= on_screen and any(t.endswith(" mm") for t in on_screen)
    text, mm = _pdf_text(tmp_path / "v.pdf")
    assert mm == pytest.approx(85, abs=0.5)
    for label in on_screen:  # every label of the screen, in the PDF
        assert label.replace(" ", "") in text, (label, text[:200])
    svg = (tmp_path / "v.svg").read_text()
    assert float(re.search(r'width="([0-9.]+)pt"', svg).group(1)) == pytest.approx(85 / 25.4 * 72, abs=0.5)
    with Image.open(tmp_path / "v.png") as im:  # the PNG: the same figure, rasterised at the DPI asked
        assert abs(im.size[0] - 85 / 25.4 * 300) <= 1.5 and im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
        img = np.asarray(im.convert("L"))
    assert (img < 128).mean() > 0.001  # drawn: not an empty page


def test_the_vector_view_has_no_grid_the_screen_lacks(qapp, ema, main_window_factory):
    """The translucent zero-velocity plane is one outline, not polygons whose overlapping edges print as a grid."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import PathPatch

    from app.figures.view_export import view_figure

    with main_window_factory(qapp, ema, size=(1300, 850)) as w:
        fig = view_figure(w._view_plotter("manifold"), width=85 / 25.4)
    ax = fig.axes[0]
    patches = [p for p in ax.patches if isinstance(p, PathPatch)]
    assert len(patches) == 1 and patches[0].get_edgecolor()[3] == 0  # the plane, filled once, no edges
    assert not any(isinstance(c, PolyCollection) and c.get_facecolors()[:, 3].max() < 1 for c in ax.collections)


def _vtk_legend_entries(plotter) -> list:
    """(text, symbol colour) of every entry of the view's visible legend boxes, as on screen."""
    from app.figures.view_vector import _entry

    out = []
    props = plotter.renderer.GetViewProps()
    props.InitTraversal()
    for _ in range(props.GetNumberOfItems()):
        a = props.GetNextProp()
        if a.GetVisibility() and type(a).__name__ == "vtkLegendBoxActor":
            out += [_entry(a, k)[:2] for k in range(a.GetNumberOfEntries())]
    return out


def test_every_legend_box_of_the_view_is_in_the_export_in_its_colours(qapp, ema, main_window_factory):
    """Both legend boxes (the points' and the glyphs'), every entry with its symbol's colour: below the view at a
    journal width (the figure grows, the view keeps its size), in their corners as on screen."""
    from matplotlib.colors import to_rgb

    from app.figures.view_export import view_figure

    with main_window_factory(qapp, ema, size=(1300, 850)) as w:
        w.state.select_frame(20)
        for _ in range(10):
            qapp.processEvents()
        plotter = w._view_plotter("manifold")
        entries = _vtk_legend_entries(plotter)
        journal = view_figure(plotter, width=85 / 25.4)
        screen = view_figure(plotter, width=None)
    texts = [t for t, _ in entries]
    assert "selected frame" in texts and "beyond the horizon" in texts  # the glyphs' box and the points' box
    (below,) = [leg for leg in journal.legends if leg.get_gid() == "view:legend"]
    drawn = {t.get_text(): to_rgb(h.get_color()) for t, h in zip(below.get_texts(), below.legend_handles)}
    assert list(drawn) == texts
    for text, colour in entries:
        assert np.allclose(drawn[text], colour, atol=1e-3), text
    view = journal.axes[0].get_window_extent()
    assert view.width / journal.dpi == pytest.approx(85 / 25.4, rel=1e-3)  # the view keeps the column's width
    assert below.get_window_extent().y1 <= view.y0 + 1  # the legend lies below the view, not over it
    from matplotlib.legend import Legend

    corner = [t.get_text() for leg in screen.axes[0].artists if isinstance(leg, Legend) for t in leg.get_texts()]
    assert sorted(corner) == sorted(texts) and not screen.legends
