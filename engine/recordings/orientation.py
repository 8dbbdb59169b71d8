"""The talker's anatomical frame: which way is up, left and forward in a corpus's coordinates.

Recording systems put their axes anywhere: an articulograph may give x anterior, y lateral,
z vertical; another x lateral, y anterior, z down; a 2-D mid-sagittal system x and y in
the sagittal plane. A view that shows the data's x-y plane then shows the lips from above
or from the side, rotated or mirrored. :func:`anatomical_frame` finds the talker's own
directions from the point roles on a reference frame (the mean shape):

* **up**: from the lower lip's points to the upper lip's;
* **left**: from the talker's right mouth corner to the left one (one corner: from the
  mid-line of the lips to it), made perpendicular to up;
* **forward** (out of the mouth, towards a viewer facing the talker): left x up in a
  right-handed system. Recording systems can be left-handed (one axis mirrored), so the
  sign is checked against the anatomy: the lips' mid-line points lie in front of the mouth
  corners (the lips curve round the teeth), and the jaw and tongue sensors behind the lips.
  When a cue says the cross product points backwards, the data are mirrored and the frame
  says so (determinant -1).

Without corners, left follows from up and forward (forward from the jaw / tongue points);
with one corner, its offset along that forward direction (it lies behind the lips too) is
left out of left.
2-D (mid-sagittal) data get a profile frame: forward and up.

A derived direction within 30 degrees of a coordinate axis is snapped to it, so data whose
axes are already anatomical are shown along their own axes (only permuted or flipped).
When the roles cannot give the frame, ``lipspace import --axes x=forward,y=left,z=up``
states it (``Corpus.axes``, :func:`parse_axes`); failing both, the views keep the data's
axes and say so (:attr:`AnatomicalFrame.source` ``"none"``).

The frame maps data points to **view coordinates**: x towards the viewer's right (the
talker's left: a front view, as a camera sees a face), y up, z towards the viewer (3-D);
x forward, y up (2-D, the profile facing right). The lip view, the lip-shape figures and the
MP4 and glTF exports draw points in these coordinates (glTF's own convention: +Y up, the
asset facing +Z, its left +X).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["AnatomicalFrame", "anatomical_frame", "parse_axes", "AxesError", "DIRECTIONS", "SNAP_DEGREES"]

#: a derived direction this close to a coordinate axis (degrees) is snapped to it
SNAP_DEGREES = 30.0
#: anatomical direction words -> (view axis name, sign); synonyms accepted by --axes
DIRECTIONS = {"left": ("left", 1), "right": ("left", -1), "up": ("up", 1), "down": ("up", -1),
              "superior": ("up", 1), "inferior": ("up", -1), "forward": ("forward", 1), "anterior": ("forward", 1),
              "front": ("forward", 1), "back": ("forward", -1), "backward": ("forward", -1),
              "posterior": ("forward", -1)}
_VIEW_AXES = {3: ("left", "up", "forward"), 2: ("forward", "up")}
_NAMES = "xyz"
#: a posterior cue must be at least this fraction of the lip height to decide handedness
_CUE_MIN = 0.05


class AxesError(ValueError):
    """An ``--axes`` specification that cannot be used."""


@dataclass(frozen=True)
class AnatomicalFrame:
    """Data coordinates -> view coordinates (see the module docstring).

    Attributes
    ----------
    matrix : ndarray of shape (dims, dims)
        Rows: the view axes (3-D: talker's left, up, forward; 2-D: forward, up) in data
        coordinates, unit length, orthogonal. ``view = data @ matrix.T``.
    source : {"roles", "axes", "none"}
        Derived from the point roles, stated by the corpus (``Corpus.axes``: ``import --axes``, the
        synthetic talker's own), or not known (identity).
    note : str
        How it was found (or why not), in words.
    """

    matrix: np.ndarray
    source: str
    note: str

    @property
    def dims(self) -> int:
        return int(self.matrix.shape[0])

    @property
    def mirrored(self) -> bool:
        """True when the data's axes are left-handed against the talker (the map includes a reflection)."""
        return bool(np.linalg.det(self.matrix) < 0)

    def view(self, points) -> np.ndarray:
        """Points ``(..., dims)`` or flat frames ``(..., dims * V)`` in view coordinates, same shape, float64."""
        P = np.asarray(points, dtype=np.float64)
        d = self.dims
        flat = P.shape[-1] % d == 0 and P.shape[-1] != d
        Q = P.reshape(P.shape[:-1] + (-1, d)) if flat else P
        out = Q @ self.matrix.T
        return out.reshape(P.shape) if flat else out

    def view_frames(self, frames) -> np.ndarray:
        """Flat frames ``(n, dims * V)`` in view coordinates, float32 (for drawing and exports)."""
        F = np.asarray(frames)
        return self.view(F.reshape(F.shape[0], -1, self.dims)).reshape(F.shape).astype(np.float32)

    def axes_text(self) -> str:
        """Which data axis points where: ``x = forward, y = left, z = up`` (signed, or mixed when oblique)."""
        words = {"left": ("left", "right"), "up": ("up", "down"), "forward": ("forward", "back")}
        parts = []
        for j in range(self.dims):
            col = self.matrix[:, j]  # data axis j in view coordinates
            k = int(np.argmax(np.abs(col)))
            pos, neg = words[_VIEW_AXES[self.dims][k]]
            w = pos if col[k] > 0 else neg
            off = "" if abs(col[k]) > 0.999 else f" ({np.degrees(np.arccos(min(1.0, abs(col[k])))):.0f} deg off)"
            parts.append(f"{_NAMES[j]} = {w}{off}")
        return ", ".join(parts)

    def describe(self) -> str:
        """One line for ``lipspace info``."""
        if self.source == "none":
            return f"not known ({self.note}); views show the data's x right, y up"
        mirror = ("; the data's axes are mirrored (left-handed): views undo it" if self.mirrored and self.dims == 3
                  else "")
        return f"{self.axes_text()} ({self.note}){mirror}"

    def spec(self) -> str:
        """The ``--axes`` text of this frame (snapped to the nearest axes)."""
        words = {"left": ("left", "right"), "up": ("up", "down"), "forward": ("forward", "back")}
        out = []
        for j in range(self.dims):
            col = self.matrix[:, j]
            k = int(np.argmax(np.abs(col)))
            pos, neg = words[_VIEW_AXES[self.dims][k]]
            out.append(f"{_NAMES[j]}={pos if col[k] > 0 else neg}")
        return ",".join(out)


def identity(dims: int, note: str) -> AnatomicalFrame:
    return AnatomicalFrame(np.eye(dims), "none", note)


def parse_axes(spec: str, dims: int) -> AnatomicalFrame:
    """An ``--axes`` specification as a frame: ``x=forward,y=left,z=up`` (3-D) or ``x=forward,y=up`` (2-D).

    Each data axis gets one direction word (left/right, up/down, forward/back and the
    synonyms of :data:`DIRECTIONS`); every view axis must be named exactly once.

    Raises
    ------
    AxesError
        Naming what is wrong and what is expected.
    """
    dims = int(dims)
    need = _VIEW_AXES[dims]
    example = "x=forward,y=left,z=up" if dims == 3 else "x=forward,y=up"
    text = str(spec).strip().lower().replace(" ", "")
    items = [t for t in text.split(",") if t]
    got = {}
    for it in items:
        if "=" not in it:
            raise AxesError(f"--axes {spec!r}: {it!r} is not AXIS=DIRECTION; expected e.g. {example}")
        ax, word = it.split("=", 1)
        if ax not in _NAMES[:dims]:
            raise AxesError(f"--axes {spec!r}: axis {ax!r}; the data have {dims} axes ({', '.join(_NAMES[:dims])})")
        if word not in DIRECTIONS:
            raise AxesError(f"--axes {spec!r}: direction {word!r}; expected one of "
                            f"{', '.join(sorted(DIRECTIONS))}")
        if ax in got:
            raise AxesError(f"--axes {spec!r}: axis {ax} is given twice")
        got[ax] = DIRECTIONS[word]
    if sorted(got) != list(_NAMES[:dims]):
        raise AxesError(f"--axes {spec!r}: give a direction for each of the {dims} axes, e.g. {example}")
    views = [v for v, _ in got.values()]
    if sorted(views) != sorted(need):
        raise AxesError(f"--axes {spec!r}: the directions must cover {', '.join(need)} once each "
                        f"({'left/right, ' if dims == 3 else ''}up/down, forward/back), e.g. {example}")
    M = np.zeros((dims, dims))
    for j, ax in enumerate(_NAMES[:dims]):
        v, sign = got[ax]
        M[need.index(v), j] = sign
    return AnatomicalFrame(M, "axes", f"stated by the corpus: {AnatomicalFrame(M, 'axes', '').spec()}, "
                           "as import --axes sets it")


def _unit(v):
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-12 else None


def _snap(M):
    """``M`` snapped to a signed permutation when every row is within :data:`SNAP_DEGREES` of an axis."""
    cos = np.cos(np.radians(SNAP_DEGREES))
    k = np.argmax(np.abs(M), axis=1)
    if len(set(k.tolist())) != len(k) or not np.all(np.abs(M[np.arange(len(k)), k]) >= cos):
        return M, False
    S = np.zeros_like(M)
    S[np.arange(len(k)), k] = np.sign(M[np.arange(len(k)), k])
    return S, True


def anatomical_frame(corpus, mean=None) -> AnatomicalFrame:
    """The talker's frame of ``corpus`` (see the module docstring).

    Parameters
    ----------
    corpus : Corpus
        Its ``axes`` (given on import) win; else its ``point_roles`` are used.
    mean : ndarray of shape (dims * V,), optional
        Reference frame (e.g. a manifold's ``shape_.mean_``); default: the mean of the
        corpus's first 20,000 frames.

    Returns
    -------
    AnatomicalFrame
    """
    dims = int(corpus.dims)
    if getattr(corpus, "axes", ""):
        return parse_axes(corpus.axes, dims)
    roles = corpus.point_roles
    if roles is None:
        return identity(dims, "the corpus names no point roles; give them with import --layout or --roles, or "
                        "state the axes with import --axes")
    if mean is None:
        F = corpus.frames
        mean = np.asarray(F[:min(F.shape[0], 20000)], dtype=np.float64).mean(axis=0)
    P = np.asarray(mean, dtype=np.float64).reshape(-1, dims)

    def centroid(*names):
        idx = [i for i, r in enumerate(roles) if r in names]
        return P[idx].mean(axis=0) if idx else None

    ul, ll = centroid("upper_lip"), centroid("lower_lip")
    if ul is None or ll is None:
        return identity(dims, "the corpus names no upper_lip and lower_lip points; state the axes with import "
                        "--axes")
    up = _unit(ul - ll)
    if up is None:
        return identity(dims, "the upper and lower lip points coincide on the mean frame")
    mid = 0.5 * (ul + ll)
    height = float(np.linalg.norm(ul - ll))
    back_pts = centroid("jaw", "tongue")
    if dims == 2:
        fwd = np.array([up[1], -up[0]])  # up turned clockwise
        how = "from the roles: upper lip above lower lip"
        if back_pts is not None and abs((mid - back_pts) @ fwd) >= _CUE_MIN * height:
            fwd = fwd * np.sign((mid - back_pts) @ fwd)
            how += ", jaw / tongue behind the lips"
        else:
            how += "; forward taken as the data's own (no jaw or tongue point behind the lips)"
        M, snapped = _snap(np.vstack([fwd, up]))
        return AnatomicalFrame(M, "roles", how + (", snapped to the data's axes" if snapped else ""))
    left_c, right_c = centroid("left_corner"), centroid("right_corner")
    if left_c is not None and right_c is not None:
        lat = left_c - right_c
    elif left_c is not None:
        lat = left_c - mid
    elif right_c is not None:
        lat = mid - right_c
    else:
        lat = None
    corners = [c for c in (left_c, right_c) if c is not None]
    how = "from the roles: upper lip above lower lip"
    if lat is not None:
        lat = lat - (lat @ up) * up
        if len(corners) == 1 and back_pts is not None:  # one corner lies behind the lips too: keep its side only
            f0 = _unit((mid - back_pts) - ((mid - back_pts) @ up) * up)
            if f0 is not None:
                lat = lat - (lat @ f0) * f0
        lat = _unit(lat)
    if lat is None:  # no corner: forward from the points behind the lips, left from up and forward
        if back_pts is None:
            return identity(3, "the roles name no mouth corner and no jaw or tongue point, so left and forward "
                            "cannot be told; state the axes with import --axes")
        fwd = _unit((mid - back_pts) - ((mid - back_pts) @ up) * up)
        if fwd is None:
            return identity(3, "the jaw / tongue points lie straight below the lips; state the axes with import --axes")
        lat = np.cross(up, fwd)
        how += ", jaw / tongue behind the lips (no mouth corner)"
    else:
        fwd = np.cross(lat, up)  # right-handed data
        how += ", corners left and right"
        # handedness: the lips' mid-line lies in front of the corners, the jaw and tongue behind the lips
        cue, what = 0.0, ""
        if corners:
            c = mid - np.mean(corners, axis=0)
            cue, what = float(c @ fwd), "lips in front of the corners"
        if abs(cue) < _CUE_MIN * height and back_pts is not None:
            cue, what = float((mid - back_pts) @ fwd), "jaw / tongue behind the lips"
        if abs(cue) >= _CUE_MIN * height:
            how += f", {what}"
            if cue < 0:  # left-handed recording: the anatomy, not the cross product, says where forward is
                fwd = -fwd
        else:
            how += "; facing taken from a right-handed system (no cue for front and back)"
    M, snapped = _snap(np.vstack([lat, up, fwd]))
    return AnatomicalFrame(M, "roles", how + (", snapped to the data's axes" if snapped else ""))
