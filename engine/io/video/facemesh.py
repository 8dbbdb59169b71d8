"""MediaPipe FaceMesh landmarks: the lip subset, the rigid reference subset, the lip mesh.

FaceMesh (``refine_landmarks=True``) returns 478 landmarks per face. Its lip refinement
model re-estimates 80 of them, published in MediaPipe's
``tensors_to_face_landmarks_with_attention.pbtxt`` as four closed rings around the mouth:
the outer contour (the lip/skin border), a semi-outer ring, a semi-inner ring and the
inner contour (the mouth opening). Each ring is listed as its lower half from the right
mouth corner to the left one (11 points) and its upper half without the corners
(9 points). The outer and inner rings are the 40 points of ``FACEMESH_LIPS``; the two
rings between them cover the vermilion. :data:`LIP_POINTS` keeps all 80 (ring by ring,
outer first) and :data:`LIP_FACES` triangulates the three bands between consecutive rings:
both contours and the vermilion between them, the mouth opening left open.

:data:`REFERENCE_POINTS` are landmarks that move with the skull, not with speech:
forehead, nose bridge, temples and eye corners (never jaw, cheeks, lips or brows).
Head pose is fitted to them (:mod:`engine.recordings.headpose`).

Only :class:`FaceTracker` needs ``mediapipe`` (the ``[video]`` extra), imported when
one is made; :func:`require_mediapipe` raises the one-line install hint when it is missing.
MediaPipe's C++ start-up messages (TensorFlow Lite's delegate line, absl's log lines),
written straight to file descriptor 2 while a tracker starts, are not for the user: that
descriptor goes to the null device from the tracker's creation to the end of its first
frame (``LIPSPACE_NATIVE_LOGS=1`` keeps them, for debugging).
"""
from __future__ import annotations

import os
import sys
import warnings

import numpy as np

__all__ = ["LIP_RINGS", "LIP_POINTS", "LIP_NAMES", "LIP_FACES", "LIP_ROLES", "REFERENCE_POINTS", "EYE_CORNERS",
           "TRACKED_POINTS", "FaceTracker", "require_mediapipe", "MissingExtraError", "to_metric"]

_INSTALL = "pip install -e '.[video]'"


class MissingExtraError(ImportError, ValueError):
    """The optional ``[video]`` extra (mediapipe) is not installed (a ValueError too, so every
    command line and loader that reports bad input reports it as one line)."""


#: the lip refinement rings, each (lower half corner-to-corner, then upper half without corners)
LIP_RINGS = {
    "outer": (61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291,
              185, 40, 39, 37, 0, 267, 269, 270, 409),
    "semi_outer": (76, 77, 90, 180, 85, 16, 315, 404, 320, 307, 306,
                   184, 74, 73, 72, 11, 302, 303, 304, 408),
    "semi_inner": (62, 96, 89, 179, 86, 15, 316, 403, 319, 325, 292,
                   183, 42, 41, 38, 12, 268, 271, 272, 407),
    "inner": (78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308,
              191, 80, 81, 82, 13, 312, 311, 310, 415),
}
_RING_ORDER = ("outer", "semi_outer", "semi_inner", "inner")


#: positions 0..19 of a ring in walking order round the mouth (lower half 0..10, upper half back 19..11)
_RING_CYCLE = tuple(range(11)) + tuple(range(19, 10, -1))


#: the 80 FaceMesh indices kept per frame, ring by ring (outer, semi-outer, semi-inner, inner)
LIP_POINTS = tuple(i for name in _RING_ORDER for i in LIP_RINGS[name])
#: point names ``<ring>_<facemesh index>``
LIP_NAMES = tuple(f"{name}_{i}" for name in _RING_ORDER for i in LIP_RINGS[name])


def _roles():
    roles = []
    for name in _RING_ORDER:
        for k in range(20):
            if k == 0:
                roles.append("right_corner" if name == "outer" else "lip")
            elif k == 10:
                roles.append("left_corner" if name == "outer" else "lip")
            elif k == 5 and name in ("outer", "inner"):
                roles.append("lower_lip")
            elif k == 15 and name in ("outer", "inner"):
                roles.append("upper_lip")
            else:
                roles.append("lip")
    return tuple(roles)


#: roles of :data:`LIP_POINTS` (:data:`engine.recordings.layouts.ROLES`): the outer corners, the
#: lower/upper lip mid-points of both contours (indices 17/0 and 14/13), "lip" otherwise
LIP_ROLES = _roles()


def _faces():
    cyc = _RING_CYCLE
    tris = []
    for b in range(3):  # bands outer|semi-outer, semi-outer|semi-inner, semi-inner|inner
        a0, b0 = 20 * b, 20 * (b + 1)
        for k in range(20):
            i, j = cyc[k], cyc[(k + 1) % 20]
            p, q, r, s = a0 + i, a0 + j, b0 + j, b0 + i
            tris.append((p, q, r))
            tris.append((p, r, s))
    return np.asarray(tris, dtype=np.int64)


#: (120, 3) triangles over :data:`LIP_POINTS` (positions in that tuple)
LIP_FACES = _faces()

#: rigid reference landmarks: forehead (10, 151, 9, 108, 337), nose bridge (8, 168, 6, 197),
#: temples (54, 284, 127, 356), eye corners (33, 133, 362, 263)
REFERENCE_POINTS = (10, 151, 9, 108, 337, 8, 168, 6, 197, 54, 284, 127, 356, 33, 133, 362, 263)
#: (outer, inner) corners of the eye on the image's left, then of the eye on its right
EYE_CORNERS = ((33, 133), (263, 362))
#: every FaceMesh index the importer keeps per frame: lips, then reference points
TRACKED_POINTS = LIP_POINTS + REFERENCE_POINTS


def require_mediapipe():
    """Import and return ``mediapipe``; :class:`MissingExtraError` with the install line when absent."""
    try:
        import mediapipe  # noqa: F401
        from mediapipe.python.solutions import face_mesh
    except ImportError as exc:
        raise MissingExtraError(f"video import needs the optional video extra (mediapipe, not installed: {exc}); "
                                f"install it with: {_INSTALL}") from None
    return face_mesh


def to_metric(lm, width: int, height: int) -> np.ndarray:
    """FaceMesh normalised landmarks (n, 3) -> isotropic pixel units, x right, y up, z toward the camera.

    FaceMesh gives x / width and y / height in [0, 1] (y down) and z in units of the
    image width (smaller = nearer the camera).
    """
    lm = np.asarray(lm, dtype=np.float64)
    out = np.empty_like(lm)
    out[..., 0] = lm[..., 0] * width
    out[..., 1] = -lm[..., 1] * height
    out[..., 2] = -lm[..., 2] * width
    return out


class _QuietNativeStderr:
    """File descriptor 2 sent to the null device until :meth:`stop` (C++ libraries' logs written to it)."""

    def __init__(self):
        self._saved = None
        if os.environ.get("LIPSPACE_NATIVE_LOGS"):
            return
        try:
            sys.stderr.flush()
            saved = os.dup(2)
        except (OSError, ValueError, AttributeError):
            return  # no descriptor 2 to silence
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(null, 2)
            finally:
                os.close(null)
        except OSError:
            os.close(saved)
            return
        self._saved = saved

    def stop(self) -> None:
        if self._saved is None:
            return
        saved, self._saved = self._saved, None
        try:
            os.dup2(saved, 2)
        finally:
            os.close(saved)


class FaceTracker:
    """FaceMesh in video mode (``static_image_mode=False``, refined landmarks, one face).

    ``track(rgb)`` returns the :data:`TRACKED_POINTS` of the face in an RGB frame
    (H, W, 3) uint8 as an (n, 3) float32 array in isotropic pixel units
    (:func:`to_metric`), or None when no face is found. Use as a context manager or call
    :meth:`close`.

    Parameters
    ----------
    min_detection_confidence, min_tracking_confidence : float
        FaceMesh's thresholds (its defaults, 0.5).
    points : sequence of int, optional
        FaceMesh indices to return (default :data:`TRACKED_POINTS`).
    """

    def __init__(self, *, min_detection_confidence: float = 0.5, min_tracking_confidence: float = 0.5,
                 points=TRACKED_POINTS):
        face_mesh = require_mediapipe()
        # mediapipe 0.10.14 calls a protobuf API that protobuf 4.25 deprecates, once per frame
        warnings.filterwarnings("ignore", message=r"SymbolDatabase\.GetPrototype\(\) is deprecated",
                                category=UserWarning)
        self.points = np.asarray(points, dtype=np.int64)
        self._mesh = None
        self._quiet = _QuietNativeStderr()  # until the graph has started: its first frame
        try:
            self._mesh = face_mesh.FaceMesh(static_image_mode=False, max_num_faces=1, refine_landmarks=True,
                                            min_detection_confidence=min_detection_confidence,
                                            min_tracking_confidence=min_tracking_confidence)
        except BaseException:
            self._quiet.stop()
            raise

    def track(self, rgb) -> np.ndarray | None:
        rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
        if rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"frame of shape {rgb.shape}; expected (height, width, 3) RGB")
        if self._mesh is None:
            raise ValueError("the face tracker is closed; make a new one")
        try:
            res = self._mesh.process(rgb)
        finally:
            self._quiet.stop()
        if not res.multi_face_landmarks:
            return None
        lms = res.multi_face_landmarks[0].landmark
        lm = np.array([(lms[i].x, lms[i].y, lms[i].z) for i in self.points], dtype=np.float64)
        return to_metric(lm, rgb.shape[1], rgb.shape[0]).astype(np.float32)

    def close(self) -> None:
        self._quiet.stop()
        if self._mesh is not None:
            self._mesh.close()
            self._mesh = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
