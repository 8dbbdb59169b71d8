"""The session palette: one colour per level, the same for every reader, distinct for every reader."""
import numpy as np
import pytest

from app.models.palette import (
    CLASS_COLOURS,
    CLASS_LABELS,
    OKABE_ITO,
    SessionPalette,
    qualitative_colours,
    simulate_cvd,
    srgb_to_lab,
    to_hex,
)


def _min_distance(rgb) -> float:
    lab = srgb_to_lab(np.asarray(rgb, dtype=np.float64))
    d = np.linalg.norm(lab[:, None] - lab[None], axis=-1)
    return float(d[np.triu_indices(len(lab), 1)].min())


def test_sequence_starts_with_okabe_ito_and_has_no_greys():
    seq = qualitative_colours(64)
    assert [to_hex(c) for c in seq[:7]] == list(OKABE_ITO)
    lab = srgb_to_lab(seq.astype(np.float64))
    assert np.hypot(lab[:, 1], lab[:, 2]).min() > 25          # nothing a reader could take for grey
    assert lab[:, 0].max() < 90                               # nor for the white background
    assert np.array_equal(qualitative_colours(70)[64:], seq[:6])  # repeats after 64


@pytest.mark.parametrize("kind", ["deuteranopia", "protanopia"])
def test_first_colours_stay_apart_under_colour_vision_deficiency(kind):
    from matplotlib import colormaps

    twelve = qualitative_colours(12).astype(np.float64)
    assert _min_distance(twelve) > 20
    assert _min_distance(simulate_cvd(twelve, kind)) > 8
    # the baseline a plotting library gives: tab10's ten colours fall to 7.2 (deuteranopia), 4.6 (protanopia)
    tab10 = np.asarray(colormaps["tab10"].colors, dtype=np.float64)
    assert _min_distance(simulate_cvd(qualitative_colours(10).astype(np.float64), kind)) > \
        2 * _min_distance(simulate_cvd(tab10, kind))
    assert _min_distance(simulate_cvd(qualitative_colours(7).astype(np.float64), kind)) > 9


def test_simulation_keeps_greys_and_refuses_an_unknown_kind():
    grey = np.array([[0.5, 0.5, 0.5]])
    np.testing.assert_allclose(simulate_cvd(grey), grey, atol=0.01)
    with pytest.raises(ValueError, match="deuteranopia"):
        simulate_cvd(grey, "nope")


def test_levels_keep_their_colour_whoever_asks_first():
    p = SessionPalette(ranking={"phone": ["sil", "ax", "p", "b", "m"]})
    first = p.colours("phone", ["m", "b", "p"])
    assert p.colours("phone", ["p", "b", "m"]) == {k: first[k] for k in ["p", "b", "m"]}
    assert p.hex("phone", "sil") == OKABE_ITO[0] and p.hex("phone", "p") == OKABE_ITO[2]
    new = p.colour("phone", "zz")                             # never ranked: the next free colour, kept
    assert to_hex(new) == to_hex(qualitative_colours(6)[5]) and p.colour("phone", "zz") == new
    assert p.levels("phone")[-1] == "zz"


def test_tangent_classes_keep_their_design():
    p = SessionPalette()
    assert [p.hex("class", n) for n in CLASS_LABELS] == list(CLASS_COLOURS)
    L = srgb_to_lab(np.asarray([p.colour("class", n) for n in CLASS_LABELS]))[:, 0]
    assert L[0] < L[1] - 20 and L[2] < L[3] - 20              # accelerating darker than decelerating: greyscale tells


def test_for_corpus_ranks_by_frames_and_round_trips(small_corpus):
    p = SessionPalette.for_corpus(small_corpus, fields={"emotion": ["N", "A", "A"]})
    mid, labels, _u, a, b = small_corpus.phone_table()
    spans = {lab: 0 for lab in set(labels)}
    for lab, s, e in zip(labels, a, b):
        spans[lab] += max(e - s, 1)
    top = max(spans, key=lambda k: (spans[k], -ord(k[0])))
    assert p.levels("phone")[0] == top
    assert p.levels("field:emotion") == ["A", "N"]
    q = SessionPalette.from_dict(p.to_dict())
    for kind in ("phone", "speaker", "field:emotion"):
        assert q.levels(kind) == p.levels(kind)
        assert q.colours(kind, p.levels(kind)) == p.colours(kind, p.levels(kind))
    with pytest.raises(ValueError, match="list of strings"):
        SessionPalette.from_dict({"ranking": {"phone": [1, 2]}})
