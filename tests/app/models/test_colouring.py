"""app.models.colouring: what colour each frame gets, per mode; Qt-free."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.colour_maps import lightness
from app.models.colouring import (
    DENSITY_CMAP,
    FUTURE_CMAP,
    OUTSIDE_RGB,
    PAST_CMAP,
    UNREACHABLE_RGB,
    colormap_rgb,
    hemisphere_coloring,
    hop_table,
    point_colors,
)
from app.models.state import COLOR_MODES, AppState


def test_hop_table_is_one_band_per_whole_hop():
    t, lo, hi = hop_table(4, "future")
    assert (lo, hi) == (-0.5, 4.5) and t.shape == (5, 3)   # 0..4: each hop in the middle of its band
    assert lightness(t[0]) < 20                             # 0 hops (the state itself): the darkest
    assert np.all(np.diff(lightness(t)) > 0)                # far = lighter, same family
    assert t[-1][0] > t[-1][2]                              # warm
    tb, lo, hi = hop_table(3, "both")
    assert (lo, hi) == (-3.5, 3.5) and tb.shape == (7, 3)
    assert np.all(tb[:3, 2] > tb[:3, 0])                    # the past side is a cool family (blue > red)
    assert (tb[4:, 0] - tb[4:, 2]).mean() > (tb[:3, 0] - tb[:3, 2]).mean() + 0.3   # the future side warmer
    assert lightness(tb[:3]).min() > lightness(tb[3:]).max()  # and darker: apart in greyscale


def test_hemisphere_coloring_dims_outside_the_horizon_and_reads_out_the_fraction(app_manifold):
    m = app_manifold
    g, lab = m.states_, m.states_.labels_
    s = int(lab[250])
    c = hemisphere_coloring(m, s, "future", horizon_ms=2 * 1000 / m.corpus_.rate)  # 2 frame periods = 2 hops
    d = g.future(s)[lab]
    inside = d <= 2
    np.testing.assert_array_equal(np.isfinite(c.values), inside)
    np.testing.assert_array_equal(c.values[inside], d[inside])
    outside = np.isfinite(d) & ~inside
    assert outside.any()
    np.testing.assert_allclose(c.rgb[outside], np.broadcast_to(OUTSIDE_RGB, (outside.sum(), 3)), atol=1e-6)
    assert c.clim == (-0.5, 2.5) and list(c.ticks) == [0, 1, 2]   # whole hops only: no 0.67 or 1.33
    frac = 100 * inside.mean()
    assert f"{frac:.1f}% of frames" in c.readout and "2 hops at 60 frames/s" in c.readout
    # the colour of each frame is its hop's band
    t, lo, _ = hop_table(2, "future")
    np.testing.assert_allclose(c.rgb[inside], t[(c.values[inside] - lo).astype(int)], atol=1e-6)
    # no horizon: every reachable frame coloured, scale up to the deepest state
    full = hemisphere_coloring(m, s, "future", None)
    assert np.array_equal(np.isfinite(full.values), np.isfinite(d))
    assert full.clim[1] == np.nanmax(d[np.isfinite(d)]) + 0.5
    # both: past frames negative, future positive, each the nearer side
    both = hemisphere_coloring(m, s, "both", None)
    fut, past = g.future(s)[lab], g.past(s)[lab]
    neg = both.values < 0
    np.testing.assert_array_equal(-both.values[neg], past[neg])
    assert np.all(past[neg] < fut[neg])


def test_point_colors_every_mode(app_manifold):
    m = app_manifold
    s = AppState(m)
    s.set_utterance(m.corpus_.utterances[0].id)
    N = m.Fy_.shape[0]
    for mode in COLOR_MODES:
        c = point_colors(mode, m, s)
        assert c.rgb.shape == (N, 3) and c.rgb.dtype == np.float32
        assert np.all((c.rgb >= 0) & (c.rgb <= 1))
    cls = point_colors("class", m, s)
    k = m.tangent_.classes_
    for a in range(4):  # one colour per class
        assert len(np.unique(cls.rgb[k == a], axis=0)) == 1
    utt = point_colors("utterance", m, s)
    u = m.corpus_.utterances[0]
    assert np.all(utt.rgb[u.start:u.stop] == 0)  # the current utterance in black
    ph = point_colors("phone", m, s)
    f = int(np.flatnonzero(s.phones != "")[0])
    np.testing.assert_allclose(ph.rgb[f], s.palette.colour("phone", s.phones[f]), atol=1e-6)  # the session's colour
    spk = point_colors("speaker", m, s)
    assert [n for n, _ in spk.legend] == [sp or "(speaker not named)" for sp in m.corpus_.speakers]
    dens = point_colors("density", m, s)
    assert dens.values.shape == (N,) and np.isfinite(dens.values).all()
    with pytest.raises(ValueError):
        point_colors("bogus", m, s)


def test_phone_filter_colours_only_the_chosen_phones(app_manifold):
    s = AppState(app_manifold)
    all_c = point_colors("phone", app_manifold, s)
    assert len(all_c.legend) <= 17 and "more" in all_c.legend[-1][0]  # ~45 phones: no 45-row legend
    s.set_phone_filter(["p", "b", "m"])
    c = point_colors("phone", app_manifold, s)
    chosen = np.isin(s.phones, ["p", "b", "m"])
    np.testing.assert_allclose(c.rgb[chosen], all_c.rgb[chosen])
    np.testing.assert_allclose(c.rgb[~chosen], np.broadcast_to(OUTSIDE_RGB, ((~chosen).sum(), 3)), atol=1e-6)
    assert [n for n, _ in c.legend] == ["b", "m", "p", "other phones (dimmed)"]
    assert dict(c.legend)["p"] == all_c.legend[[n for n, _ in all_c.legend].index("p")][1] \
        if "p" in dict(all_c.legend) else True              # one colour per phone, filtered or not


def test_points_dim_while_ellipsoids_are_shown(app_manifold):
    s = AppState(app_manifold)
    s.set_color_mode("class")
    bright = point_colors("class", app_manifold, s).rgb
    s.set_visible_phones(["p"])
    dimmed = point_colors("class", app_manifold, s).rgb
    # towards the background grey: less saturated than before
    assert np.ptp(dimmed, axis=1).mean() < 0.5 * np.ptp(bright, axis=1).mean()


def test_maps_are_perceptually_ordered_and_the_hemispheres_part_in_greyscale():
    """No rainbow: every continuous map rises in lightness; future, past and beyond-horizon (and
    unreachable) frames keep apart in greyscale (CIELAB L*), not by hue alone."""
    t = np.linspace(0, 1, 64)
    for name in (DENSITY_CMAP, FUTURE_CMAP, PAST_CMAP):
        L = lightness(colormap_rgb(name, t))
        assert np.all(np.diff(L) > 0), name                   # jet's lightness goes up and down
    fut, past = lightness(colormap_rgb(FUTURE_CMAP, t)), lightness(colormap_rgb(PAST_CMAP, t))
    beyond, unreachable = float(lightness(OUTSIDE_RGB)), float(lightness(UNREACHABLE_RGB))
    assert fut.max() + 8 < past.min() and past.max() + 6 < unreachable < beyond - 6
    # the old maps (YlOrRd_r, PuBu_r, pale ends): a 6-hop future and past were both at L* ~ 85
    t6 = np.linspace(0, 1, 7)[-1]
    assert abs(float(lightness(colormap_rgb(FUTURE_CMAP, t6))) - float(lightness(colormap_rgb(PAST_CMAP, t6)))) > 20


def test_shipped_colour_tables_are_matplotlibs_entry_by_entry():
    """The colouring reads shipped tables (no matplotlib in app.models); they must be matplotlib's,
    and a colour looked up through them must be what matplotlib's colormap gives."""
    import json

    import numpy as np
    from matplotlib import colormaps

    from app.figures.colour_tables import OWN, TABLE_FILE, TABLES, colormap, colour_tables

    shipped = json.loads(TABLE_FILE.read_text())
    fresh = colour_tables()
    assert sorted(shipped) == sorted([*TABLES, *OWN])
    for name in shipped:
        np.testing.assert_allclose(shipped[name], fresh[name], atol=1e-7, err_msg=name)
    t = np.r_[0.0, 1.0, np.random.default_rng(0).random(500), 0.5 - 1e-9, 255 / 256]
    for name in (DENSITY_CMAP, FUTURE_CMAP, PAST_CMAP):  # a figure's colour map is the explorer's
        np.testing.assert_allclose(colormap_rgb(name, t), colormap(name)(t)[:, :3], atol=1e-7, err_msg=name)
    np.testing.assert_allclose(colormap_rgb("viridis", t), colormaps["viridis"](t)[:, :3], atol=1e-7)
