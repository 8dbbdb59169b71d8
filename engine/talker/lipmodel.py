"""A parametric 3D lip surface driven by fourteen articulatory controls and a speaker's anatomy.

The surface is two grids of ``rows x cols`` points, the upper and the lower lip. Row 0
of each grid is the inner lip contour (where the lips meet), the next rows cross the
vermilion (the red of the lip) to the vermilion border, and the outer rows are the
surrounding skin (up to the nose base above, down past the mentolabial sulcus towards
the chin below). Columns run from the left cheek through the left corner
(commissure), across the mouth, to the right corner and cheek; they are denser near
the midline, where the Cupid's bow and the philtrum are. The skin beyond the corners
is part of both grids, where the inner contours of the two lips coincide.

Coordinates are millimetres: x to the talker's left-right, y up, z forward (out of
the face). The lips meet at y = 0 at rest.

Anatomy (:class:`Anatomy`, one per speaker): mouth half-width, vermilion heights,
philtrum length, Cupid's bow (two peaks of the upper vermilion border either side of
a midline notch, under the two philtral columns with the philtral groove between
them), lip thickness (how far the vermilion bulges forward of the inner contour),
the depth of the mentolabial sulcus, the rest gap between the lips and a habitual
left-right asymmetry. The mean values are adult anthropometric norms (Farkas 1994:
mouth width ch-ch about 50 mm, upper vermilion ls-sto about 8 mm, lower sto-li about
9-10 mm, philtrum sn-ls about 12-14 mm and 10 mm wide).

The controls (:data:`CONTROL_NAMES`; the signed ones, :data:`SIGNED_CONTROLS`, about
-1..1, the others about 0..1):

===============  ==========================================================================
``jaw``          jaw opening: the lower lip and chin go down (up to ~14.4 mm) and back,
                 the upper lip goes up a little (~3.6 mm); the largest motion. With
                 ``kinematics="calibrated"`` (see below) the mandible rotates about the
                 condyle (90 mm behind and 40 mm above the lower lip): the lower lip (up to
                 12 mm) and chin go down and back on an arc, more the lower the point; the
                 upper lip goes up by half the lower lip's drop (6 mm); the corners go down
                 by 30 % of it; the vermilion of both lips thins as wide opening stretches
                 it (up to 20 %).
``round``        rounding (orbicularis oris): the mouth narrows (corners in by ~16 %),
                 the opening becomes rounder at the corners, the vermilion thickens,
                 with only a little forward push (1 mm).
``spread``       spreading: the corners move out (~8 %) and back, the lips thin.
``raise``        upper-lip raise (levator labii superioris): the upper lip goes up
                 (~4 mm either side of the philtrum, half that on the midline) and everts.
``closure``      bilabial closure: the lips meet and press together (contact, then
                 compression that thins the vermilion), whatever the jaw does. The lips
                 share the closing as they share the opening (lower lip 80 %, upper
                 20 %), and the skin below the lower lip follows its rise.
``labiodental``  the lower lip moves up and back under the upper teeth (/f v/).
``protrude``     protrusion, separate from rounding: both lips push forward (upper
                 4 mm, lower 5 mm) and evert; the skin follows, fading.
``depress``      lower-lip depression (depressor labii inferioris), independent of
                 the jaw: the lower lip goes down by up to 3 mm and everts.
``corner``       corner raise (+) / lower (-) (zygomaticus / depressor anguli oris):
                 the commissures move up or down by up to 2.5 mm, and back when raised.
``asymmetry``    left-right asymmetry: the talker's left half opens, raises and
                 protrudes up to 15 % more (+) or less (-) than the right; the corners
                 tilt by up to 1 mm. The midline is unchanged.
``jaw_lateral``  lateral jaw shift: the lower lip and chin move sideways up to 1.5 mm.
``jaw_forward``  jaw protrusion (+) / retraction (-), the mandible's translation, which
                 in speech is controlled apart from its rotation: the chin and, less,
                 the lower lip move forward or back by up to 3 mm (``"calibrated"`` only).
``roll``         vermilion eversion (+) / inversion (-) (the lip tissue rolling out or
                 in about the inner contour, orbicularis oris pars marginalis): the
                 visible red lip grows or shrinks by up to 30 % and its border moves
                 forward or back by up to 2 mm; the inner contour is unchanged.
``mentalis``     chin raise (mentalis): the soft tissue of the chin goes up (3 mm) and
                 forward (1.5 mm), the mentolabial sulcus deepens, and the lower
                 vermilion is pushed up and out (1 mm); the inner contour is unchanged.
===============  ==========================================================================

Kinematics (:data:`KINEMATICS`). ``"classic"`` (the default) drops the lower lip almost
straight, gives the upper lip a fifth of the opening and keeps the corners still.
``"calibrated"`` moves the jaw, the upper lip and the corners as articulograph
recordings of real speakers show (docs/DECISIONS.md, F7): the jaw's arc and
protrusion, the upper lip's larger share of the opening, corners that descend with the
jaw, narrow and widen whole (the mouth's width change reaches 95 % at the commissure
instead of 50 %) and slide forward and back over the curved face as they do, the upper
and lower lips moving as one where they meet beyond the corners.

The inner-lip gap is kept non-negative with a soft contact (a softplus of width
0.3 mm), so the lips never pass through each other and the aperture is a smooth,
strictly monotone function of how hard they are pushed together.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

__all__ = ["CONTROL_NAMES", "SIGNED_CONTROLS", "RESOLUTIONS", "KINEMATICS", "Anatomy", "LipModel",
           "vermilion_weight"]

CONTROL_NAMES = ("jaw", "round", "spread", "raise", "closure", "labiodental", "protrude", "depress", "corner",
                 "asymmetry", "jaw_lateral", "jaw_forward", "roll", "mentalis")
#: controls that range over -1..1 (the others over 0..1)
SIGNED_CONTROLS = ("corner", "asymmetry", "jaw_lateral", "jaw_forward", "roll")
_NC = len(CONTROL_NAMES)

#: How the jaw, upper lip and corners move: per kinematics, the upper lip's share of the
#: opening and closing, the corners' descent with the jaw (a fraction of the lower lip's
#: drop), the vermilion's thinning by full opening (times jaw squared), how far beyond the
#: corner (mm) the mouth's width change fades, and whether the jaw turns on an arc (with
#: protrusion, the curved face and corners shared by both lips) instead of dropping straight
KINEMATICS = {
    "classic": {"upper_share": 0.2, "corner_drop": 0.0, "stretch": 0.0, "width_reach": 0.0, "arc": False},
    "calibrated": {"upper_share": 1.0 / 3.0, "corner_drop": 0.3, "stretch": 0.2, "width_reach": 9.0, "arc": True},
}

#: Named resolutions: (rows per lip, columns). Points = 2 * rows * cols.
RESOLUTIONS = {
    "small": (6, 13),      # 156 points, for tests
    "default": (12, 25),   # 600 points
    "paper": (30, 71),     # 4,260 points = 12,780 coordinates (paper: 4,261 / 12,784)
}


@dataclass(frozen=True)
class Anatomy:
    """A speaker's lip anatomy (mm unless stated).

    Parameters
    ----------
    half_width : mouth half-width, centre to corner, at rest.
    upper_vermilion, lower_vermilion : vermilion heights on the midline.
    philtrum : skin height from the upper vermilion border to the nose base.
    chin : skin height below the lower vermilion down the grid's edge.
    bow : height of the Cupid's bow peaks above the midline notch.
    philtrum_width : distance between the two philtral columns (= Cupid's bow peaks).
    thickness : how far the vermilion bulges forward of the inner contour.
    sulcus : depth of the mentolabial sulcus below the lower lip.
    gap : inner-lip gap at rest.
    asymmetry : habitual left-right asymmetry (a fraction; added to the control).
    """

    half_width: float = 25.0
    upper_vermilion: float = 8.0
    lower_vermilion: float = 10.0
    philtrum: float = 12.0
    chin: float = 16.0
    bow: float = 1.6
    philtrum_width: float = 10.0
    thickness: float = 4.5
    sulcus: float = 2.5
    gap: float = 2.0
    asymmetry: float = 0.0

    @classmethod
    def draw(cls, rng, sd: float = 0.08) -> Anatomy:
        """A speaker drawn around the mean: every size times exp(sd * N(0, 1)) (s.d. ``sd``),
        a habitual asymmetry of s.d. 0.1."""
        out = {}
        for f in fields(cls):
            base = f.default
            out[f.name] = (float(0.1 * rng.standard_normal()) if f.name == "asymmetry"
                           else float(base * np.exp(sd * rng.standard_normal())))
        return cls(**out)

    def as_dict(self) -> dict:
        return asdict(self)


# deformation magnitudes (mm or fractions); sources and assumptions in docs/DECISIONS.md, F5
_GJ = 18.0         # inner gap added by full jaw opening
_GR = 4.0          # upper-lip raise
_KC = 3.0          # compression depth of full closure
_WR = 0.16         # mouth narrowing by full rounding (fraction of the width)
_WSP = 0.08        # mouth widening by full spreading
_PRR = 1.0         # forward push by full rounding alone
_PRU, _PRL = 4.0, 5.0  # protrusion of the upper and lower lip by full protrusion
_DEP = 3.0         # lower-lip depression
_COR = 2.5         # corner raise / lower
_ASY = 0.15        # left-right asymmetry of the displacements
_JL = 1.5          # lateral jaw shift
_JF = 3.0          # jaw protrusion / retraction (translation) by full jaw_forward
_PIV_Y, _PIV_Z = 40.0, 90.0  # the jaw's pivot (condyle): above and behind the lower lip's inner midline
_EPS = 0.3         # soft-contact width
_VR = 0.08         # vermilion thickening (eversion) by full rounding
_VP = 0.10         # vermilion eversion by full protrusion
_VS = 0.08         # vermilion thinning by full spreading
_RMID = 0.5        # upper-lip raise on the midline relative to its lateral peak
_RLH = 0.30        # vermilion height change by full eversion / inversion (fraction)
_RLZ = 2.0         # forward / backward motion of the vermilion border by full roll
_MTY, _MTZ = 3.0, 1.5  # chin soft tissue up / forward by full mentalis
_MTL = 1.0         # lower vermilion pushed up and out by full mentalis
_MTS = 0.8         # mentolabial sulcus deepening by full mentalis (fraction of its depth)
_TV = 0.4          # row parameter of the vermilion border


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def vermilion_weight(point_names) -> np.ndarray | None:
    """Per point, 1 on the vermilion and 0 on the skin (a soft edge), from the lip model's
    point names (``"U03_12"``); None when the names are not the lip model's.

    The renderer colours the lips with it.
    """
    if point_names is None or len(point_names) == 0:
        return None
    try:
        rows = np.array([int(n[1:3]) for n in point_names])
        ok = all(n[0] in "UL" and n[3] == "_" and len(n) == 6 for n in point_names)
    except (ValueError, IndexError, TypeError):
        return None
    if not ok:
        return None
    R = rows.max() + 1
    if R < 3:
        return None
    t = (rows / (R - 1)) ** 1.4
    return np.clip((_TV + 0.06 - t) / 0.12, 0.0, 1.0)


class LipModel:
    """The lip surface at a given resolution, for one speaker's anatomy.

    Parameters
    ----------
    resolution : {"small", "default", "paper"} or (rows, cols)
        Rows per lip and columns; ``cols`` odd puts a column on the midline.
    anatomy : Anatomy or None
        The speaker (default: the mean :class:`Anatomy`).
    kinematics : {"classic", "calibrated"}, default="classic"
        How the jaw, upper lip and corners move (:data:`KINEMATICS`).

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
    border_row : int
        The grid row nearest the vermilion border (row 0 is the inner contour).
    corner_column : int
        The grid column nearest the talker's left commissure (+x).
    """

    def __init__(self, resolution="default", anatomy=None, *, kinematics="classic"):
        if isinstance(resolution, str):
            if resolution not in RESOLUTIONS:
                raise ValueError(f"unknown resolution {resolution!r}; use one of {sorted(RESOLUTIONS)} or (rows, cols)")
            rows, cols = RESOLUTIONS[resolution]
        else:
            rows, cols = (int(v) for v in resolution)
        if rows < 3 or cols < 5:
            raise ValueError(f"resolution (rows={rows}, cols={cols}) too coarse; need rows >= 3 and cols >= 5")
        an = Anatomy() if anatomy is None else anatomy
        if not isinstance(an, Anatomy):
            raise ValueError(f"anatomy must be an engine.talker.lipmodel.Anatomy or None, got {type(an).__name__}")
        self.anatomy = an
        if kinematics not in KINEMATICS:
            raise ValueError(f"kinematics must be one of {sorted(KINEMATICS)}, got {kinematics!r}")
        self.kinematics = kinematics
        kin = KINEMATICS[kinematics]
        self._ju, self._kj, self._str, self._arc = kin["upper_share"], kin["corner_drop"], kin["stretch"], kin["arc"]
        # fields the surface depends on: classic has no arc, protrusion, curved-face or corner-drop fields
        self._K = len(self._FIELDS) if self._arc else len(self._FIELDS) - 4
        self.rows, self.cols = rows, cols
        self.n_points = 2 * rows * cols
        W = an.half_width
        self._W = W
        ws = 1.44 * W
        # columns denser near the midline (Cupid's bow, philtrum); rows denser near the inner contour
        u = np.linspace(-1.0, 1.0, cols)
        self._x = ws * (0.45 * u + 0.55 * u ** 3)
        self._t = np.linspace(0.0, 1.0, rows) ** 1.4
        x, t = self._x, self._t
        ax = np.abs(x) / W
        self._e = np.clip(1.0 - ax ** 2, 0.0, None) ** 0.6                  # opening shape (cols,)
        self._er = self._e * (_RMID + (1 - _RMID) * 2.0 * np.minimum(ax, 1.0))  # upper-lip raise profile
        self._m = 1.0 / (1.0 + np.exp((np.abs(x) - W) / 3.0))              # mouth weight (cols,)
        # the reach of the mouth's width change: classic, the mouth weight (half at the
        # commissure); calibrated, the corners whole (95 %), fading over the skin beyond them
        self._mw = self._m if not kin["width_reach"] else \
            1.0 / (1.0 + np.exp((np.abs(x) - W - kin["width_reach"]) / 3.0))
        self._jb = np.exp(-(np.clip(np.abs(x) - 0.8 * W, 0, None) / 10.0) ** 2)  # jaw footprint
        self._cw = np.exp(-((np.abs(x) - W) / (0.28 * W)) ** 2)             # corner region (cols,)
        self._side = np.clip(x / W, -1.0, 1.0)                              # -1 right .. +1 left
        taper = 0.35 + 0.65 * np.clip(1.0 - ax ** 2, 0.0, None) ** 0.5      # vermilion taper (cols,)
        xp, pw = 0.5 * an.philtrum_width, 0.5 * an.philtrum_width
        bow = an.bow * (np.exp(-((np.abs(x) - xp) / (0.45 * pw)) ** 2) - 0.5 * np.exp(-(x / (0.3 * pw)) ** 2))
        self._hvu = an.upper_vermilion * taper + bow                        # upper vermilion height (cols,)
        self._hvl = an.lower_vermilion * taper                              # lower vermilion height (cols,)
        self._face_z = -0.012 * (25.0 / W) * x ** 2                          # face curvature (cols,)
        tv = np.minimum(t, _TV) / _TV                                         # 0..1 across vermilion
        ts = np.clip(t - _TV, 0, None) / (1 - _TV)                            # 0..1 across skin
        self._tv, self._ts = tv, ts
        self._prot = np.exp(-ts / 0.3)                                        # protrusion falloff
        self._follow = 1.0 - _smoothstep(t / 0.9)                             # lip-local motion falloff
        # depth profile of a lip from inner contour outwards: curls in, bulges, recedes
        th = an.thickness
        self._bulge = -2.0 + th * np.exp(-((t - 0.15) / 0.16) ** 2) - 2.5 * ts
        # philtral columns and groove (upper skin), mentolabial sulcus (lower skin), per (row, col)
        near = np.sqrt(np.clip(1.0 - ts, 0.0, 1.0)) * (ts > 0)
        self._philtrum = near[:, None] * (0.9 * np.exp(-((np.abs(x)[None, :] - xp) / 2.0) ** 2)
                                          - 0.5 * np.exp(-(x[None, :] / 2.5) ** 2))
        self._sulcus = -an.sulcus * np.exp(-((ts - 0.45) / 0.2) ** 2)[:, None] * (ts > 0)[:, None] \
            * np.clip(1.0 - ax ** 2, 0.0, None)[None, :] ** 0.5
        # the lower lip's and chin's rest position relative to the jaw's pivot, (rows, cols):
        # h below the pivot (negative), d in front of it; opening rotates them about it
        y_low = -(0.5 * an.gap * self._e[None, :] + self._hvl[None, :] * tv[:, None] + an.chin * ts[:, None])
        z_low = self._face_z[None, :] + self._bulge[:, None] * (0.6 + 0.4 * self._m[None, :]) + self._sulcus
        self._jh = y_low - (_PIV_Y - 0.5 * an.gap)
        self._jd = z_low + _PIV_Z
        mid = cols // 2
        self.midline = (0 * rows * cols + mid, 1 * rows * cols + mid)
        self.border_row = int(np.argmin(np.abs(t - _TV)))
        self.corner_column = int(np.argmin(np.abs(x - W)))
        self._A = self._coefficients()
        self.rest_vertices = self._assemble(self._fields(np.zeros((1, _NC))))[0].reshape(-1, 3)
        self.faces = self._make_faces()
        self.point_names = [f"{lip}{r:02d}_{c:02d}" for lip in "UL" for r in range(rows) for c in range(cols)]

    # ---------------------------------------------------------------- topology
    def _make_faces(self) -> np.ndarray:
        R, C = self.rows, self.cols
        r, c = np.meshgrid(np.arange(R - 1), np.arange(C - 1), indexing="ij")
        a = (r * C + c).ravel()
        b, d, e = a + 1, a + C, a + C + 1
        # split each quad along the diagonal that runs away from the midline, so the two
        # halves of the mouth are mirror images (no left-right shading bias)
        left = (c < (C - 1) // 2).ravel()
        t1 = np.where(left[:, None], np.stack([a, b, d], 1), np.stack([a, b, e], 1))
        t2 = np.where(left[:, None], np.stack([b, e, d], 1), np.stack([a, e, d], 1))
        one = np.concatenate([t1, t2])
        lower = one[:, ::-1] + R * C  # rows run downwards on the lower lip: flip winding
        return np.concatenate([one, lower]).astype(np.int64)  # both lips face forward (+z)

    # -------------------------------------------------------------- deformation
    def _asym(self, c):
        """Per-column factor of the displacements, (n, cols): 1 on the midline."""
        a = c[:, 9:10] + self.anatomy.asymmetry
        return 1.0 + _ASY * a * self._side[None, :]

    def _inner(self, c):
        """Inner-contour heights, compression and the lower lip's rise towards contact
        (relative to where the jaw alone puts it), each (n, cols)."""
        jaw, rnd, spr, rai, clo, lab, pro, dep = (c[:, k:k + 1] for k in range(8))
        # rounding makes the opening rounder near the corners
        e = self._e[None, :] ** (1.0 - 0.35 * np.clip(rnd, 0.0, 1.0))
        s = self._asym(c)
        g0 = self.anatomy.gap
        up_nom = e * (0.5 * g0 + s * (self._ju * _GJ * jaw + 1.5 * lab)) + s * _GR * self._er[None, :] * rai
        low_nom = -e * (0.5 * g0 + s * ((1 - self._ju) * _GJ * jaw + _DEP * dep))
        low_nom = (1 - lab) * low_nom + lab * (up_nom - 2.0 * e)
        g_nom = up_nom - low_nom
        yc = low_nom + (1 - self._ju) * g_nom
        g_raw = g_nom * (1 - clo) - clo * _KC * e
        eps = _EPS * e + 1e-3
        g = eps * np.logaddexp(0.0, g_raw / eps)
        comp = g - g_raw                                   # >= 0, ~0 when the lips are apart
        low = yc - (1 - self._ju) * g
        return yc + self._ju * g, low, comp, low - low_nom

    def aperture(self, controls) -> np.ndarray:
        """Vertical distance between the inner lips on the midline (mm), shape (n,).

        Equals ``y(upper midline inner point) - y(lower midline inner point)`` of
        :meth:`deform` exactly (noise-free).
        """
        c = self._check(controls)
        mid = self.cols // 2
        up, low, _, _ = self._inner(c)
        return (up[:, mid] - low[:, mid]).astype(np.float64)

    def _check(self, controls) -> np.ndarray:
        c = np.asarray(controls, dtype=np.float64)
        if c.ndim == 1:
            c = c[None, :]
        if c.ndim != 2 or c.shape[1] != _NC:
            raise ValueError(
                f"controls must have shape (n_frames, {_NC}) in the order {CONTROL_NAMES}, got {c.shape}"
            )
        if not np.isfinite(c).all():
            raise ValueError("controls contain NaN or inf")
        return c

    # The surface is linear in a few per-(frame, column) fields: F[n, k, c] with k over
    # _FIELDS. _assemble() is the readable elementwise formula; since it is linear in the
    # fields, probing it with unit fields once gives a coefficient tensor A (cols, K, 6*rows)
    # and deform() is then one batched matrix product per block of frames.
    _FIELDS = ("one", "x", "up_in", "low_in", "comp", "vfac_u", "vfac_l", "rot_s", "round", "spread", "raise",
               "labiodental", "rise", "prot_u", "prot_l", "corner", "jlat", "roll", "ment", "rot_c", "jfwd", "arch",
               "cdrop")

    def _fields(self, c):
        """Fields (n, K, cols) of controls ``c`` (n, 14)."""
        n = c.shape[0]
        jaw, rnd, spr, rai, clo, lab, pro, dep, cor, asy, jl, jf, rol, mnt = (c[:, k:k + 1] for k in range(_NC))
        up_in, low_in, comp, rise = self._inner(c)
        s = self._asym(c)
        wscale = 1.0 - _WR * rnd + _WSP * spr
        fx = self._x[None, :] * (1.0 + (wscale - 1.0) * self._mw[None, :])
        vfac_u = 1.0 + _VR * rnd - _VS * spr + _VP * pro
        if self._str:  # wide opening stretches the vermilion thin
            vfac_u = vfac_u - self._str * np.clip(jaw, 0.0, None) ** 2
        vfac_l = vfac_u + 0.1 * dep
        m = self._m[None, :]
        prot_u = s * (_PRR * rnd + _PRU * pro) * m
        prot_l = s * (_PRR * rnd + _PRL * pro + 1.0 * dep) * m
        a_tot = asy + self.anatomy.asymmetry
        corner = (_COR * cor * s + 1.0 * a_tot * self._side[None, :]) * self._cw[None, :]
        fields = [1.0, fx, up_in, low_in, comp, vfac_u, vfac_l, jaw, rnd, spr, rai, lab, rise, prot_u, prot_l, corner,
                  jl, rol * m, mnt * s]
        if self._arc:
            # the jaw's rotation: the angle that lowers a point _PIV_Z in front of the pivot by
            # the lower lip's share of the opening
            rot_s = np.clip((1 - self._ju) * _GJ * jaw / _PIV_Z, -0.9, 0.9)
            fields[7] = rot_s
            # the lips lie on the curved face (over the dental arch): a column that moves in or
            # out moves forward or back with the curve
            arch = -0.012 * (25.0 / self._W) * (fx ** 2 - self._x[None, :] ** 2)
            # the corners (modiolus) go down with the opening jaw, a fraction of the lower lip's drop
            cdrop = -self._kj * (1 - self._ju) * _GJ * jaw * self._cw[None, :]
            fields += [1.0 - np.sqrt(1.0 - rot_s ** 2), jf, arch, cdrop]
        F = np.empty((n, self._K, self.cols))
        for k, f in enumerate(fields):
            F[:, k, :] = f
        return F

    def _assemble(self, F):
        """Points (n, 2, rows, cols, 3) from fields (n, K, cols); elementwise, linear in F."""
        if F.shape[1] < len(self._FIELDS):  # classic: no arc fields (they would add zeros)
            F = np.concatenate([F, np.zeros((F.shape[0], len(self._FIELDS) - F.shape[1], F.shape[2]))], 1)
        (one, fx, up_in, low_in, comp, vfu, vfl, jaw, rnd, spr, rai, lab, rise, pru, prl, cor,
         jl, rol, mnt, rot_c, jf, arch, cdrop) = (F[:, k, None, :] for k in range(F.shape[1]))
        an = self.anatomy
        W = self._W
        x = self._x[None, None, :]
        m = self._m[None, None, :]
        tv, ts = self._tv[None, :, None], self._ts[None, :, None]
        prot, fol = self._prot[None, :, None], self._follow[None, :, None]
        hvu, hvl = self._hvu[None, None, :], self._hvl[None, None, :]
        out = np.empty((F.shape[0], 2, self.rows, self.cols, 3))
        z_rest = self._face_z[None, None, :] + self._bulge[None, :, None] * (0.6 + 0.4 * m)
        z_common = - 2.0 * spr * (x / W) ** 2 * m - 0.6 * cor * m
        if self._arc:
            z_common = z_common + arch
        # eversion: the vermilion rolls forward, most at its middle
        roll = (tv * (1.0 - tv) * 4.0) * (ts == 0)
        # corners: raised corners also draw back a little (a smile); both lips take the same shift
        cy = ((cor + cdrop) if self._arc else cor) * (1.0 - 0.7 * ts)
        # upper lip: lip-local motion fades towards the nose base (fol: 1 -> 0 across the rows)
        phil = an.philtrum + an.upper_vermilion - hvu    # the skin ends level at the nose base
        y_rest = hvu * tv + phil * ts
        out[:, 0, ..., 0] = fx
        # vermilion roll (eversion / inversion): the red lip's height and its border's depth
        # change, growing across the vermilion (tv) and fading over the skin beyond its border
        # (so the skin rows stay in order); the inner contour stays
        rl_p = np.where(ts == 0, tv, np.exp(-ts / 0.2))
        rl_y, rl_z = _RLH * rol * rl_p, _RLZ * rol * rl_p
        out[:, 0, ..., 1] = fol * (up_in + hvu * tv * (vfu - 0.12 * comp) + phil * ts * one) \
            + (1 - fol) * (y_rest * one + 0.15 * _GR * rai * m) + cy + hvu * rl_y
        out[:, 0, ..., 2] = one * (z_rest + self._philtrum[None]) + z_common + pru * prot \
            + (rai + 0.4 * comp) * prot * m + 1.5 * (vfu - one) * roll * m + rl_z
        jb = self._jb[None, None, :]
        if self._arc:
            # the jaw turns the chin (and the lower lip's depth) about its pivot: a point h above
            # (h < 0: below) and d in front of it moves by (-h (1 - cos) - d sin, h sin - d (1 - cos))
            # (field jaw = sin); its protrusion (jaw_forward) translates it, the chin fully, the lip less
            jh, jd = self._jh[None], self._jd[None]
            rot_y = jb * (-jh * rot_c - jd * jaw)
            rot_z = jb * (jh * jaw - jd * rot_c) + _JF * jf * jb * (0.6 + 0.4 * ts)
            # where the lips meet at and beyond the corners they move as one: the upper lip
            # there takes the lower lip's depth change by the jaw (none on the midline)
            out[:, 0, ..., 2] += (1.0 - self._e[None, None, :]) * fol * rot_z[:, :1]
        else:
            jaw_drop = (1 - self._ju) * _GJ * jaw * jb
            rot_y = -jaw_drop
            rot_z = -0.25 * jaw_drop * (0.3 + 0.7 * ts)
        # lower lip: the lip follows its inner contour, the chin follows the jaw rigidly; the
        # skin between them also takes the lip's own rise towards contact (mentalis), fading
        # linearly to nothing at the chin
        out[:, 1, ..., 0] = fx + _JL * jl * (0.6 + 0.4 * ts)
        # mentalis: the chin's soft tissue rises and bunches forward (most at the chin, fading
        # up to the vermilion border), the sulcus deepens, the lower vermilion is pushed up
        # and out (most at its border); zero on the inner contour
        chin = _smoothstep(ts / 0.6)
        mt_y = mnt * (_MTY * chin + _MTL * tv * (ts == 0) + _MTL * (ts > 0) * (1 - chin)) * m
        mt_z = mnt * (_MTZ * chin + _MTL * tv * (ts == 0) + _MTL * (ts > 0) * (1 - chin)) * m \
            + _MTS * mnt * self._sulcus[None]
        out[:, 1, ..., 1] = fol * (low_in - hvl * tv * (vfl - 0.12 * comp - 0.3 * lab) - an.chin * ts * one) \
            + (1 - fol) * (-(hvl * tv + an.chin * ts) * one + rot_y + (1 - ts) * rise) + cy \
            - hvl * rl_y + mt_y
        out[:, 1, ..., 2] = one * (z_rest + self._sulcus[None]) + z_common + prl * prot \
            + 0.4 * comp * prot * m + rot_z \
            - 5.0 * lab * (1.0 - tv) * fol * m + 1.5 * (vfl - one) * roll * m + rl_z + mt_z
        return out

    def _coefficients(self):
        K, R, C = self._K, self.rows, self.cols
        probe = np.zeros((K, K, C))
        probe[np.arange(K), np.arange(K), :] = 1.0
        P = self._assemble(probe)                       # (K, 2, R, C, 3)
        return np.ascontiguousarray(P.transpose(3, 0, 1, 2, 4).reshape(C, K, 6 * R)).astype(np.float32)

    def deform(self, controls, *, out=None, chunk=None) -> np.ndarray:
        """Surface points for each row of controls.

        Parameters
        ----------
        controls : array-like of shape (n_frames, 14)
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
        from engine.threads import one_blas_thread

        # many small products (K = 19 fields inner size): one BLAS thread is 10x faster than two
        # that spin against each other on a busy machine (measured 0.08 s vs 1.3 s per block)
        with one_blas_thread():
            for s in range(0, n, chunk):
                blk = c[s:s + chunk]
                Ft = np.ascontiguousarray(self._fields(blk).transpose(2, 0, 1), dtype=np.float32)  # (C, b, K)
                P = np.matmul(Ft, self._A).reshape(C, len(blk), 2, R, 3)
                out[s:s + len(blk)].reshape(len(blk), 2, R, C, 3)[...] = P.transpose(1, 2, 3, 0, 4)
        return out
