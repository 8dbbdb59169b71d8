"""Colour vision: every colour map the figures use has a lightness that only grows (or only falls), so it reads in
greyscale and for colour-blind readers; the categorical colours the figures draw stay apart under simulated
deuteranopia (and protanopia). The simulation and the uniform colour space are colorspacious's (CAM02-UCS,
Machado et al. 2009 at full severity), not this project's own code.

The window's maps are read by name from :mod:`app.models.colour_maps` (whatever they name): a figure showing a
density, a future or a past hemisphere colours it as the window does.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

colorspacious = pytest.importorskip("colorspacious", reason="colorspacious (the test extra) simulates colour vision")

#: colour maps known not to be perceptually uniform; a map of this list is a defect the explorer's change removes
RAINBOWS = ("jet", "rainbow", "gist_rainbow", "hsv", "nipy_spectral", "turbo", "gist_ncar")
#: the smallest CAM02-UCS distance between two categorical colours a reader tells apart on a small marker (a
#: just-noticeable difference is about 1-2; markers a few points wide need several times that)
MIN_DELTA = 10.0
CVD = ("deuteranomaly", "protanomaly")


def _window_maps():
    from app.models import colour_maps

    return [("DENSITY_CMAP", colour_maps.DENSITY_CMAP), ("FUTURE_CMAP", colour_maps.FUTURE_CMAP),
            ("PAST_CMAP", colour_maps.PAST_CMAP)]


def _maps():
    from app.figures.colours import MAGNITUDE_CMAP

    out = []
    for const, name in _window_maps() + [("MAGNITUDE_CMAP", MAGNITUDE_CMAP)]:
        out.append(pytest.param(const, name, id=const))
    return out


def _lightness(rgb) -> np.ndarray:
    """CAM02-UCS lightness J' of sRGB colours (n, 3) in [0, 1]."""
    return colorspacious.cspace_convert(np.clip(np.asarray(rgb, float)[:, :3], 0, 1), "sRGB1", "CAM02-UCS")[:, 0]


def _monotonic(J, tol=0.3) -> bool:
    d = np.diff(J)
    return bool(np.all(d >= -tol) or np.all(d <= tol))


@pytest.mark.parametrize("const, name", _maps())
def test_each_colour_map_lightness_is_monotonic(const, name):
    from app.figures.colours import continuous_cmap

    assert name not in RAINBOWS, (const, name)
    cmap = continuous_cmap(name)  # as the figures draw it
    J = _lightness(cmap(np.linspace(0, 1, 256)))
    assert _monotonic(J), (const, name, np.round(J[::32], 1))
    assert np.ptp(J) >= 15, (const, name, np.ptp(J))  # a lightness ramp a greyscale print keeps


def test_the_figures_maps_are_the_windows_tables():
    """Figure and window draw a meaning from the same entries (app.models.colour_tables.json)."""
    from app.figures.colours import density_cmap, future_cmap, past_cmap
    from app.models.colour_maps import DENSITY_CMAP, FUTURE_CMAP, PAST_CMAP, colormap_rgb

    t = np.linspace(0, 1, 97)
    for cmap, name in ((density_cmap(), DENSITY_CMAP), (future_cmap(), FUTURE_CMAP), (past_cmap(), PAST_CMAP)):
        np.testing.assert_allclose(cmap(t)[:, :3], colormap_rgb(name, t), atol=1e-6, err_msg=name)


def test_the_lightness_check_catches_a_rainbow():
    from matplotlib import colormaps

    assert not _monotonic(_lightness(colormaps["jet"](np.linspace(0, 1, 256))))
    assert _monotonic(_lightness(colormaps["viridis"](np.linspace(0, 1, 256))))


def _apart(colours, kind) -> float:
    """The smallest CAM02-UCS distance between two of ``colours`` as a reader with ``kind`` sees them."""
    rgb = np.clip(np.asarray(colours, float)[:, :3], 0, 1)
    seen = colorspacious.cspace_convert(rgb, {"name": "sRGB1+CVD", "cvd_type": kind, "severity": 100}, "sRGB1")
    J = colorspacious.cspace_convert(np.clip(seen, 0, 1), "sRGB1", "CAM02-UCS")
    return min(float(np.linalg.norm(J[i] - J[j])) for i, j in itertools.combinations(range(len(J)), 2))


@pytest.fixture(scope="module")
def drawn(small_manifold):
    """The categorical colours the figures draw: the tangent classes, X and Y, the bilabials, the landmarks."""
    from matplotlib.colors import to_rgba

    import app.figures as F
    from app.figures.colours import palette_for

    m = small_manifold
    w = 85 / 25.4
    classes = F.make_figure("classes", m, width=w)
    bars = [a for a in classes.findobj(lambda a: a.get_gid() == "classes:bars")]
    fig1b = F.make_figure("fig1b", m, width=w)
    lines = [a for g in ("fig1b:X", "fig1b:Y") for a in fig1b.findobj(lambda a, g=g: a.get_gid() == g)]
    fig4 = F.make_figure("fig4", m, width=w)
    phones = [a for p in ("b", "p", "m") for a in fig4.findobj(lambda a, p=p: a.get_gid() == f"fig4:points:{p}")]
    pal = palette_for(m)
    return {"classes": [b.get_facecolor() for b in bars],
            "X and Y": [to_rgba(line.get_color()) for line in lines],
            "bilabials": [c.get_facecolors()[0] for c in phones],
            "landmarks": [pal.colour("landmark", k) for k in ("open", "opening", "closing", "closed")]}


@pytest.mark.parametrize("kind", CVD)
def test_categorical_colours_stay_apart_for_colour_blind_readers(drawn, kind):
    assert len(drawn["classes"]) == 4 and len(drawn["X and Y"]) == 2 and len(drawn["bilabials"]) == 3
    for what, colours in drawn.items():
        assert _apart(colours, kind) >= MIN_DELTA, (what, kind, round(_apart(colours, kind), 1))


def test_the_categorical_colours_are_the_session_palettes(drawn, small_manifold):
    from app.models.palette import CLASS_LABELS, SessionPalette

    pal = SessionPalette.for_corpus(small_manifold.corpus_)
    np.testing.assert_allclose(np.asarray(drawn["classes"])[:, :3], [pal.colour("class", c) for c in CLASS_LABELS])
    np.testing.assert_allclose(np.asarray(drawn["bilabials"])[:, :3], [pal.colour("phone", p) for p in "bpm"],
                               atol=1e-6)


def test_the_distance_check_catches_colours_a_deuteranope_confuses():
    red, green = (0.8, 0.2, 0.2), (0.35, 0.55, 0.2)  # apart for most readers, one colour for a deuteranope
    J = colorspacious.cspace_convert(np.array([red, green]), "sRGB1", "CAM02-UCS")
    assert np.linalg.norm(J[0] - J[1]) > 2 * MIN_DELTA  # normal vision
    assert _apart([red, green], "deuteranomaly") < MIN_DELTA
