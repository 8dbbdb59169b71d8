"""The comparison figure at one and two journal columns: every panel, its units, text of 7 pt or more, nothing cut."""
import numpy as np
import pytest

from app.figures.comparison import MIN_TEXT_PT, make_comparison
from app.figures.export import save_figure
from app.models.palette import SessionPalette
from engine.comparison.compare import ConditionComparison
from tests.app.figures.test_figures_journal import _recorded_texts


@pytest.fixture(scope="module")
def result(conditions):
    cc, m = conditions
    return ConditionComparison(n_permutations=199, n_bootstrap=50).fit(
        m, cc.fields["condition"], by="condition", contrasts=[("a", "b")], pairs=cc.fields["text"],
        paired_by="text")


def _texts(fig):
    """Every text the renderer draws: (string, size in pt, (x0, y0, x1, y1) from the top left, width, height)."""
    with _recorded_texts() as rec:
        fig.canvas.draw()
    return [(s, size, (*lo, *hi), w, h) for s, lo, hi, size, w, h in rec]


@pytest.mark.parametrize("mm", [85.0, 180.0])
def test_the_figure_at_journal_widths(conditions, result, mm, tmp_path):
    cc, m = conditions
    pal = SessionPalette.for_corpus(m.corpus_, fields={"condition": cc.fields["condition"]})
    fig = make_comparison(m, result, palette=pal, width=mm / 25.4)
    assert fig.get_figwidth() * 25.4 == pytest.approx(mm)
    texts = [t for t in _texts(fig) if t[0].strip()]
    assert min(size for _, size, _, _, _ in texts) >= MIN_TEXT_PT
    for s, _, (x0, y0, x1, y1), w, h in texts:
        assert x0 >= -1 and y0 >= -1 and x1 <= w + 1 and y1 <= h + 1, s
    labels = [s for s, _, _, _, _ in texts]
    for want in ("S: lip aperture (mm)", "V: opening velocity (mm/s)", "shift (mm per point, RMS)",
                 "shift (pooled s.d.)", "ratio b / a (log scale)", "log2 occupancy ratio (b / a)", "more a", "more b"):
        assert want in labels, want
    assert fig.lipspace["contrast"] == ("a", "b") and fig.lipspace["testable"]
    assert fig.lipspace["clusters_shown"][0] in ("b", "p")
    # the level names carry their palette colours
    ends = {t.get_text(): t.get_color() for t in fig.findobj(lambda t: hasattr(t, "get_text"))
            if t.get_text() in ("more a", "more b")}
    for lv in ("a", "b"):
        assert np.allclose(ends[f"more {lv}"], pal.colour("field:condition", lv))
    for suffix in ("pdf", "svg", "png"):
        assert save_figure(fig, tmp_path / f"diff.{suffix}").stat().st_size > 1000


def test_an_untestable_comparison_says_so_on_the_figure(conditions):
    cc, m = conditions
    levels = np.full(len(cc.fields["condition"]), "", dtype=object)
    levels[0], levels[2] = "x", "y"
    r = ConditionComparison(n_permutations=99, n_bootstrap=0).fit(m, levels, by="condition", contrasts=[("x", "y")])
    fig = make_comparison(m, r, width=85 / 25.4)
    text = " ".join(t[0] for t in _texts(fig)).replace("\n", " ")
    assert "descriptive only: one utterance per level" in text and "not tested" in text
    assert not fig.lipspace["testable"]
