"""The live mirror's 3-D scene (Qt-free; any pyvista plotter): the manifold cloud, its
states coloured by the current live state's future hemisphere, the live trajectory of
the last few seconds and a marker on the newest frame."""
from __future__ import annotations

import numpy as np

from app.scene.manifold import add_manifold_points, add_marker, add_trajectory, scene_scale

__all__ = ["LiveScene", "future_colours", "state_points", "TRAIL_SECONDS"]

#: seconds of live trajectory drawn
TRAIL_SECONDS = 3.0
_NEAR = np.array([0.85, 0.10, 0.10])   # one hop ahead
_FAR = np.array([0.15, 0.35, 0.90])    # the horizon
_HERE = np.array([1.0, 0.85, 0.0])     # the current state
_OUT = np.array([0.78, 0.78, 0.78])    # not in the future hemisphere (within the horizon)


def future_colours(hops) -> np.ndarray:
    """(K, 3) colours for hop distances (K,): yellow at 0, red near to blue far, grey at inf."""
    d = np.asarray(hops, dtype=np.float64)
    rgb = np.tile(_OUT, (d.size, 1))
    fin = np.isfinite(d)
    if fin.any():
        top = max(float(d[fin].max()), 1.0)
        w = (d[fin] / top)[:, None]
        rgb[fin] = (1 - w) * _NEAR + w * _FAR
    rgb[d == 0] = _HERE
    return rgb


def state_points(manifold) -> np.ndarray:
    """(K, 3): each state's mean F^y (first three dimensions) over its frames."""
    Fy = np.asarray(manifold.Fy_, dtype=np.float64)[:, :3]
    lab = np.asarray(manifold.states_.labels_)
    K = manifold.states_.centroids_.shape[0]
    n = np.bincount(lab, minlength=K).astype(np.float64)
    P = np.stack([np.bincount(lab, weights=Fy[:, j], minlength=K) for j in range(3)], axis=1)
    return P / np.maximum(n, 1)[:, None]


class LiveScene:
    """Build the scene in ``plotter`` for ``manifold``; :meth:`update` adds live samples.

    Parameters
    ----------
    plotter : pyvista plotter
    manifold : Manifold
    rate : float
        Live frame rate (sets how many samples the trail keeps).
    """

    def __init__(self, plotter, manifold, *, rate: float = 30.0, max_cloud: int = 20000):
        self.plotter = plotter
        self.manifold = manifold
        Fy = np.asarray(manifold.Fy_, dtype=np.float32)[:, :3]
        step = max(1, len(Fy) // int(max_cloud))
        self.cloud = add_manifold_points(plotter, Fy[::step], point_size=2.0, spheres=False, name="live_cloud")
        self.cloud.actor.GetProperty().SetOpacity(0.35)
        self.states = add_manifold_points(plotter, state_points(manifold), future_colours(
            np.full(manifold.states_.centroids_.shape[0], np.inf)), point_size=9.0, name="live_states")
        self.trail = add_trajectory(plotter, np.zeros((0, 3)), color=(0.0, 0.0, 0.0), line_width=4.0,
                                    name="live_trail")
        self.marker = add_marker(plotter, None, radius=0.02 * scene_scale(Fy), color=(1.0, 0.85, 0.0),
                                 name="live_marker")
        self.keep = max(2, int(round(TRAIL_SECONDS * float(rate))))
        self.Y = np.zeros((0, 3), np.float32)
        self.state = None
        plotter.reset_camera()

    def update(self, samples, future=None) -> bool:
        """Append samples (:class:`app.models.live.LiveSample`); recolour the states when the current
        state changed (``future(state) -> hops (K,)``). Returns whether anything changed."""
        if not samples:
            return False
        Y = np.stack([np.asarray(s.y[:3], np.float32) for s in samples])
        self.Y = np.concatenate([self.Y, Y])[-self.keep:]
        self.trail.update(self.Y)
        self.marker.move(self.Y[-1])
        self.marker.set_visible(True)
        st = samples[-1].state
        if st != self.state and future is not None:
            hops = future(st)
            self.states.set_colors(future_colours(hops), np.where(np.isfinite(hops), hops, np.nan))
        self.state = st
        return True
