"""The manifold view's scene layers: the cloud, plane, S and V, markers, paths, trajectories, ellipsoids.

A part of :class:`app.views.manifold_view.ManifoldView` (a mixin): builds the layers with the
:mod:`app.scene` builders once per manifold and brings each up to date in place.
"""
from __future__ import annotations

import numpy as np

from app import scene
from app.models.colouring import ellipsoid_colors, point_colors
from app.models.picking import CloudLocator
from app.scene import legend as scene_legend
from app.scene.colour_bar import add_scalar_bar, configure_scalar_bar
from app.scene.projection import project, standard_camera, view_transform
from app.views._common import blocked

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
        self._legend_mode, self.legend = None, None  # cleared with the other actors
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
        h["local"] = scene.add_local_frame(p, length=0.18 * L)
        h["marker"] = scene.add_marker(p, None, 0.018 * L, color=(1.0, 0.85, 0.0), name="selected")
        h["target"] = scene.add_marker(p, None, 0.018 * L, color=(0.0, 0.8, 0.8), name="target")
        h["path"] = scene.add_state_path(p, m.states_.centroids_[:, :3], None, node_radius=0.006 * L)
        h["original"] = scene.add_trajectory(p, None, scene.ORIGINAL_COLOUR, name="original")
        h["synthetic"] = scene.add_trajectory(p, None, scene.SYNTHETIC_COLOUR, name="synthetic")
        h["play_o"] = scene.add_marker(p, None, 0.016 * L, color=scene.ORIGINAL_COLOUR, name="play_original")
        h["play_s"] = scene.add_marker(p, None, 0.016 * L, color=scene.SYNTHETIC_COLOUR, name="play_synthetic")
        for key in self.OVERLAY:  # drawn over the cloud: never buried inside it
            scene.move_to_overlay(p, h[key])
        self._bar = add_scalar_bar(p)
        # a click or the pointer finds its frame among every frame, drawn or not
        self.locator = CloudLocator(m.Fy_, cloud, dot_radius=0.5 * size)
        self.picker = scene.enable_click_picking(p, h["points"].actor, self._on_pick, locate=self.frame_at)
        self._set_visible("plane", self.plane_box.isChecked())
        self._show_points(self.points_box.isChecked())
        self._show_axes(self.axes_box.isChecked())
        with blocked(self.path_box):
            self.path_box.setChecked(self.state.path_mode)
        self._on_mode(render=False)
        self._on_selection(render=False, recolor=False)  # _on_mode has coloured the points
        self._on_path(render=False)
        self._on_trajectories(render=False)
        self._on_phones(render=False)
        self._install_hover()
        self.standard_view("default", render=False)
        p.camera_set = True  # keep this framing (pyvista re-frames everything on first camera access otherwise)
        self.renderer.request()

    #: handles drawn in the overlay layer, over the cloud
    OVERLAY = ("marker", "target", "path", "local", "original", "synthetic", "play_o", "play_s")
    #: milliseconds between two hover look-ups while the pointer moves
    HOVER_INTERVAL_MS = 60

    def standard_view(self, name: str, render: bool = True) -> None:
        """Put the camera in a standard view: "side" (S–V plane), "top" (down V) or "default"."""
        m = self.state.manifold
        if m is None or "points" not in self.handles:
            return
        t = m.tangent_
        # the cloud's bounds stand for every frame (the camera only reads their extent)
        pos, focal, up = standard_camera(name, self.state.cloud.bounds, t.plane_point_, t.S_, t.plane_normal_)
        cam = self.plotter.renderer.GetActiveCamera()
        cam.SetPosition(*pos)
        cam.SetFocalPoint(*focal)
        cam.SetViewUp(*up)
        ren = self.plotter.renderer
        lo, hi = np.reshape(self.handles["points"].mesh.bounds, (3, 2)).T
        tips = self.handles["axes"].get("tips") if isinstance(self.handles.get("axes"), dict) else None
        if tips is not None:  # the S and V labels stand beyond the cloud: frame them too
            lo, hi = np.minimum(lo, tips.min(axis=0)), np.maximum(hi, tips.max(axis=0))
        ren.ResetCamera(*np.column_stack([lo, hi]).ravel())  # fit the cloud and the labels, same direction
        if tips is not None:  # and keep the labels' text inside the view, not cut at its edge
            for _ in range(2):
                M, size = view_transform(self.plotter)
                z = scene.label_zoom(project(tips, M, size)[0], size)
                if z >= 0.999:
                    break
                cam.Zoom(z)
        ren.ResetCameraClippingRange()
        if render:
            self.renderer.request()

    def _set_visible(self, key, on):
        if key in self.handles:
            self.handles[key].set_visible(on)
            self.renderer.request()

    def _show_points(self, on):
        if "points" in self.handles:
            self.handles["points"].set_visible(on)
            self._bar.SetVisibility(on and self.coloring is not None and self.coloring.cmap is not None)
            self.renderer.request()

    def _show_axes(self, on):
        axes = self.handles.get("axes")
        if axes:
            for k in ("S", "V"):
                axes[k].set_visible(on)
            if "labels" in axes:
                axes["labels"].SetVisibility(on)
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
        self._bar.SetVisibility(c.cmap is not None and self.points_box.isChecked())
        legend = tuple((n, tuple(col)) for n, col in c.legend)
        if legend != self._legend_mode:
            if self.legend is not None:
                scene_legend.remove_legend(self.plotter, self.legend)
                self.legend = None
            if legend:
                self.legend = scene_legend.add_legend(self.plotter, legend,
                                                      size=(0.22, min(0.6, 0.035 * len(legend) + 0.02)))
            self._legend_mode = legend or None
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
        self._update_info()
        if render:
            self.renderer.request()

    def _on_path(self, render=True):
        if "path" not in self.handles:
            return
        p = self.state.path
        C = self.state.manifold.states_.centroids_[:, :3]
        self.handles["path"].update(C[p] if p is not None else None)
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
        if "points" not in self.handles:
            return
        want = self.state.visible_phones
        colours = ellipsoid_colors(want)
        Y = self.state.manifold.Fy_
        for ph in sorted(want - set(self.ellipsoids)):
            verts, faces = self.state.clusters.ellipsoid(ph)
            self.ellipsoids[ph] = scene.add_cluster_ellipsoids(self.plotter, np.asarray(verts)[:, :3], faces,
                                                               colours[ph], name=f"ellipsoid_{ph}")
            members = Y[self.state.clusters.members(ph), :3]
            small = len(members) <= self.SPHERE_POINTS_MAX
            self.members[ph] = scene.add_point_markers(self.plotter, members, colours[ph],
                                                       point_size=7 if small else 4, spheres=small,
                                                       name=f"members_{ph}")
        for ph in self.ellipsoids:
            on = ph in want
            self.ellipsoids[ph].set_visible(on)
            self.members[ph].set_visible(on)
            if on:
                self.ellipsoids[ph].actor.prop.color = colours[ph]
                self.members[ph].actor.prop.color = colours[ph]
        if render:
            self.renderer.request()
