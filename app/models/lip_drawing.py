"""What one lip frame is drawn as: sensors as sensors, a surface only where one was measured.

The lip view, the MP4 export and the lip-shape figures (fig. 1a, fig. 2c) all draw a frame
from one :class:`LipDrawing`, after the conventions of articulograph viewers (VisArtico,
mview):

* **a measured surface** (the corpus has faces: a mesh sequence, FaceMesh landmarks tracked
  in a video, the synthetic talker's lip model) is drawn as that surface;
* **sensors** (a few named or role-carrying points, no faces) are drawn as markers, each
  labelled with its name (or its role: UL, LL, LC, RC, JAW...). The lip sensors are joined
  by straight segments in their order around the mouth; nothing between them is
  interpolated, so a shape never looks rounder, fuller or more open than what was
  measured. The lip aperture, the distance between the upper- and lower-lip sensors'
  centroids (:func:`engine.recordings.kinematics.lip_aperture`), is its own segment,
  labelled with its length in the corpus's unit. Jaw, reference and tongue sensors are
  markers of another shape, not joined;
* **bare points** (many unnamed points, no faces) are markers only.

3-D data are seen from the front (the talker's anatomical frame,
:mod:`engine.recordings.orientation`: x the talker's left on the viewer's right, y up);
2-D data are midsagittal and seen in profile, forward to the right, with the direction
the face looks shown (when the point roles tell it).

Free of Qt, VTK and matplotlib: views draw what this module says.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LipDrawing", "lip_drawing", "drawing_of", "ROLE_LABELS", "MAX_SENSORS", "LIP_ROLES"]

#: the label a sensor without a name gets from its role
ROLE_LABELS = {"upper_lip": "UL", "lower_lip": "LL", "left_corner": "LC", "right_corner": "RC", "lip": "L",
               "jaw": "JAW", "reference": "REF", "tongue": "T", "other": ""}
#: roles of points on the lips (joined by segments); the others are jaw, reference, tongue
LIP_ROLES = ("upper_lip", "lower_lip", "left_corner", "right_corner", "lip")
#: at most this many points are drawn as labelled sensors; more (without faces) are bare points
MAX_SENSORS = 20


@dataclass(frozen=True)
class LipDrawing:
    """How to draw the frames of one corpus (see the module docstring).

    Attributes
    ----------
    kind : {"surface", "sensors", "points"}
    view : {"front", "profile"}
        A front view of 3-D data, a profile (x forward, y up) of 2-D midsagittal data.
    unit : str
        The coordinates' unit (``Corpus.unit_label``).
    labels : tuple of str, one per point
        The text beside each sensor ("" = none; every label is "" for surfaces and bare points).
    lip : ndarray of shape (V,) bool
        Points on the lips (round markers, joined); the others are jaw, reference or tongue.
    segments : ndarray of shape (E, 2) int
        Point pairs joined by straight segments (consecutive lip sensors around the mouth).
    upper, lower : ndarray of int
        Upper- and lower-lip points whose centroids end the aperture segment (empty: no aperture).
    faces : ndarray of shape (F, 3) int or None
        The measured surface's triangles.
    forward : tuple of float or None
        Profile view: the direction the face looks in view coordinates ((1, 0): right), when
        known; None otherwise.
    note : str
        One line saying what is drawn, for captions and tooltips.
    """

    kind: str
    view: str
    unit: str
    labels: tuple
    lip: np.ndarray
    segments: np.ndarray
    upper: np.ndarray
    lower: np.ndarray
    faces: np.ndarray | None
    forward: tuple | None
    note: str

    @property
    def has_aperture(self) -> bool:
        return bool(self.upper.size and self.lower.size)

    def aperture(self, points):
        """The aperture segment of one frame: ``(upper end (d,), lower end (d,), length)``, or None.

        Parameters
        ----------
        points : ndarray of shape (V, d)
            The frame's points (any coordinates related to the data's by a rotation: view
            coordinates or the data's own; the length is the same).
        """
        if not self.has_aperture:
            return None
        P = np.asarray(points, np.float64)
        top, bottom = P[self.upper].mean(axis=0), P[self.lower].mean(axis=0)
        return top, bottom, float(np.linalg.norm(top - bottom))

    def aperture_text(self, value: float) -> str:
        """The aperture's label: ``"12.3 mm"`` (the unit as the corpus gives it)."""
        unit = self.unit if self.unit and not self.unit.startswith("(") else "units"
        return f"{value:.1f} {unit}"


def _ring(xy: np.ndarray) -> list[int]:
    """Positions of ``xy`` (n, 2) in angular order around their centroid (counter-clockwise from the right)."""
    c = xy.mean(axis=0)
    ang = np.arctan2(xy[:, 1] - c[1], xy[:, 0] - c[0])
    return [int(k) for k in np.argsort(ang, kind="stable")]


def _segments(ref: np.ndarray, lip_idx: np.ndarray, roles) -> np.ndarray:
    """Straight segments between consecutive lip sensors around the mouth on the reference frame ``ref``
    (view coordinates); a segment from an upper- to a lower-lip point is the aperture's, not the outline's."""
    if len(lip_idx) < 2:
        return np.zeros((0, 2), np.int64)
    order = lip_idx[_ring(ref[lip_idx, :2])]
    pairs = list(zip(order, np.roll(order, -1))) if len(order) > 2 else [(order[0], order[1])]
    vertical = {"upper_lip", "lower_lip"}

    def across(a, b):
        ra, rb = (roles[a] if roles else ""), (roles[b] if roles else "")
        return {ra, rb} == vertical

    keep = [(int(a), int(b)) for a, b in pairs if not across(a, b)]
    return np.asarray(keep, np.int64).reshape(-1, 2)


def lip_drawing(corpus, reference=None, *, frame=None) -> LipDrawing:
    """How the frames of ``corpus`` are drawn.

    Parameters
    ----------
    corpus : engine.recordings.corpus.Corpus
    reference : ndarray of shape (V, 3), optional
        A frame in view coordinates (``frame.view``) that fixes the sensors' order around the
        mouth, e.g. the mean shape; default: the mean of the corpus's first 20,000 frames.
    frame : engine.recordings.orientation.AnatomicalFrame, optional
        The talker's frame (default :func:`engine.recordings.orientation.anatomical_frame`).

    Returns
    -------
    LipDrawing
    """
    from engine.recordings.corpus import frame_points
    from engine.recordings.orientation import anatomical_frame

    dims = int(corpus.dims)
    if frame is None:
        frame = anatomical_frame(corpus)
    if reference is None:
        F = corpus.frames
        mean = np.asarray(F[:min(F.shape[0], 20000)], np.float64).mean(axis=0)
        reference = frame_points(frame.view_frames(mean[None])[0], dims)
    return drawing_of(reference, dims=dims, faces=corpus.faces, roles=corpus.point_roles, names=corpus.point_names,
                      unit=corpus.unit_label, facing_known=frame.source != "none")


def drawing_of(reference, *, dims: int, faces=None, roles=None, names=None, unit: str = "mm",
               facing_known: bool = True) -> LipDrawing:
    """:func:`lip_drawing` from a corpus's parts: ``reference`` (V, 3) a frame in view coordinates, the faces,
    point roles and names, the coordinates' unit, and whether the talker's frame is known (a profile then
    shows the face direction)."""
    ref = np.asarray(reference, np.float64)
    V = int(ref.shape[0])
    ref = ref.reshape(V, -1)
    roles = list(roles) if roles is not None else None
    names = list(names) if names is not None else None
    view = "profile" if int(dims) == 2 else "front"
    forward = (1.0, 0.0) if int(dims) == 2 and facing_known else None
    upper = np.asarray([i for i, r in enumerate(roles or []) if r == "upper_lip"], np.int64)
    lower = np.asarray([i for i, r in enumerate(roles or []) if r == "lower_lip"], np.int64)
    if not (upper.size and lower.size):
        upper = lower = np.zeros(0, np.int64)
    faces = None if faces is None or not len(faces) else np.asarray(faces, np.int64)
    no_labels = ("",) * V
    if faces is not None:
        what = "the measured lip surface" + (", the aperture as a segment" if upper.size else "")
        return LipDrawing("surface", view, unit, no_labels, np.ones(V, bool), np.zeros((0, 2), np.int64), upper,
                          lower, faces, forward, what)
    if roles is not None:
        lip = np.asarray([r in LIP_ROLES for r in roles], bool)
    else:
        lip = np.ones(V, bool)
    if V > MAX_SENSORS or (roles is None and names is None):
        what = f"{V} points as markers" + (" and the aperture" if upper.size else "")
        return LipDrawing("points", view, unit, no_labels, lip, np.zeros((0, 2), np.int64), upper, lower, None,
                          forward, what)
    labels = []
    for i in range(V):
        name = names[i] if names is not None else ""
        labels.append(name or ROLE_LABELS.get(roles[i] if roles else "", ""))
    segments = _segments(ref, np.flatnonzero(lip), roles)
    n_lip = int(lip.sum())
    what = (f"{V} sensor{'s' * (V != 1)} as measured: the {n_lip} lip sensor{'s' * (n_lip != 1)} joined by straight "
            "segments" + (", the lip aperture as a labelled segment" if upper.size else "")
            + (", seen in profile (midsagittal)" if view == "profile" else ""))
    return LipDrawing("sensors", view, unit, tuple(labels), lip, segments, upper, lower, None, forward, what)
