"""A parametric 3D lip surface driven by six articulatory controls.

The surface is two grids of ``rows x cols`` points, the upper and the lower lip. Row 0
of each grid is the inner lip contour (where the lips meet), the next rows cross the
vermilion (the red of the lip) to the vermilion border, and the outer rows are the
surrounding skin (up to the nose base above, down towards the chin below). Columns
run from the left cheek through the left corner (commissure), across the mouth, to the
right corner and cheek; the skin beyond the corners is part of both grids, where the
inner contours of the two lips coincide.

Coordinates are millimetres: x to the talker's left-right, y up, z forward (out of
the face). The lips meet at y = 0 at rest.

The controls, each about 0..1 (see :data:`CONTROL_NAMES`):

``jaw``          jaw opening: the lower lip and chin go down (up to ~14.4 mm) and back,
                 the upper lip goes up a little (~3.6 mm); the largest motion of the
                 surface.
``round``        rounding / protrusion: the mouth narrows (corners move in by ~16 %) and
                 the lips push forward (~3.5 mm) and thicken.
``spread``       spreading: the corners move out (~8 %) and back, the lips thin.
``raise``        upper-lip raise: the upper lip goes up (~3.4 mm either side of the
                 philtrum, half that on the midline) and everts.
``closure``      bilabial closure: the lips meet and press together (contact, then
                 compression that thins the vermilion), whatever the jaw does. The lips
                 share the closing as they share the opening (lower lip 80 %, upper
                 20 %), and the skin below the lower lip follows its rise, fading to
                 nothing at the chin.
``labiodental``  the lower lip moves up and back under the upper teeth (/f v/).

The inner-lip gap is kept non-negative with a soft contact (a softplus of width
0.3 mm), so the lips never pass through each other and the aperture is a smooth,
strictly monotone function of how hard they are pushed together.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CONTROL_NAMES", "RESOLUTIONS", "LipModel"]

CONTROL_NAMES = ("jaw", "round", "spread", "raise", "closure", "labiodental")

#: Named resolutions: (rows per lip, columns). Points = 2 * rows * cols.
RESOLUTIONS = {
    "small": (6, 13),      # 156 points, for tests
    "default": (12, 25),   # 600 points
    "paper": (30, 71),     # 4,260 points = 12,780 coordinates (paper: 4,261 / 12,784)
}

# geometry (mm)
_W = 25.0          # half-width of the mouth (corner to centre) at rest
_WS = 36.0         # half-width of the grid (skin beyond the corners)
_TV = 0.4          # row parameter of the vermilion border
_HV = (8.0, 10.0)  # vermilion height (upper, lower)
_HS = (12.0, 16.0)  # skin height beyond the vermilion (upper to nose base, lower to chin)
_G0 = 2.0          # inner gap at rest
_GJ = 18.0         # inner gap added by full jaw opening
_GR = 4.0          # upper-lip raise
_KC = 3.0          # compression depth of full closure
_WR = 0.16         # mouth narrowing by full rounding (fraction of the width)
_WSP = 0.08        # mouth widening by full spreading
_PR = 3.5          # protrusion by full rounding
_EPS = 0.3         # soft-contact width
_JU = 0.2          # share of the opening (and of the closing) carried by the upper lip
_VR = 0.08         # vermilion thickening (eversion) by full rounding
_VS = 0.08         # vermilion thinning by full spreading
_RMID = 0.5        # upper-lip raise on the midline relative to its lateral peak


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


class LipModel:
    """The lip surface at a given resolution.

    Parameters
    ----------
    resolution : {"small", "default", "paper"} or (rows, cols)
        Rows per lip and columns; ``cols`` odd puts a column on the midline.

    Attributes
    ----------
    rows, cols : int
    n_points : int
        ``2 * rows * cols``.
    rest_vertices : ndarray of shape (n_points, 3)
        The surface with all controls at 0 (upper lip first, row-major).
    faces : ndarray of shape (n_faces, 3)
        Triangles over the points.
    point_names : list of str
        ``"U03_12"`` = upper lip, row 3, column 12 (``L`` for the lower lip).
    midline : tuple of int
        Indices of the upper and lower inner-contour points on the midline.
    """

    def __init__(self, resolution="default"):
        if isinstance(resolution, str):
            if resolution not in RESOLUTIONS:
                raise ValueError(f"unknown resolution {resolution!r}; use one of {sorted(RESOLUTIONS)} or (rows, cols)")
            rows, cols = RESOLUTIONS[resolution]
        else:
            rows, cols = (int(v) for v in resolution)
        if rows < 3 or cols < 5:
            raise ValueError(f"resolution (rows={rows}, cols={cols}) too coarse; need rows >= 3 and cols >= 5")
        self.rows, self.cols = rows, cols
        self.n_points = 2 * rows * cols
        # columns: x from -WS to WS; rows: t in [0, 1], denser near the inner contour
        self._x = np.linspace(-_WS, _WS, cols)
        self._t = np.linspace(0.0, 1.0, rows) ** 1.4
        x, t = self._x, self._t
        ax = np.abs(x) / _W
        self._e = np.clip(1.0 - ax ** 2, 0.0, None) ** 0.6                  # opening shape (cols,)
        self._er = self._e * (_RMID + (1 - _RMID) * 2.0 * ax)               # upper-lip raise profile (cols,)
        self._m = 1.0 / (1.0 + np.exp((np.abs(x) - _W) / 3.0))              # mouth weight (cols,)
        self._jb = np.exp(-(np.clip(np.abs(x) - 0.8 * _W, 0, None) / 10.0) ** 2)  # jaw footprint
        self._vt = 0.35 + 0.65 * np.clip(1.0 - ax ** 2, 0.0, None) ** 0.5    # vermilion taper (cols,)
        self._face_z = -0.012 * x ** 2                                       # face curvature (cols,)
        tv = np.minimum(t, _TV) / _TV                                         # 0..1 across vermilion
        ts = np.clip(t - _TV, 0, None) / (1 - _TV)                            # 0..1 across skin
        self._tv, self._ts = tv, ts
        self._prot = np.exp(-ts / 0.3)                                        # protrusion falloff
        self._follow = 1.0 - _smoothstep(t / 0.9)                             # lip-local motion falloff
        # depth profile of a lip from inner contour outwards: curls in, bulges, recedes
        self._bulge = -2.0 + 4.5 * np.exp(-((t - 0.15) / 0.16) ** 2) - 2.5 * ts
        mid = cols // 2
        self.midline = (0 * rows * cols + mid, 1 * rows * cols + mid)
        self._A = self._coefficients()
        self.rest_vertices = self._assemble(self._fields(np.zeros((1, 6))))[0].reshape(-1, 3)
        self.faces = self._make_faces()
        self.point_names = [f"{lip}{r:02d}_{c:02d}" for lip in "UL" for r in range(rows) for c in range(cols)]

    # ---------------------------------------------------------------- topology
    def _make_faces(self) -> np.ndarray:
        R, C = self.rows, self.cols
        r, c = np.meshgrid(np.arange(R - 1), np.arange(C - 1), indexing="ij")
        a = (r * C + c).ravel()
        b, d, e = a + 1, a + C, a + C + 1
        one = np.concatenate([np.stack([a, b, e], 1), np.stack([a, e, d], 1)])
        lower = one[:, ::-1] + R * C  # rows run downwards on the lower lip: flip winding
        return np.concatenate([one, lower]).astype(np.int64)  # both lips face forward (+z)

    # -------------------------------------------------------------- deformation
    def _inner(self, c):
        """Inner-contour heights, compression and the lower lip's rise towards contact
        (relative to where the jaw alone puts it), each (n, cols)."""
        jaw, rnd, spr, rai, clo, lab = (c[:, k:k + 1] for k in range(6))
        e = self._e[None, :]
        up_nom = e * (0.5 * _G0 + _JU * _GJ * jaw + 1.5 * lab) + _GR * self._er[None, :] * rai
        low_nom = -e * (0.5 * _G0 + (1 - _JU) * _GJ * jaw)
        low_nom = (1 - lab) * low_nom + lab * (up_nom - 2.0 * e)
        g_nom = up_nom - low_nom
        yc = low_nom + (1 - _JU) * g_nom
        g_raw = g_nom * (1 - clo) - clo * _KC * e
        eps = _EPS * e + 1e-3
        g = eps * np.logaddexp(0.0, g_raw / eps)
        comp = g - g_raw                                   # >= 0, ~0 when the lips are apart
        low = yc - (1 - _JU) * g
        return yc + _JU * g, low, comp, low - low_nom

    def aperture(self, controls) -> np.ndarray:
        """Vertical distance between the inner lips on the midline (mm), shape (n,).

        Equals ``y(upper midline inner point) - y(lower midline inner point)`` of
        :meth:`deform` exactly (noise-free).
        """
        c = self._check(controls)
        mid = self.cols // 2
        up, low, _, _ = self._inner(c[:, :6])
        return (up[:, mid] - low[:, mid]).astype(np.float64)

    def _check(self, controls) -> np.ndarray:
        c = np.asarray(controls, dtype=np.float64)
        if c.ndim == 1:
            c = c[None, :]
        if c.ndim != 2 or c.shape[1] != 6:
            raise ValueError(
                f"controls must have shape (n_frames, 6) in the order {CONTROL_NAMES}, got {c.shape}"
            )
        if not np.isfinite(c).all():
            raise ValueError("controls contain NaN or inf")
        return c

    # The surface is linear in a few per-(frame, column) fields: F[n, k, c] with k over
    # _FIELDS. _assemble() is the readable elementwise formula; since it is linear in the
    # fields, probing it with unit fields once gives a coefficient tensor A (cols, K, 6*rows)
    # and deform() is then one batched matrix product per block of frames.
    _FIELDS = ("one", "x", "up_in", "low_in", "comp", "vfac", "jaw", "round", "spread", "raise", "labiodental", "rise")

    def _fields(self, c):
        """Fields (n, K, cols) of controls ``c`` (n, 6)."""
        n = c.shape[0]
        jaw, rnd, spr, rai, clo, lab = (c[:, k:k + 1] for k in range(6))
        up_in, low_in, comp, rise = self._inner(c)
        wscale = 1.0 - _WR * rnd + _WSP * spr
        fx = self._x[None, :] * (1.0 + (wscale - 1.0) * self._m[None, :])
        vfac = 1.0 + _VR * rnd - _VS * spr
        F = np.empty((n, len(self._FIELDS), self.cols))
        for k, f in enumerate((1.0, fx, up_in, low_in, comp, vfac, jaw, rnd, spr, rai, lab, rise)):
            F[:, k, :] = f
        return F

    def _assemble(self, F):
        """Points (n, 2, rows, cols, 3) from fields (n, K, cols); elementwise, linear in F."""
        one, fx, up_in, low_in, comp, vfac, jaw, rnd, spr, rai, lab, rise = (F[:, k, None, :] for k in range(F.shape[1]))
        x = self._x[None, None, :]
        m = self._m[None, None, :]
        tv, ts = self._tv[None, :, None], self._ts[None, :, None]
        prot, fol = self._prot[None, :, None], self._follow[None, :, None]
        vt = self._vt[None, None, :]
        out = np.empty((F.shape[0], 2, self.rows, self.cols, 3))
        z_common = one * (self._face_z[None, None, :] + self._bulge[None, :, None] * (0.6 + 0.4 * m)) \
            + _PR * rnd * prot * m - 2.0 * spr * (x / _W) ** 2 * m
        # upper lip: lip-local motion fades towards the nose base (fol: 1 -> 0 across the rows)
        y_rest = _HV[0] * vt * tv + _HS[0] * ts
        out[:, 0, ..., 0] = fx
        out[:, 0, ..., 1] = fol * (up_in + _HV[0] * vt * tv * (vfac - 0.12 * comp) + _HS[0] * ts * one) \
            + (1 - fol) * (y_rest * one + 0.15 * _GR * rai * m)
        out[:, 0, ..., 2] = z_common + (rai + 0.4 * comp) * prot * m
        # lower lip: the lip follows its inner contour, the chin follows the jaw rigidly; the
        # skin between them also takes the lip's own rise towards contact (mentalis), fading
        # linearly to nothing at the chin
        jaw_drop = (1 - _JU) * _GJ * jaw * self._jb[None, None, :]
        out[:, 1, ..., 0] = fx
        out[:, 1, ..., 1] = fol * (low_in - _HV[1] * vt * tv * (vfac - 0.12 * comp - 0.3 * lab) - _HS[1] * ts * one) \
            + (1 - fol) * (-(_HV[1] * vt * tv + _HS[1] * ts) * one - jaw_drop + (1 - ts) * rise)
        out[:, 1, ..., 2] = z_common + 0.4 * comp * prot * m - 0.25 * jaw_drop * (0.3 + 0.7 * ts) \
            - 5.0 * lab * (1.0 - tv) * fol * m
        return out

    def _coefficients(self):
        K, R, C = len(self._FIELDS), self.rows, self.cols
        probe = np.zeros((K, K, C))
        probe[np.arange(K), np.arange(K), :] = 1.0
        P = self._assemble(probe)                       # (K, 2, R, C, 3)
        return np.ascontiguousarray(P.transpose(3, 0, 1, 2, 4).reshape(C, K, 6 * R)).astype(np.float32)

    def deform(self, controls, *, out=None, chunk=None) -> np.ndarray:
        """Surface points for each row of controls.

        Parameters
        ----------
        controls : array-like of shape (n_frames, 6)
            Columns in the order of :data:`CONTROL_NAMES`.
        out : ndarray of shape (n_frames, 3 * n_points) float32, optional
            Written in place if given.
        chunk : int or None
            Frames per block; by default about 2 million coordinates per block, which
            bounds temporary memory and keeps the transposed writes cache-friendly.

        Returns
        -------
        ndarray of shape (n_frames, 3 * n_points) float32
            Coordinates interleaved per point (x0, y0, z0, x1, ...), upper lip first,
            then row-major over (row, column).
        """
        c = self._check(controls)
        n, R, C = c.shape[0], self.rows, self.cols
        if out is None:
            out = np.empty((n, 3 * self.n_points), dtype=np.float32)
        if chunk is None:
            chunk = max(16, 2_000_000 // (3 * self.n_points))
        for s in range(0, n, chunk):
            blk = c[s:s + chunk]
            Ft = np.ascontiguousarray(self._fields(blk).transpose(2, 0, 1), dtype=np.float32)  # (C, b, K)
            P = np.matmul(Ft, self._A).reshape(C, len(blk), 2, R, 3)
            out[s:s + len(blk)].reshape(len(blk), 2, R, C, 3)[...] = P.transpose(1, 2, 3, 0, 4)
        return out
