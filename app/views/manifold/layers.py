"""The manifold view's scene layers: the cloud, plane, S and V, markers, paths, trajectories, ellipsoids.

A part of :class:`app.views.manifold_view.ManifoldView` (a mixin): builds the layers with the
:mod:`app.scene` builders once per manifold and brings each up to date in place. Trajectories
and the path carry cones pointing the way they run; cluster ellipsoids take their label's
colour from the session palette, with an opaque outline and a fill of the chosen opacity.
"""
from __future__ import annotations

import numpy as np

from app import scene
from app.models.colour_maps import RESERVED_COLOURS
from app.models.colouring import point_colors
from app.models.picking import CloudLocator
from app.models.view_legend import ellipsoid_kind
from app.scene.axes import add_embedding_axes, axis_labels
from app.scene.colour_bar import add_scalar_bar, configure_scalar_bar

__all__ = ["ManifoldLayers", "axes_origin"]


def axes_origin(Y, plane_point, S, V, length_scale) -> np.ndarray:
    """Where to root the global S and V arrows: on the zero-velocity plane, beside the cloud.

    S and V are directions; drawn from the plane point they vanish inside the points,
    so they start at the cloud's back edge along S, just outside it across the plane
    (like the axes glyph of the paper's Fig. 2a).
    """
    S = np.asarray(S, float) / np.linalg.norm(S)
    V = np.asarray(V, float) / np.linalg.norm(V)
    W = np.cross(V, S)
    d = np.asarray(Y, float)[:, :3] - plane_point
    return np.asarray(plane_point, float) + (d @ S).min() * S + ((d @ W).max() + 0.05 * length_scale) * W


class ManifoldLayers:
    """The scene of :class:`app.views.manifold_view.ManifoldView`."""

    #: clouds (and a cluster's member markers) up to this many points are drawn as shaded spheres,
    #: larger ones as flat dots: 12,759 members of a phone at 1M frames took 50-70 ms of a 75-ms render
    #: as spheres
    SPHERE_POINTS_MAX = 10000

    # ------------------------------------------------------------------ build
    def rebuild(self) -> None:
        """Redraw everything for the state's manifold (after loading one)."""
        p = self.plotter
        if self.picker is not None:
            self.picker.remove()
        p.clear_actors()
        scene.overlay_renderer(p).RemoveAllViewProps()
        self.handles, self.ellipsoids, self.members = {}, {}, {}
        self._forget_legends()  # cleared with the other actors
        m = self.state.manifold
        if m is None:
            self.renderer.request()
            return
        cloud = self.state.cloud  # level of detail: every frame, or one point per group of frames (app.models.lod)
        Y = np.asarray(m.Fy_[cloud.frames, :3], dtype=np.float64)  # the drawn points
        L = scene.scene_scale(cloud.bounds)
        self.scale = L
        t = m.tangent_
        h = self.handles
        # shaded spheres cost ~4x flat dots per frame in software GL; at 3.5 px they are hardly
        # distinguishable, so large clouds (the default talker's 28,800 frames) use dots
        small = len(Y) <= self.SPHERE_POINTS_MAX
        size = 5.0 if small else 3.5
        h["points"] = scene.add_manifold_points(p, m.Fy_, point_size=size, spheres=small,
                                                frames=None if cloud.whole else cloud.frames)
        h["plane"] = scene.add_zero_velocity_plane(p, t.plane_point_, t.plane_normal_, 1.1 * L)
        h["axes"] = scene.add_global_axes(p, axes_origin(Y, t.plane_point_, t.S_, t.plane_normal_, L), t.S_,
                                          t.plane_normal_, 0.45 * L)
        shares = getattr(getattr(m, "embedding_", None), "explained_variance_ratio_", None)
        h["yaxes"] = add_embedding_axes(p, np.column_stack(np.asarray(cloud.bounds)).ravel(), axis_labels(shares))
        h["local"] = scene.add_local_frame(p, length=0.18 * L)
        h["marker"] = scene.add_marker(p, None, 0.018 * L, color=RESERVED_COLOURS["selected"], name="selected")
        h["target"] = scene.add_marker(p, None, 0.018 * L, color=RESERVED_COLOURS["target"], name="target")
        arrow = self.ARROW_SIZE * L  # the cones that show which way a trajectory or path runs
        h["path"] = scene.add_state_path(p, m.states_.centroids_[:, :3], None, node_radius=0.006 * L,
                                         arrow_size=arrow)
        h["original"] = scene.add_trajectory(p, None, scene.ORIGINAL_COLOUR, name="original", arrow_size=arrow)
        h["synthetic"] = scene.add_trajectory(p, None, scene.SYNTHETIC_COLOUR, name="synthetic", arrow_size=arrow)
        h["play_o"] = scene.add_marker(p, None, 0.016 * L, color=scene.ORIGINAL_COLOUR, name="play_original")
        h["play_s"] = scene.add_marker(p, None, 0.016 * L, color=scene.SYNTHETIC_COLOUR, name="play_synthetic")
        for key in self.OVERLAY:  # drawn over the cloud: never buried inside it
            scene.move_to_overlay(p, h[key])
        self._add_gesture_marks(L)
        self._bar = add_scalar_bar(p)
        # a click or the pointer finds its frame among every frame, drawn or not
        self.locator = CloudLocator(m.Fy_, cloud, dot_radius=0.5 * size)
        self.picker = scene.enable_click_picking(p, h["points"].actor, self._on_pick, locate=self.frame_at)
        self._on_layers(render=False)
        self._sync_layer_boxes()
        self._sync_box(self.path_box, self.state.path_mode)
        self._on_mode(render=False)
        self._on_selection(render=False, recolor=False)  # _on_mode has coloured the points
        self._on_path(render=False)
        self._on_trajectories(render=False)
        self._on_phones(render=False)
        self._on_gesture_marks(render=False)
        self._install_hover()
        self._update_hover()  # the last file's pointer readout goes with it
        self.standard_view("default", render=False)
        p.camera_set = True  # keep this framing (pyvista re-frames everything on first camera access otherwise)
        self._update_legends()
        self.renderer.request()

    #: handles drawn in the overlay layer, over the cloud
    OVERLAY = ("marker", "target", "path", "local", "original", "synthetic", "play_o", "play_s")
    #: milliseconds between two hover look-ups while the pointer moves
    HOVER_INTERVAL_MS = 60
    #: length of the direction cones on trajectories and paths, as a share of the cloud's extent
    ARROW_SIZE = 0.035

    def _on_layers(self, render=True) -> None:
        """Show the layers the state does not hide (points, plane, S / V and the named axes, legends)."""
        h, hidden = self.handles, self.state.hidden_layers
        if "points" not in h:
            return
        h["points"].set_visible("points" not in hidden)
        h["plane"].set_visible("plane" not in hidden)
        axes = "axes" not in hidden
        for k in ("S", "V"):
            h["axes"][k].set_visible(axes)
        if "labels" in h["axes"]:
            h["axes"]["labels"].SetVisibility(axes)
        h["yaxes"]["lines"].set_visible(axes)
        h["yaxes"]["labels"].SetVisibility(axes)
        self._bar.SetVisibility("points" not in hidden and self.coloring is not None and self.coloring.cmap is not None)
        self._update_legends()
        if render:
            self.renderer.request()

    def _on_mode(self, render=True):
        self._sync_mode_boxes()
        self._recolor(render=render)

    def _recolor(self, render=True):
        if "points" not in self.handles:
            return
        c = point_colors(self.state.color_mode, self.state.manifold, self.state)
        self.n_recolors += 1
        self.coloring = c
        self.handles["points"].set_colors(c.rgb, c.values)
        configure_scalar_bar(self._bar, c)
        self._bar.SetVisibility(c.cmap is not None and "points" not in self.state.hidden_layers)
        self._update_legends()
        self._update_info()
        if render:
            self.renderer.request()

    def _on_selection(self, render=True, recolor=True):
        if "points" not in self.handles:
            return
        s, m, h = self.state, self.state.manifold, self.handles
        if s.frame is not None:
            i = s.frame
            t = m.tangent_
            y = m.Fy_[i, :3]
            h["marker"].move(y)
            h["local"].update(y, *t.drawn_local_frame(i))
        elif s.state is not None:
            h["marker"].move(m.states_.centroids_[s.state, :3])
            h["local"].set_visible(False)
        else:
            h["marker"].set_visible(False)
            h["local"].set_visible(False)
        if s.target is not None:
            h["target"].move(m.states_.centroids_[s.target, :3])
        else:
            h["target"].set_visible(False)
        if recolor and s.color_mode == "distance":
            self._recolor(render=False)
        self._update_legends()
        self._update_info()
        if render:
            self.renderer.request()

    def _on_path(self, render=True):
        if "path" not in self.handles:
            return
        p = self.state.path
        C = self.state.manifold.states_.centroids_[:, :3]
        self.handles["path"].update(C[p] if p is not None else None)
        self._update_legends()
        self._update_info()
        if render:
            self.renderer.request()

    def _on_trajectories(self, render=True):
        if "original" not in self.handles:
            return
        for key in ("original", "synthetic"):
            traj = getattr(self.state, key)
            self.handles[key].update(None if traj is None else np.asarray(traj.Y)[:, :3])
        self._on_playback(render=False)
        self._update_legends()
        if render:
            self.renderer.request()

    #: while playing, the manifold view renders the moving markers at most this often, and at most
    #: PLAYBACK_RENDER_SHARE of the time (its last render's duration sets a longer interval on a slow
    #: or busy machine): the lip view gets the frame budget (a manifold frame costs several lip frames
    #: in software GL)
    PLAYBACK_RENDER_INTERVAL_S = 0.5
    PLAYBACK_RENDER_SHARE = 0.1

    def _on_playback(self, render=True):
        """Move the playback markers (actor positions only: the cloud is never recoloured)."""
        if "play_o" not in self.handles:
            return
        k = self.state.playback
        for key, traj in (("play_o", self.state.original), ("play_s", self.state.synthetic)):
            if k is None or traj is None:
                self.handles[key].set_visible(False)
            else:
                self.handles[key].move(np.asarray(traj.Y)[min(k, len(traj) - 1), :3])
        if render:
            self._request_playback_render()

    def _request_playback_render(self):
        """A render for moved playback markers: throttled while playing, at once otherwise."""
        wait = 0.0
        if self.state.playing:
            wait = max(self.PLAYBACK_RENDER_INTERVAL_S, self.renderer.last_duration / self.PLAYBACK_RENDER_SHARE)
            # counted from Play too, not only from the last render: rendered just as the clock
            # starts, the markers held back the first lip frames (the first tick came ~90 ms late)
            wait += max(0.0, self._play_started - self.renderer.last_flush)
        self.renderer.request(min_interval_s=wait)

    def _on_phones(self, render=True):
        """The shown clusters' ellipsoids and member points, each in its label's palette colour."""
        if "points" not in self.handles:
            return
        s = self.state
        want = s.visible_phones
        kind = ellipsoid_kind(s) if want or self.ellipsoids else "phone"
        Y = s.manifold.Fy_
        for ph in sorted(want - set(self.ellipsoids)):
            colour = s.palette.colour(kind, ph)
            verts, faces = s.clusters.ellipsoid(ph)
            self.ellipsoids[ph] = scene.add_cluster_ellipsoids(self.plotter, np.asarray(verts)[:, :3], faces, colour,
                                                               opacity=s.ellipsoid_opacity, name=f"ellipsoid_{ph}")
            members = Y[s.clusters.members(ph), :3]
            small = len(members) <= self.SPHERE_POINTS_MAX
            self.members[ph] = scene.add_point_markers(self.plotter, members, colour,
                                                       point_size=7 if small else 4, spheres=small,
                                                       name=f"members_{ph}")
        for ph in self.ellipsoids:
            on = ph in want
            self.ellipsoids[ph].set_visible(on)
            self.members[ph].set_visible(on)
            if on:
                colour = s.palette.colour(kind, ph)
                self.ellipsoids[ph].set_color(colour)
                self.ellipsoids[ph].set_opacity(s.ellipsoid_opacity)
                self.members[ph].actor.prop.color = colour
        self._update_legends()
        if render:
            self.renderer.request()
