"""The paper's figure set (app.figures): artists, numbers and atomic export."""
from __future__ import annotations

import os
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection, PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

import app.figures as F
from app.figures.colours import GENERATED, ORIGINAL, UNREACHABLE, density_cmap, future_cmap
from app.figures.style import RASTERIZE_ABOVE


@pytest.fixture(scope="module")
def m(small_manifold):
    return small_manifold


@pytest.fixture(scope="module")
def figs(m):
    """Every figure rendered once (and drawn, so colours are resolved) for the module."""
    out = {}
    for name, fn in F.FIGURES.items():
        fig = fn(m)
        fig.canvas.draw()
        out[name] = fig
    return out


def by_gid(fig, gid, kind=None):
    found = [a for a in fig.findobj(lambda a: a.get_gid() == gid) if kind is None or isinstance(a, kind)]
    return found


def one(fig, gid, kind=None):
    found = by_gid(fig, gid, kind)
    assert len(found) == 1, f"expected one artist {gid!r}, found {len(found)}"
    return found[0]


# ------------------------------------------------------------------ all figures
def test_every_figure_is_an_agg_figure_with_content(figs):
    assert list(F.FIGURES) == ["fig1a", "fig1b", "fig2a", "fig2b", "fig2c", "fig3", "fig4", "scree", "classes"]
    assert set(F.DESCRIPTIONS) == set(F.FIGURES)
    for name, fig in figs.items():
        assert isinstance(fig, Figure), name
        assert isinstance(fig.canvas, FigureCanvasAgg), name
        assert fig.axes, name
        assert isinstance(fig.lipspace, dict), name


def test_figures_never_touch_pyplot():
    code = ("import sys, app.figures, app.cli.figures\n"
            "print('matplotlib.pyplot' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_make_figure_rejects_unknown_names(m):
    with pytest.raises(ValueError, match="fig2b"):
        F.make_figure("fig9", m)


def test_figures_need_a_fitted_manifold():
    from engine.manifold.model import Manifold

    with pytest.raises(ValueError, match="fitted"):
        F.make_fig1b(Manifold())


# ------------------------------------------------------------------ fig 1
def test_fig1a_shows_components_as_shapes_coloured_by_displacement(figs, m):
    fig = figs["fig1a"]
    shape = m.shape_
    # the largest displacement on the colour scale is that of the +-2 s.d. shapes
    comp = shape.components_[:2].reshape(2, -1, m.corpus_.dims)
    expect = max(2 * np.sqrt(shape.explained_variance_[k]) * np.linalg.norm(comp[k], axis=1).max() for k in range(2))
    assert fig.lipspace["max_displacement"] == pytest.approx(expect, rel=1e-4)
    for pc in (1, 2):
        mean = one(fig, f"fig1a:pc{pc}:+0")
        lo, hi = one(fig, f"fig1a:pc{pc}:-2"), one(fig, f"fig1a:pc{pc}:+2")
        # the mean shape is uniform grey; deformed shapes run from dark blue (still) to light yellow (moved)
        mc = mean.get_facecolors()[:, :3]
        assert np.allclose(mc[:, 0], mc[:, 1], atol=1e-6) and np.allclose(mc[:, 1], mc[:, 2], atol=1e-6)
        for coll in (lo, hi):
            fc = coll.get_facecolors()
            assert (fc[:, 2] > fc[:, 0]).any()           # some parts barely move (blue)
            assert len({tuple(np.round(c, 3)) for c in fc}) > 5
    # PC1 moves the surface more than PC2 (its colours reach further towards the light end)
    red1 = one(fig, "fig1a:pc1:+2").get_facecolors()[:, 0].max()
    red2 = one(fig, "fig1a:pc2:+2").get_facecolors()[:, 0].max()
    assert red1 > red2


def test_fig1b_residuals_in_the_palettes_X_and_Y_colours_non_increasing(figs, m):
    from app.models.palette import SessionPalette

    fig = figs["fig1b"]
    lx, ly = one(fig, "fig1b:X"), one(fig, "fig1b:Y")
    pal = SessionPalette.for_corpus(m.corpus_)
    assert to_rgba(lx.get_color()) == to_rgba(pal.colour("space", "X"))
    assert to_rgba(ly.get_color()) == to_rgba(pal.colour("space", "Y"))
    assert fig.axes[0].get_yscale() == "log"
    for line, ratio in ((lx, m.shape_.scree_), (ly, m.embedding_.explained_variance_ratio_)):
        y = np.asarray(line.get_ydata())
        assert y[0] == 100.0  # per cent of the total
        drawn = y[np.isfinite(y)]
        assert np.all(np.diff(drawn) <= 0)
        n = len(y) - 1
        expect = 100 * (1 - np.cumsum(ratio[:n]))
        expect[expect <= 100 * F.shape.NUMERICAL_FLOOR] = np.nan
        assert np.allclose(y[1:], expect, equal_nan=True)


def test_an_axis_margin_never_implies_a_negative_aperture():
    """A lip aperture from 0.1 to 15.5 mm starts at 0, not at -0.5 (the margin would carry it across zero); data
    on both sides of zero keep the margin on both sides."""
    from app.figures.style import data_limits

    ax = Figure().subplots()
    data_limits(ax, [0.1, 7.0, 15.5], [-200.0, 0.0, 180.0])
    assert ax.get_xlim() == (0.0, pytest.approx(15.5 + 0.04 * 15.4))
    assert ax.get_ylim() == (pytest.approx(-200 - 0.04 * 380), pytest.approx(180 + 0.04 * 380))
    data_limits(ax, [-3.0, -0.05], [10.0, 20.0])
    assert ax.get_xlim()[1] == 0.0 and ax.get_ylim()[0] == pytest.approx(9.6)


def test_residuals_leave_the_numerical_floor_undrawn():
    r = F.shape.residuals([0.5, 0.5, 0.0])
    assert r[0] == 1.0 and r[1] == 0.5 and np.isnan(r[2]) and np.isnan(r[3])
    assert np.isnan(F.shape.residuals([0.5, 0.5 - 1e-7])[2])  # 1e-7 of the total left: numerical zero, not data


def test_fig1b_says_where_a_curve_reaches_the_numerical_floor():
    from types import SimpleNamespace

    shape = SimpleNamespace(scree_=np.r_[0.6, 0.3, 0.1 - 1e-9, 1e-9, 0.0], n_components_=5, mean_=None)
    emb = SimpleNamespace(explained_variance_ratio_=np.r_[0.5, 0.3, 0.1, 0.05])
    fake = SimpleNamespace(Fy_=np.zeros((3, 3)), shape_=shape, embedding_=emb, corpus_=None)
    from app.models.palette import SessionPalette

    fig = F.make_fig1b(fake, palette=SessionPalette())
    x = one(fig, "fig1b:X").get_ydata()
    assert np.isfinite(x[:3]).all() and np.isnan(x[3:]).all()
    notes = [t.get_text() for t in fig.findobj(lambda a: a.get_gid() == "note")]
    assert len(notes) == 1 and "X: numerical zero" in notes[0] and "from 3 components" in notes[0]


# ------------------------------------------------------------------ fig 2
def test_fig2a_projections_density_arrows_plane_and_trajectory(figs, m):
    fig = figs["fig2a"]
    N = m.Fy_.shape[0]
    for tag in ("Y1Y2", "Y1Y3", "Y2Y3"):
        sc = one(fig, f"fig2a:points:{tag}", PathCollection)
        assert sc.get_offsets().shape == (N, 2)
        d = np.asarray(sc.get_array())
        assert d.min() == 0 and d.max() == 1 and np.all(np.diff(d) >= 0)   # densest drawn last
        # the densest point's colour is the dense end of the window's density map
        assert np.allclose(sc.get_facecolors()[-1], density_cmap()(1.0))
    assert len(by_gid(fig, "fig2a:points:3d")) == 1
    assert len(by_gid(fig, "zero-velocity-plane")) >= 2
    assert len(by_gid(fig, "fig2a:S")) == 3 and len(by_gid(fig, "fig2a:V")) == 3
    assert len(by_gid(fig, "fig2a:s_i")) == 3 * len(fig.lipspace["local_frames"]) > 0
    traj = fig.lipspace["trajectory_frames"]
    q = by_gid(fig, "fig2a:trajectory")
    assert len(q) == 3
    assert np.allclose(q[0].get_xydata(), m.Fy_[traj][:, :2])
    assert len(by_gid(fig, "fig2a:trajectory:direction")) >= 3 * 3  # its direction, in every panel
    # the trajectory stays inside one utterance
    assert len(set(m.corpus_.utterance_index[traj])) == 1


def test_fig2a_arrow_directions_are_the_projected_S_and_V(figs, m):
    fig = figs["fig2a"]
    t = m.tangent_
    for ann, vec in ((by_gid(fig, "fig2a:S")[0], t.S_), (by_gid(fig, "fig2a:V")[0], t.plane_normal_)):
        d = np.subtract(ann.xy, ann.xyann)                        # first panel: Y1-Y2
        cos = d @ vec[:2] / (np.linalg.norm(d) * np.linalg.norm(vec[:2]))
        assert cos == pytest.approx(1.0, abs=1e-6)


def test_fig2a_example_trajectory_comes_from_the_requested_utterance(m):
    u = m.corpus_.utterances[3]
    seg = F.manifold.example_segment(m, u.id, n_frames=30)
    assert len(seg) == min(30, u.n_frames) and u.start <= seg[0] and seg[-1] < u.stop
    assert np.all(np.diff(seg) == 1)
    with pytest.raises(ValueError, match="no utterance"):
        F.manifold.example_segment(m, "nope")
    with pytest.raises(ValueError, match="out of range"):
        F.manifold.example_segment(m, 10_000)


def test_fig2b_seed_states_and_hop_colours(figs, m):
    fig = figs["fig2b"]
    st = m.states_
    seeds = fig.lipspace["seeds"]
    assert list(seeds) == ["opening", "zero velocity", "closing"]
    msv = F.hops.state_signed_velocity(m)
    assert msv[seeds["opening"]] > msv[seeds["zero velocity"]] > msv[seeds["closing"]]
    assert msv[seeds["opening"]] > 0 > msv[seeds["closing"]]
    assert abs(msv[seeds["zero velocity"]]) < min(msv[seeds["opening"]], -msv[seeds["closing"]])
    labels = np.asarray(st.labels_)
    for name, s in seeds.items():
        sc = one(fig, f"fig2b:distance:{name}", PathCollection)
        frames = sc.lipspace_frames
        d = np.asarray(sc.get_array())
        assert np.array_equal(d, st.future(s)[labels[frames]])
        # the seed's own frames are at distance 0 and take the "near" end of the window's future map
        own = labels[frames] == s
        assert own.any() and np.all(d[own] == 0)
        assert np.allclose(sc.get_facecolors()[own], future_cmap()(0.0))
        un = one(fig, f"fig2b:unreachable:{name}", PathCollection)
        assert len(un.get_offsets()) + len(frames) == len(labels)
        if len(un.get_offsets()):  # open grey circles: told apart from the map by their shape, in greyscale too
            assert np.allclose(un.get_edgecolors()[0], to_rgba(UNREACHABLE))
            assert len(un.get_facecolors()) == 0 or un.get_facecolors()[0][3] == 0
        assert 1 <= fig.lipspace["info"][name]["n_future_directions"] <= 2


def test_fig2b_accepts_explicit_states_and_checks_range(m):
    fig = F.make_fig2b(m, states=(0, 1, 2))
    assert fig.lipspace["seeds"] == {"opening": 0, "zero velocity": 1, "closing": 2}
    K = m.states_.centroids_.shape[0]
    with pytest.raises(ValueError, match=f"{K} states"):
        F.make_fig2b(m, states={"x": K})


def test_fig2c_shapes_ordered_by_S_open_up(figs, m):
    fig = figs["fig2c"]
    sv = fig.lipspace["s_values"]
    assert len(sv) == 7 and np.all(np.diff(sv) > 0)
    assert sum(fig.lipspace["frames_per_shape"]) > 0.9 * m.Fy_.shape[0]
    # S orders shapes by opening: the vertical extent of the mouth grows from first to last
    heights = []
    for k in (0, 6):
        coll = one(fig, f"fig2c:shape{k}")
        pts = np.concatenate([p.vertices for p in coll.get_paths()]) if isinstance(coll, PolyCollection) \
            else coll.get_offsets()
        heights.append(np.ptp(pts[:, 1]))
    assert heights[1] > heights[0]


# ------------------------------------------------------------------ fig 3
def test_fig3_original_black_generated_red_circles_at_mid_points(figs, m):
    fig = figs["fig3"]
    c = m.corpus_
    u = c.utterance(fig.lipspace["utterance"])
    lo, lg = one(fig, "fig3:original"), one(fig, "fig3:generated")
    assert to_rgba(lo.get_color()) == to_rgba(ORIGINAL) and to_rgba(lg.get_color()) == to_rgba(GENERATED)
    assert ORIGINAL == (0.0, 0.0, 0.0) and GENERATED == (1.0, 0.0, 0.0)  # the window's: black and red
    assert np.allclose(lo.get_xydata(), m.Fy_[u.start:u.stop, :2])
    assert len(lg.get_xydata()) == u.n_frames
    mk = one(fig, "fig3:midpoints")
    assert mk.get_marker() == "o"
    tf = fig.lipspace["target_frames"]
    mids = sorted({c.time_to_frame(u, p.mid) - u.start for p in u.phones})
    assert list(tf) == mids                      # one circle per distinct phone mid-point frame
    assert np.allclose(mk.get_xydata(), m.Fy_[u.start + tf, :2])
    assert 0 < fig.lipspace["rmse_x"] < np.sqrt(np.sum(np.var(m.Fx_, axis=0))) * 2


def test_fig3_uses_the_requested_utterance(m):
    uid = m.corpus_.utterances[1].id
    fig = F.make_fig3(m, utterance=uid, label_phones=False)
    assert fig.lipspace["utterance"] == uid
    with pytest.raises(ValueError, match="no utterance"):
        F.make_fig3(m, utterance="nope")


# ------------------------------------------------------------------ fig 4
def _phone_colours(m, phones):
    """The session palette's colours of ``phones`` for the manifold's corpus (the window's)."""
    from app.models.palette import SessionPalette

    pal = SessionPalette.for_corpus(m.corpus_)
    return [pal.colour("phone", p) for p in phones]


def test_fig4_takes_the_palette_it_is_given(m):
    from app.models.palette import SessionPalette

    pal = SessionPalette(ranking={"phone": ["m", "p", "b"]})
    fig = F.make_fig4(m, palette=pal)
    _check_clusters(fig, ("b", "p", "m"), [pal.colour("phone", p) for p in ("b", "p", "m")])


def _mahalanobis(pts, mean, cov):
    d = np.asarray(pts) - mean
    return np.sqrt(np.einsum("ij,ij->i", d @ np.linalg.inv(cov), d))


def _check_clusters(fig, phones, colours):
    for phone, col in zip(phones, colours):
        sc = one(fig, f"fig4:points:{phone}", PathCollection)
        pts = np.asarray(sc.get_offsets())
        assert np.allclose(sc.get_facecolors(), to_rgba(col))
        mean = one(fig, f"fig4:mean:{phone}")
        assert mean.get_marker() == "s"
        assert np.allclose(mean.get_xydata()[0], pts.mean(axis=0))
        ell = one(fig, f"fig4:ellipse:{phone}").get_xydata()
        assert np.allclose(ell[0], ell[-1])                           # closed outline
        # every outline point is 2 s.d. (Mahalanobis) from the members' mean, sample covariance
        r = _mahalanobis(ell, pts.mean(axis=0), np.cov(pts, rowvar=False))
        assert np.allclose(r, 2.0, atol=1e-6)


def test_fig4_bilabial_clusters_colours_ellipses_and_plane(figs, m):
    fig = figs["fig4"]
    assert fig.lipspace["missing"] == []
    _check_clusters(fig, ("b", "p", "m"), _phone_colours(m, ("b", "p", "m")))
    mids, labels = m.corpus_.phone_table()[:2]
    for p in ("b", "p", "m"):
        assert fig.lipspace["found"][p]["count"] == int(np.sum(labels == p))
    zl = one(fig, "fig4:zero-velocity")
    assert zl.get_linestyle() == ":" and np.allclose(zl.get_ydata(), 0)
    # in the (S, V) plane a point's height is its signed velocity: the opening fractions agree
    for p in ("b", "p", "m"):
        pts = one(fig, f"fig4:points:{p}").get_offsets()
        assert fig.lipspace["found"][p]["opening_fraction"] == pytest.approx(np.mean(pts[:, 1] > 0))


def test_fig4_in_Y_axes_uses_the_cluster_ellipses(m):
    fig = F.make_fig4(m, axes=(0, 1))
    fig.canvas.draw()
    _check_clusters(fig, ("b", "p", "m"), _phone_colours(m, ("b", "p", "m")))
    pts = one(fig, "fig4:points:b").get_offsets()
    mids, labels = m.corpus_.phone_table()[:2]
    assert np.allclose(np.sort(pts[:, 0]), np.sort(m.Fy_[mids[labels == "b"], 0]))


def test_fig4_matches_arpabet_labels_and_notes_missing_phones(m):
    import copy
    from dataclasses import replace

    from engine.recordings.corpus import Corpus

    c = m.corpus_
    upper = [replace(u, phones=tuple(replace(p, label=p.label.upper()) for p in u.phones)) for u in c.utterances]
    m2 = copy.copy(m)
    m2.corpus_ = Corpus(c.frames, c.rate, upper, dims=c.dims, faces=c.faces, name="arpabet")
    fig = F.make_fig4(m2, phones=("b", "p", "zz"))
    fig.canvas.draw()
    assert fig.lipspace["found"]["b"]["label"] == "B"
    assert fig.lipspace["found"]["b"]["count"] == int(np.sum(c.phone_table()[1] == "b"))
    assert fig.lipspace["missing"] == ["zz"]
    assert "/zz/" in one(fig, "fig4:note").get_text()
    assert len(by_gid(fig, "fig4:points:zz")) == 0
    _check_clusters(fig, ("b", "p"), _phone_colours(m2, ("B", "P")))


# ------------------------------------------------------------------ extras
def test_classes_bars_are_the_class_proportions(figs, m):
    fig = figs["classes"]
    bars = by_gid(fig, "classes:bars")
    props = m.tangent_.class_proportions()
    assert len(bars) == 4
    assert np.allclose([b.get_height() for b in bars], [100 * props[n] for n in m.tangent_.CLASS_NAMES])
    assert fig.lipspace["true_agreement"] is None or 0.5 < fig.lipspace["true_agreement"] <= 1


def test_scree_bars_are_the_explained_variance(figs, m):
    fig = figs["scree"]
    bx = by_gid(fig, "scree:X")
    assert np.allclose([b.get_height() for b in bx], 100 * m.shape_.scree_[:len(bx)])


# ------------------------------------------------------------------ export
def test_export_writes_valid_png_svg_pdf(m, tmp_path):
    for suf in ("png", "svg", "pdf"):
        out = F.export_figure("fig1b", m, tmp_path / f"f.{suf}", dpi=60)
        data = out.read_bytes()
        if suf == "png":
            assert data[:8] == b"\x89PNG\r\n\x1a\n"
        elif suf == "svg":
            assert ET.fromstring(data).tag.endswith("svg")
        else:
            assert data.startswith(b"%PDF")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png", "f.svg"]   # no temp files
    # no dates or random ids: the same figure gives the same bytes
    again = F.export_figure("fig1b", m, tmp_path / "g.svg", dpi=60)
    assert again.read_bytes() == (tmp_path / "f.svg").read_bytes()


def test_export_rejects_unknown_formats_without_writing(m, tmp_path):
    with pytest.raises(ValueError, match=r"\.png, \.svg, \.pdf"):
        F.export_figure("fig1b", m, tmp_path / "f.jpg")
    with pytest.raises(ValueError, match="no figure"):
        F.export_figure("nope", m, tmp_path / "f.png")
    assert list(tmp_path.iterdir()) == []


class _Boom(Artist):
    def draw(self, renderer):
        raise RuntimeError("renderer failed half-way")


def test_failing_save_leaves_existing_file_untouched(tmp_path):
    from app.figures.style import new_figure

    fig = new_figure(2, 2)
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    target = tmp_path / "f.svg"
    target.write_bytes(b"previous figure")
    fig.add_artist(_Boom())
    with pytest.raises(RuntimeError, match="half-way"):
        F.save_figure(fig, target)
    assert target.read_bytes() == b"previous figure"
    assert [p.name for p in tmp_path.iterdir()] == ["f.svg"]


def test_vector_exports_rasterise_dense_scatters(m, tmp_path):
    # large scatters are embedded as images inside SVG, keeping files small
    fig = F.make_fig2b(m)
    out = F.save_figure(fig, tmp_path / "f.svg", dpi=50)
    tags = {el.tag.rsplit("}", 1)[-1] for el in ET.fromstring(out.read_bytes()).iter()}
    assert m.Fy_.shape[0] > RASTERIZE_ABOVE
    assert "image" in tags                        # the scatters, as embedded images
    assert "text" in tags or "use" in tags or "path" in tags   # axes and labels stay vectors


# ------------------------------------------------------------------ 3-D views (pyvista, off screen)
_PROBE = ("import pyvista as pv\n"
          "p = pv.Plotter(off_screen=True, window_size=(64, 48))\n"
          "p.add_mesh(pv.Sphere())\n"
          "img = p.screenshot(return_img=True)\n"
          "assert img.shape[:2] == (48, 64)\n")


@pytest.fixture(scope="module")
def can_render():
    """Skip unless VTK can render off screen here (an X display, Xvfb, EGL or OSMesa)."""
    try:
        r = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.skip("off-screen VTK rendering timed out; run under a display (e.g. xvfb-run -a pytest)")
    if r.returncode != 0:
        why = "no DISPLAY" if not os.environ.get("DISPLAY") else f"DISPLAY={os.environ['DISPLAY']}"
        pytest.skip(f"VTK cannot render off screen ({why}); run under Xvfb (xvfb-run -a pytest) — "
                    f"{r.stderr.strip().splitlines()[-1] if r.stderr.strip() else 'renderer failed'}")


@pytest.fixture
def plotter(can_render):
    import pyvista as pv

    p = pv.Plotter(off_screen=True, window_size=(160, 120))
    p.add_mesh(pv.Sphere(), color="red")
    p.add_points(pv.Sphere().points[:30], color="black", point_size=4)
    p.add_text("lips", font_size=8)
    yield p
    p.close()


def _png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


@pytest.mark.gui
def test_png_export_is_atomic_and_scaled(plotter, tmp_path):
    out = F.save_plotter_image(plotter, tmp_path / "view.png")
    assert _png_size(out) == (160, 120)
    out2 = F.save_plotter_image(plotter, tmp_path / "view2.png", scale=2)
    assert _png_size(out2) == (320, 240)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["view.png", "view2.png"]


@pytest.mark.gui
def test_png_export_rejects_other_suffixes_and_closed_plotters(plotter, tmp_path):
    with pytest.raises(ValueError, match=r"\.png"):
        F.save_plotter_image(plotter, tmp_path / "view.jpg")
    with pytest.raises(ValueError, match="positive integer"):
        F.save_plotter_image(plotter, tmp_path / "view.png", scale=0)
    plotter.close()
    with pytest.raises(ValueError, match="closed"):
        F.save_plotter_image(plotter, tmp_path / "view.png")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gui
@pytest.mark.parametrize("suffix", [".svg", ".PDF", ".eps"])
def test_vector_export_writes_valid_files(plotter, tmp_path, suffix):
    out = F.save_plotter_vector(plotter, tmp_path / f"view{suffix}")  # the suffix in any case
    data = out.read_bytes()
    if suffix == ".svg":
        root = ET.fromstring(data)
        assert root.tag.endswith("svg")
    elif suffix == ".PDF":
        assert data.startswith(b"%PDF") and b"/Subtype /Image" not in data   # no embedded raster
    else:
        assert data.startswith(b"%!PS") and b"colorimage" not in data and b" image\n" not in data
    assert [p.name for p in tmp_path.iterdir()] == [f"view{suffix}"]


@pytest.mark.gui
def test_vector_export_of_a_3d_view_holds_paths_not_an_image(plotter, tmp_path):
    from app.figures.view_vector import scene_figure

    fig = scene_figure(plotter)
    assert fig.lipspace["n_points"] == 30 and fig.lipspace["n_polygons"] > 100   # the 30 dots, the sphere
    root = ET.fromstring(F.save_plotter_vector(plotter, tmp_path / "view.svg").read_bytes())
    tags = [el.tag.rsplit("}", 1)[-1] for el in root.iter()]
    assert "image" not in tags                          # gl2ps embedded the geometry as one PNG
    assert tags.count("path") > 100                     # sphere facets and dots as vector paths
    # the sphere's facets keep their colour: red, shaded (not a grey or white fill)
    fills = [el.get("style", "") for el in root.iter() if el.tag.endswith("path")]
    assert sum("fill: #" in f and f.split("fill: #")[1][:2] > "80" and f.split("fill: #")[1][2:6] < "3030"
               for f in fills) > 50


@pytest.mark.gui
def test_vector_export_rejects_raster_suffix(plotter, tmp_path):
    with pytest.raises(ValueError, match=r"\.svg"):
        F.save_plotter_vector(plotter, tmp_path / "view.png")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gui
def test_png_export_at_a_dpi_keeps_the_size_and_records_it(plotter, tmp_path):
    from PIL import Image

    out = F.save_plotter_image(plotter, tmp_path / "view.PNG", dpi=300)
    with Image.open(out) as im:
        assert im.size == (round(160 * 300 / 96), round(120 * 300 / 96))
        assert im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
    with pytest.raises(ValueError, match="outside 30..1200"):
        F.save_plotter_image(plotter, tmp_path / "x.png", dpi=5000)


def test_suffix_from_the_chosen_filter():
    from pathlib import Path

    from app.figures.export import suffix_from_filter

    assert suffix_from_filter("/d/fig", "SVG (*.svg)") == Path("/d/fig.svg")
    assert suffix_from_filter("/d/fig.PDF", "PNG image (*.png)") == Path("/d/fig.PDF")   # typed suffix wins
    assert suffix_from_filter("/d/fig.v2", "PDF (*.pdf)") == Path("/d/fig.v2.pdf")


def test_export_dialogs_allow_exactly_the_suffixes_their_writers_take():
    """Each File > Export dialog takes the suffixes it accepts from its filter string: they are the
    ones the figure and animation writers know, in the filters' order."""
    from app.export.current import ANIMATION_SUFFIXES
    from app.figures.export import FIGURE_FORMATS, filter_suffixes
    from app.main_window import ANIMATION_FILTERS, FIGURE_FILTERS, TRAJECTORY_FILTERS

    assert filter_suffixes(FIGURE_FILTERS) == tuple(FIGURE_FORMATS)
    assert filter_suffixes(ANIMATION_FILTERS) == ANIMATION_SUFFIXES
    assert filter_suffixes(TRAJECTORY_FILTERS) == (".csv", ".npy", ".obj", ".ply")
    assert filter_suffixes("PNG image (*.PNG);;no pattern") == (".png",)


def _drawn_texts(fig):
    """Every text the figure draws: tick labels of the ticks in view (2-D axes), labels, titles,
    legends, notes, annotations whose point is drawn. mplot3d places its tick labels itself."""
    from matplotlib.text import Annotation, Text

    r = fig.canvas.get_renderer()
    tick_texts, out = set(), []
    for ax in fig.axes:
        for axis in ax._axis_map.values():
            for t in axis.get_major_ticks() + axis.get_minor_ticks():
                tick_texts.update({id(t.label1), id(t.label2)})
            if ax.name != "3d" and ax.axison:  # an axes switched off draws no tick labels
                for t in axis._update_ticks():
                    out += [lab for lab in (t.label1, t.label2) if lab.get_visible()]
    out += [t for t in fig.findobj(Text) if id(t) not in tick_texts and t.get_visible()]
    return [t for t in out if t.get_text().strip() and not (isinstance(t, Annotation) and not t._check_xy(r))]


@pytest.mark.parametrize("name", list(F.FIGURES))
def test_no_two_texts_of_a_figure_overlap(figs, name):
    fig = figs[name]
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(r)) for t in _drawn_texts(fig)]
    assert len(boxes) >= 3
    clashes = [(a, b) for i, (a, ba) in enumerate(boxes) for b, bb in boxes[i + 1:] if ba.overlaps(bb)]
    assert clashes == []


def test_fig3_phone_labels_avoid_each_other_in_a_crowd():
    from app.figures.labels import place_labels
    from app.figures.style import new_figure

    fig = new_figure(4, 3)
    ax = fig.subplots()
    rng = np.random.default_rng(1)
    xy = np.vstack([rng.normal(0, 0.15, (12, 2)), rng.uniform(-5, 5, (8, 2))])  # 12 in a tight knot
    ax.plot(xy[:, 0], xy[:, 1], "o")
    left_out = place_labels(ax, xy, [f"p{k}" for k in range(len(xy))])
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    texts = [t for t in ax.texts if t.get_text().startswith("p")]
    assert len(texts) == len(xy) - left_out and len(texts) >= 14
    boxes = [t.get_window_extent(r) for t in texts]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])


def test_phone_labels_are_never_struck_through_by_a_line():
    from app.figures.labels import line_segments, place_labels
    from app.figures.style import new_figure

    fig = new_figure(4, 3)
    ax = fig.subplots()
    t = np.linspace(0, 6 * np.pi, 200)
    ax.plot(np.cos(t) * t, np.sin(t) * t, "-", color="k")  # a spiral crossing the labels' neighbourhoods
    xy = np.column_stack([np.cos(t[::20]) * t[::20], np.sin(t[::20]) * t[::20]])
    ax.plot(xy[:, 0], xy[:, 1], "o", ls="none")
    left_out = place_labels(ax, xy, [f"ph{k}" for k in range(len(xy))])
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    segs = line_segments(ax)
    from app.figures.labels import _crosses

    texts = [t for t in ax.texts if t.get_text().startswith("ph")]
    assert len(texts) == len(xy) - left_out >= len(xy) // 2
    assert not any(_crosses(t.get_window_extent(r), segs) for t in texts)


def test_fig2a_panels_fill_their_cells(figs):
    fig = figs["fig2a"]
    r = fig.canvas.get_renderer()
    flat = [ax for ax in fig.axes if ax.name == "rectilinear" and ax.get_xlabel() and ax.get_label() != "<colorbar>"]
    assert len(flat) == 3
    # the corner layout: panels sharing Y1 have the same width, panels sharing Y3 the same height
    box = {ax.get_xlabel().split()[0] + ax.get_ylabel().split()[0]: ax.get_window_extent(r) for ax in flat}
    assert box["Y1Y2"].width == pytest.approx(box["Y1Y3"].width, rel=0.03)
    assert box["Y1Y3"].height == pytest.approx(box["Y2Y3"].height, rel=0.03)


@pytest.mark.gui
def test_vector_export_shades_smooth_surfaces_smoothly(can_render, tmp_path):
    """A smooth-shaded opaque surface (the lips) is exported as Gouraud triangles, not flat facets."""
    import pyvista as pv
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from app.figures.view_vector import scene_figure

    def export(smooth):
        p = pv.Plotter(off_screen=True, window_size=(200, 200))
        p.add_mesh(pv.Sphere(theta_resolution=10, phi_resolution=10), color=(0.8, 0.8, 0.8), smooth_shading=smooth)
        p.camera.zoom(0.7)
        p.render()
        fig = scene_figure(p)
        out = F.save_plotter_vector(p, tmp_path / f"s{int(smooth)}.pdf")
        p.close()
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        grey = np.asarray(canvas.buffer_rgba())[85:115, 85:115, 0].astype(float)  # inside the sphere
        # facet edges: the largest steps between neighbouring pixels
        return out.read_bytes(), fig.lipspace["n_polygons"], np.percentile(np.abs(np.diff(grey, axis=1)), 99)

    pdf_s, n_s, step_s = export(True)
    pdf_f, n_f, step_f = export(False)
    assert b"/ShadingType 4" in pdf_s and b"/ShadingType 4" not in pdf_f   # a Gouraud mesh vs polygons
    assert n_s > 50 and n_f > 50 and b"/Subtype /Image" not in pdf_s
    assert step_f >= 3 and step_s <= 0.5 * step_f, (step_s, step_f)


@pytest.mark.gui
def test_vector_export_shades_a_smooth_surface_with_the_windows_normals(can_render):
    """The Gouraud corners are shaded by VTK's point normals (unweighted mean of the face normals, as the
    window draws them), not by area-weighted ones: a fold of a large and a small triangle tells them apart."""
    import pyvista as pv

    from app.figures.view_vector import _actor_primitives
    from app.scene.projection import view_transform

    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0.1]], float)
    mesh = pv.PolyData(P, np.array([3, 0, 1, 2, 3, 0, 3, 1]))
    p = pv.Plotter(off_screen=True, window_size=(120, 120))
    try:
        actor = p.add_mesh(mesh, color=(0.8, 0.8, 0.8), smooth_shading=True)
        p.camera_position = [(2.0, 3.0, 1.0), (0.2, 0.2, 0.0), (0, 0, 1)]
        p.render()
        cam = p.renderer.GetActiveCamera()
        view_dir = np.subtract(cam.GetFocalPoint(), cam.GetPosition())
        view_dir /= np.linalg.norm(view_dir)
        prims, _ = _actor_primitives(actor, *view_transform(p), view_dir)
    finally:
        p.close()
    (kind, _, _, vc), = [q for q in prims if q[0] == "gouraud"]
    ref = mesh.compute_normals(cell_normals=False, split_vertices=False)
    n_vtk = np.asarray(ref.point_data["Normals"], float)
    fn = np.cross(P[[1, 3]] - P[0], P[[2, 1]] - P[0])   # the two faces' normals, length = 2 x area
    n_area = fn.sum(0) / np.linalg.norm(fn.sum(0))       # area-weighted at the shared point 0
    shade = lambda n: 0.8 * (0.45 + 0.55 * abs(n @ view_dir))  # noqa: E731
    assert abs(shade(n_vtk[0]) - shade(n_area)) > 0.02        # the weighting shows at point 0
    assert vc[0, 0, :3] == pytest.approx([shade(n_vtk[0])] * 3, abs=1e-5)   # face 0's corner at point 0
    assert vc[1, 0, :3] == pytest.approx([shade(n_vtk[0])] * 3, abs=1e-5)   # face 1's corner at point 0
    assert vc[0, 2, :3] == pytest.approx([shade(n_vtk[2])] * 3, abs=1e-5)


def test_fig4_without_any_of_its_phones_is_refused_not_drawn_empty(m):
    with pytest.raises(ValueError, match=r"none of /zz/, /qq/ has 3 or more mid-points .*choose phones"):
        F.make_fig4(m, phones=("zz", "qq"))


def test_the_figure_names_and_descriptions_import_no_matplotlib():
    """The window's menus read the names and descriptions; the figure modules load when a figure is asked for."""
    import textwrap

    script = textwrap.dedent("""
        import sys
        from app.figures import DESCRIPTIONS, UTTERANCE_FIGURES
        print("BEFORE", any(m.startswith("matplotlib") for m in sys.modules))
        import app.figures as F
        print("FIGURES", list(F.FIGURES) == list(DESCRIPTIONS), F.make_fig3.__module__, F.save_figure.__module__)
        print("AFTER", "matplotlib.figure" in sys.modules, set(UTTERANCE_FIGURES) <= set(DESCRIPTIONS))
        try:
            F.no_such_figure
        except AttributeError as exc:
            print("MISSING", exc)
        print("MODULE", F.hops.__name__)
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "BEFORE False" in r.stdout
    assert "FIGURES True app.figures.synthesis app.figures.export" in r.stdout
    assert "AFTER True True" in r.stdout
    assert "MISSING module 'app.figures' has no attribute 'no_such_figure'" in r.stdout
    assert "MODULE app.figures.hops" in r.stdout


def test_make_figure_calls_the_function_the_package_holds(monkeypatch):
    monkeypatch.setattr(F, "make_fig2b", lambda manifold, **opts: ("drawn", manifold, opts))
    assert F.make_figure("fig2b", "m", width=90) == ("drawn", "m", {"width": 90})
