"""What the comparison views draw: the diverging difference colours, small multiples, field colours, row selections."""
import numpy as np
import pytest

from app.models.comparison import (
    NEUTRAL_RGB,
    PUOR,
    UNKNOWN_LEVEL_RGB,
    difference_colours,
    diverging_rgb,
    field_colours,
    level_frames,
    row_selection,
)
from app.models.palette import SessionPalette, simulate_cvd, srgb_to_lab


def _hex(h):
    return np.array([int(h[i:i + 2], 16) / 255 for i in (1, 3, 5)])


def test_diverging_scale_ends_and_middle():
    rgb = diverging_rgb([-2.0, 0.0, 2.0, 9.0, np.nan], 2.0)
    np.testing.assert_allclose(rgb[0], _hex(PUOR[0]), atol=1e-6)
    np.testing.assert_allclose(rgb[1], _hex(PUOR[5]), atol=1e-6)
    np.testing.assert_allclose(rgb[2], _hex(PUOR[-1]), atol=1e-6)
    np.testing.assert_allclose(rgb[3], rgb[2])  # clipped
    np.testing.assert_allclose(rgb[4], rgb[1])  # NaN: the middle
    with pytest.raises(ValueError, match="limit=0"):
        diverging_rgb([1.0], 0)


def test_the_two_ends_stay_apart_for_colour_blind_readers():
    ends = np.stack([_hex(PUOR[1]), _hex(PUOR[-2])])
    for kind in ("deuteranopia", "protanopia", "tritanopia"):
        lab = srgb_to_lab(simulate_cvd(ends, kind))
        assert np.linalg.norm(lab[0] - lab[1]) > 40, kind


def test_difference_colours_fade_what_does_not_pass():
    lr = np.array([2.0, -1.0, 0.5, np.nan])
    q = np.array([0.01, 0.2, np.nan, np.nan])
    labels = np.array([0, 0, 1, 2, 3])
    c = difference_colours(lr, q, labels, level_a="neutral", level_b="angry")
    assert c.limit == 2.0 and c.tested
    assert c.significant.tolist() == [True, True, False, False, False]
    np.testing.assert_allclose(c.rgb[0], _hex(PUOR[-1]), atol=1e-6)  # significant: full colour
    faded = diverging_rgb([-1.0], 2.0)[0] * 0.35 + np.asarray(NEUTRAL_RGB) * 0.65
    np.testing.assert_allclose(c.rgb[2], faded, atol=1e-6)
    np.testing.assert_allclose(c.rgb[3], diverging_rgb([0.5], 2.0)[0], atol=1e-6)  # not tested: not faded
    assert c.tick_labels == ("more neutral", "more angry") and "faded: q >= 0.05" in c.title
    untested = difference_colours(lr, np.full(4, np.nan), labels)
    assert not untested.tested and untested.title.endswith("not tested")


def test_small_multiples_and_field_colours():
    values = np.array(["angry", "neutral", "", "angry"])
    uidx = np.repeat(np.arange(4), [2, 3, 1, 2])
    assert level_frames(values, uidx, "angry").tolist() == [0, 1, 6, 7]
    assert level_frames(values, uidx, "neutral").tolist() == [2, 3, 4]
    pal = SessionPalette(ranking={"field:emotion": ["neutral", "angry"]})
    rgb = field_colours(values, uidx, pal, "emotion")
    np.testing.assert_allclose(rgb[0], pal.colour("field:emotion", "angry"), atol=1e-6)
    np.testing.assert_allclose(rgb[2], pal.colour("field:emotion", "neutral"), atol=1e-6)
    np.testing.assert_allclose(rgb[5], UNKNOWN_LEVEL_RGB, atol=1e-6)


def test_each_row_selects_what_it_describes():
    base = {"level_a": "a", "level_b": "b"}
    s = row_selection({**base, "family": "cluster", "target": "p"})
    assert s.kind == "cluster" and s.phones == frozenset({"p"}) and s.levels == ("a", "b")
    assert row_selection({**base, "family": "state", "target": "17"}).state == 17
    assert row_selection({**base, "family": "dynamics", "target": "closing/decelerating"}).tangent_class == 3
    assert row_selection({**base, "family": "dynamics", "target": "all frames"}).kind == "dynamics"
    with pytest.raises(ValueError, match="row family 'x'"):
        row_selection({**base, "family": "x", "target": ""})
