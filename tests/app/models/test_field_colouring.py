"""Colour and filter the manifold by per-utterance fields, and the difference view (Qt-free, on the state)."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.colour_maps import OUTSIDE_RGB, UNREACHABLE_RGB
from app.models.colouring import point_colors
from app.models.field_colouring import colour_fields, field_levels, frame_mask, utterance_field_values
from app.models.state import AppState


@pytest.fixture
def state(field_manifold):
    return AppState(field_manifold)


def _pure_points(state, values):
    """Drawn points whose frames all have one level; returns (points, level of each)."""
    cd, c = state.cloud, state.manifold.corpus_
    level = values[c.utterance_index]
    first = {}
    mixed = set()
    for f, g in enumerate(cd.group_of):
        lv = level[f]
        if first.setdefault(int(g), lv) != lv:
            mixed.add(int(g))
    pts = np.array(sorted(set(first) - mixed), np.int64)
    return pts, np.array([first[int(g)] for g in pts])


def test_the_colour_menu_offers_the_corpus_fields_and_levels_in_palette_order(state):
    assert colour_fields(state) == ["text", "condition", "repetition"]
    assert sorted(field_levels(state, "condition")) == ["a", "b", "c"]
    with pytest.raises(ValueError, match="no field 'emotion'; this corpus's utterances have speaker, text, condition"):
        state.set_color_field("emotion")


def test_colour_by_field_gives_every_point_its_level_colour(state):
    state.colour_by_field("condition")
    assert (state.color_mode, state.color_field) == ("field", "condition")
    c = point_colors(state.color_mode, state.manifold, state)
    values = utterance_field_values(state)["condition"]
    pts, lv = _pure_points(state, values)
    assert len(pts) > 20 and set(lv) == {"a", "b", "c"}
    for level in "abc":
        want = np.asarray(state.palette.colour("field:condition", level), np.float32)
        np.testing.assert_allclose(c.rgb[pts[lv == level]], np.broadcast_to(want, (np.sum(lv == level), 3)), atol=1e-6)
    assert [row[0] for row in c.legend] == field_levels(state, "condition")
    assert c.readout == "condition: 3 levels"
    # three distinct colours, none the grey of "no value"
    cols = {tuple(np.round(state.palette.colour("field:condition", lv), 4)) for lv in "abc"}
    assert len(cols) == 3 and tuple(np.round(UNREACHABLE_RGB, 4)) not in cols


def test_field_filter_dims_the_other_levels_in_any_colour_mode(state):
    values = utterance_field_values(state)["condition"]
    state.set_color_mode("density")
    state.set_field_levels("condition", ["a"])
    assert state.field_filter == frozenset({("condition", "a")})
    mask = frame_mask(state)
    np.testing.assert_array_equal(mask, values[state.manifold.corpus_.utterance_index] == "a")
    c = point_colors("density", state.manifold, state)
    pts, lv = _pure_points(state, values)
    assert np.all(c.rgb[pts[lv != "a"]] == np.asarray(OUTSIDE_RGB, np.float32))
    assert not np.any(np.all(c.rgb[pts[lv == "a"]] == np.asarray(OUTSIDE_RGB, np.float32), axis=1))
    assert f"shown: condition a ({100 * mask.mean():.1f}% of frames)" in c.readout
    state.set_field_levels("condition", [])
    assert frame_mask(state) is None
    with pytest.raises(ValueError, match="field 'condition' has no level 'z'; its levels are a, b, c"):
        state.set_field_filter({("condition", "z")})
    with pytest.raises(TypeError, match="\\(field, level\\) pairs"):
        state.set_field_filter({"condition"})


def test_the_difference_view_colours_each_point_by_its_states_enrichment(state, condition_comparison):
    c = point_colors("difference", state.manifold, state)
    assert "run a comparison" in c.readout and np.all(c.rgb == np.asarray(UNREACHABLE_RGB, np.float32))
    state.set_comparison(condition_comparison)
    c = point_colors("difference", state.manifold, state)
    r = condition_comparison.result
    a, b = condition_comparison.levels
    assert (a, b) == ("a", "b")
    np.testing.assert_allclose(c.values, r.enrichment_[0][state.cloud.state], atol=1e-5)
    assert c.clim[0] == -c.clim[1] and c.clim[1] > 0  # diverging: symmetric about no difference
    n_sig = int(np.sum(r.enrichment_q_[0] < r.alpha))
    assert c.readout == f"b against a: {n_sig} of {len(r.enrichment_q_[0])} states differ at q < 0.05"
    assert [row[0] for row in c.legend][:2] == ["more a (orange)", "more b (purple)"]
    state.set_comparison(condition_comparison.with_contrast(1))
    assert point_colors("difference", state.manifold, state).title == "log2 occupancy\nc / a"


def test_a_session_keeps_the_colour_field_and_the_filter(state, tmp_path):
    import json

    from app.files.session import SessionError, apply_session, load_session, save_session

    state.colour_by_field("condition")
    state.set_field_levels("condition", ["b", "c"])
    path = save_session(state, tmp_path / "s.lipspace")
    back = AppState(state.manifold)
    apply_session(back, load_session(path))
    assert (back.color_mode, back.color_field) == ("field", "condition")
    assert back.field_filter == {("condition", "b"), ("condition", "c")}
    d = json.loads(path.read_text())
    d["field_filter"] = [["condition"]]
    path.write_text(json.dumps(d))
    with pytest.raises(SessionError, match="field 'field_filter\\[0\\]' must be a \\[field, level\\] pair"):
        load_session(path)
