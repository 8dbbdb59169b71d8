"""What the manifold view's legends say: the colours of the points, and every glyph drawn (Qt-free).

Two lists of ``(label, rgb, symbol)`` rows (symbols as :mod:`app.scene.legend` draws them):
:func:`point_legend`, the categories (or the greys of "no value") the points are coloured
by; :func:`glyph_legend`, one row per kind of thing drawn over or beside them now: the
selected frame or state, the target and the path, the trajectories, the playback
position, the local frame's arrows, S and V, the zero-velocity plane, the named axes and
each shown cluster ellipsoid in its palette colour. A row appears only while its glyph is
drawn, so the legend always says what is on the screen.
"""
from __future__ import annotations

from app.models.colour_maps import RESERVED_COLOURS as R

__all__ = ["point_legend", "glyph_legend", "ellipsoid_kind"]


def point_legend(coloring) -> list[tuple]:
    """The points' legend rows from a :class:`app.models.colouring.Coloring` (circles)."""
    if coloring is None:
        return []
    return [(str(label), tuple(float(c) for c in rgb), "circle") for label, rgb in coloring.legend]


def ellipsoid_kind(state) -> str:
    """The palette kind of the cluster labels: ``"phone"``, or ``"landmark"`` for kinematic clusters."""
    return "landmark" if state.cluster_kind == "kinematic" else "phone"


def glyph_legend(state, *, hidden=frozenset(), local_frame: bool = False, landmarks=()) -> list[tuple]:
    """One row per kind of glyph drawn now.

    Parameters
    ----------
    state : app.models.state.AppState
    hidden : set of str
        Layers the user hid (``"plane"``, ``"axes"``: S, V and the named Y axes).
    local_frame : bool
        Whether the selected frame's local arrows are drawn (a frame with a forward step).
    landmarks : sequence of (str, rgb)
        The gestural landmarks marked now (code, colour), in gesture order.
    """
    rows = []
    if state.manifold is None:
        return rows
    if state.frame is not None:
        rows.append(("selected frame", R["selected"], "circle"))
    elif state.state is not None:
        rows.append(("selected state (centroid)", R["selected"], "circle"))
    if state.target is not None:
        rows.append(("target state", R["target"], "circle"))
    if state.path is not None:
        rows.append((f"fewest-hop path, {len(state.path) - 1} hops", R["state path"], "line"))
    if state.original is not None:
        rows.append((f"original trajectory ({state.original.label})", R["original trajectory"], "line"))
    if state.synthetic is not None:
        rows.append((f"synthetic trajectory ({state.synthetic.label})", R["synthetic trajectory"], "line"))
    if state.playback is not None and (state.original is not None or state.synthetic is not None):
        rows.append(("playback position", R["original trajectory"], "circle"))
    if local_frame and state.frame is not None:
        rows += [("s_i: local shape direction", R["local s"], "arrow"),
                 ("v_i: local velocity direction", R["local v"], "arrow"),
                 ("n_i: normal of the local plane", R["normal"], "arrow")]
    if "axes" not in hidden:
        rows += [("S: global shape direction", R["S"], "arrow"), ("V: global velocity direction", R["V"], "arrow")]
    if "plane" not in hidden:
        rows.append(("zero-velocity plane (V = 0)", R["plane"], "square"))
    if landmarks:
        track = state.gestures.track if state.gestures is not None else "a track"
        rows += [(f"{code}: landmark of {track}" if k == 0 else code, rgb, "square")
                 for k, (code, rgb) in enumerate(landmarks)]
    if state.visible_phones and state.palette is not None:
        kind = ellipsoid_kind(state)
        for label in sorted(state.visible_phones):
            rows.append((f"{label}: 2-s.d. ellipsoid", state.palette.colour(kind, label), "ring"))
    return [(label, tuple(float(c) for c in rgb), symbol) for label, rgb, symbol in rows]
