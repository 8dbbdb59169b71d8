"""Sensor layouts: what the columns of a plain numeric articulograph matrix mean.

A plain matrix (a ``.mat`` variable, a ``.npy`` array, a CSV without column names, an
AG500/AG501 ``.pos`` file, an NDI Wave TSV export) holds ``values`` numbers per sensor,
sensor after sensor. A :class:`Layout` says how many values each sensor has, which
of them are x, y and z, what the sensors are called and which **role** each plays:

==================  ========================================================
``upper_lip``        upper lip (mid-sagittal) sensor / marker
``lower_lip``        lower lip sensor / marker
``left_corner``      left mouth corner
``right_corner``     right mouth corner
``lip``              another point on the lips (dense marker sets)
``jaw``              jaw (lower incisor) sensor
``reference``        head sensor (nose bridge, mastoids, upper incisor, ...): used
                     to remove head motion by rigid registration
``tongue``           tongue sensor (left out of the lip space by default)
``other``            anything else
==================  ========================================================

Built-in layouts (:data:`BUILTIN`): ``ema7x6`` and ``ema7x7`` (7 sensors: UL, LL, LC,
RC, TT, TB, TD, each x y z phi theta rms [extra], the common export of 3-D
articulographs), ``ag500`` (the AG500's headerless ``.pos`` binary: 12 channels x 7
float32 values at 200 Hz), ``ag501`` (``.pos`` with an ``AG50xDATA`` header giving
channels and rate; without one 16 channels at 250 Hz) and ``wave`` (NDI Wave TSV
export; sensors in the file's order). ``ag500``, ``ag501`` and ``wave`` name their
channels ``ch1, ch2, ...`` with no roles: a user layout file (:func:`read_layout`)
names them and gives their roles.

User layout file (plain text, ``#`` starts a comment)::

    name: my-lab
    base: ag501          # optional: a built-in layout whose structure this one reuses
    values: 7            # numbers per sensor (default: the base's, else 6)
    xyz: 0 1 2           # 0-based positions of x, y, z inside a sensor's values
    rate: 250            # Hz, for inputs that carry no timing (optional)
    quality: 5           # 0-based position of each sensor's quality value (the rms of
                         # its position fit), or none (default: the base's, else none)
    sensor UL upper_lip  # one line per sensor, in column (channel) order
    sensor LL lower_lip
    sensor REF reference
    sensor T1 tongue
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

__all__ = ["ROLES", "Layout", "LayoutError", "BUILTIN", "get_layout", "read_layout", "guess_roles",
           "LIP_ROLES", "DEFAULT_KEEP_ROLES", "roles_from_spec"]

ROLES = ("upper_lip", "lower_lip", "left_corner", "right_corner", "lip", "jaw", "reference", "tongue", "other")
#: roles that are points on the lips
LIP_ROLES = ("upper_lip", "lower_lip", "left_corner", "right_corner", "lip")
#: roles kept by default on import (tongue and unassigned sensors are left out of the lip space)
DEFAULT_KEEP_ROLES = LIP_ROLES + ("jaw", "reference")
FORMATS = ("matrix", "pos", "wave")


class LayoutError(ValueError):
    """A layout (built-in name or user file) is unknown or malformed; names the file and line."""


@dataclass(frozen=True)
class Layout:
    """What the columns of a plain numeric articulograph matrix mean.

    Parameters
    ----------
    name : str
    sensors : tuple of str
        Sensor names in column (channel) order.
    roles : tuple of str
        One of :data:`ROLES` (or "") per sensor.
    values : int
        Numbers per sensor in the matrix.
    xyz : tuple of 3 int
        0-based positions of x, y, z inside a sensor's ``values``.
    rate : float or None
        Frame rate for inputs that carry no timing.
    format : {"matrix", "pos", "wave"}
        ``matrix``: any plain matrix; ``pos``: AG500/AG501 binary; ``wave``: NDI Wave TSV.
    description : str
    quality : int or None
        0-based position inside a sensor's ``values`` of its quality value (the rms
        residual of the position fit: AG500 / AG501 and the 6-value exports), or None.
    """

    name: str
    sensors: tuple[str, ...]
    roles: tuple[str, ...]
    values: int = 6
    xyz: tuple[int, int, int] = (0, 1, 2)
    rate: float | None = None
    format: str = "matrix"
    description: str = ""
    quality: int | None = None

    def __post_init__(self):
        if len(self.sensors) != len(self.roles):
            raise LayoutError(f"layout {self.name!r}: {len(self.sensors)} sensors but {len(self.roles)} roles")
        if len(set(self.sensors)) != len(self.sensors):
            dup = sorted({s for s in self.sensors if self.sensors.count(s) > 1})
            raise LayoutError(f"layout {self.name!r}: sensor name(s) {dup} appear twice; names must be unique")
        bad = sorted({r for r in self.roles if r and r not in ROLES})
        if bad:
            raise LayoutError(f"layout {self.name!r}: unknown role(s) {bad}; expected one of {', '.join(ROLES)}")
        if int(self.values) < 3:
            raise LayoutError(f"layout {self.name!r}: values={self.values}; a sensor needs at least x, y, z (3)")
        if len(self.xyz) != 3 or len(set(self.xyz)) != 3 or min(self.xyz) < 0 or max(self.xyz) >= self.values:
            raise LayoutError(f"layout {self.name!r}: xyz={tuple(self.xyz)}; expected 3 distinct positions in "
                              f"0..{self.values - 1}")
        if self.format not in FORMATS:
            raise LayoutError(f"layout {self.name!r}: format {self.format!r}; expected one of {FORMATS}")
        if self.quality is not None and not (0 <= self.quality < self.values and self.quality not in self.xyz):
            raise LayoutError(f"layout {self.name!r}: quality={self.quality}; expected a position in "
                              f"0..{self.values - 1} other than x, y, z ({list(self.xyz)}), or none")

    @property
    def n_columns(self) -> int:
        return len(self.sensors) * int(self.values)

    def with_channels(self, n: int) -> Layout:
        """This layout for ``n`` channels: generic names ``ch1..`` when it names none of its own."""
        if n == len(self.sensors):
            return self
        if any(not s.startswith("ch") for s in self.sensors):
            raise LayoutError(f"layout {self.name!r} names {len(self.sensors)} sensors but the file has {n}; "
                              "give a layout with one 'sensor' line per channel")
        return replace(self, sensors=tuple(f"ch{i + 1}" for i in range(n)), roles=("",) * n)

    def select(self, points=None) -> list[int]:
        """Sensor indices to keep.

        ``points`` None: every sensor whose role is in :data:`DEFAULT_KEEP_ROLES`, or
        every sensor when the layout gives no roles; ``"all"``: every sensor; ``"lips"``:
        lip roles only; a sequence of names: those, in that order.
        """
        if points is None:
            keep = [i for i, r in enumerate(self.roles) if r in DEFAULT_KEEP_ROLES]
            return keep if keep else list(range(len(self.sensors)))
        if isinstance(points, str) and points == "all":
            return list(range(len(self.sensors)))
        if isinstance(points, str) and points == "lips":
            keep = [i for i, r in enumerate(self.roles) if r in LIP_ROLES]
            if not keep:
                raise LayoutError(f"layout {self.name!r} gives no sensor a lip role; name the sensors to keep "
                                  f"(one of {', '.join(self.sensors)})")
            return keep
        if isinstance(points, str):
            points = [p.strip() for p in points.split(",") if p.strip()]
        upper = {s.upper(): i for i, s in enumerate(self.sensors)}
        out = []
        for p in points:
            i = upper.get(str(p).upper())
            if i is None:
                raise LayoutError(f"no sensor {p!r} in layout {self.name!r}; it has {', '.join(self.sensors)} "
                                  "(or 'all', 'lips')")
            out.append(i)
        if not out:
            raise LayoutError(f"no sensors selected from layout {self.name!r}")
        return out

    def describe(self) -> str:
        sens = ", ".join(f"{s}={r}" if r else s for s, r in zip(self.sensors, self.roles))
        q = f", quality (rms) at {self.quality}" if self.quality is not None else ""
        return (f"{self.name}: {len(self.sensors)} sensors x {self.values} values (x, y, z at {list(self.xyz)}{q})"
                f"{f', {self.rate:g} Hz' if self.rate else ''}, {self.format}; {sens}")


_EMA7 = ("UL", "LL", "LC", "RC", "TT", "TB", "TD")
_EMA7_ROLES = ("upper_lip", "lower_lip", "left_corner", "right_corner", "tongue", "tongue", "tongue")

BUILTIN = {
    "ema7x6": Layout("ema7x6", _EMA7, _EMA7_ROLES, 6, (0, 1, 2), None, "matrix",
                     "7 sensors (upper lip, lower lip, left and right corner, 3 tongue) x x y z phi theta rms", 5),
    "ema7x7": Layout("ema7x7", _EMA7, _EMA7_ROLES, 7, (0, 1, 2), None, "matrix",
                     "as ema7x6 with a 7th value per sensor (x y z phi theta rms extra)", 5),
    "ag500": Layout("ag500", tuple(f"ch{i + 1}" for i in range(12)), ("",) * 12, 7, (0, 1, 2), 200.0, "pos",
                    "Carstens AG500 .pos binary: 12 channels x 7 float32 (x y z phi theta rms extra), 200 Hz", 5),
    "ag501": Layout("ag501", tuple(f"ch{i + 1}" for i in range(16)), ("",) * 16, 7, (0, 1, 2), 250.0, "pos",
                    "Carstens AG501 .pos binary: AG50xDATA header (channels, rate), 7 float32 per channel "
                    "(x y z phi theta rms extra)", 5),
    "wave": Layout("wave", ("ch1",), ("",), 3, (0, 1, 2), None, "wave",
                   "NDI Wave TSV export: Time, then per sensor Id, Status, Tx Ty Tz (and quaternion)"),
}

#: conventional sensor / marker names -> role (upper case, compared after stripping digits/underscores)
_NAME_ROLES = {
    "UL": "upper_lip", "ULIP": "upper_lip", "UPPERLIP": "upper_lip", "ULC": "upper_lip",
    "LL": "lower_lip", "LLIP": "lower_lip", "LOWERLIP": "lower_lip", "LLC": "lower_lip",
    "ML": "left_corner", "LC": "left_corner", "LM": "left_corner", "LCORNER": "left_corner", "LLM": "left_corner",
    "MR": "right_corner", "RC": "right_corner", "RM": "right_corner", "RCORNER": "right_corner",
    "JAW": "jaw", "JAWL": "jaw", "LI": "jaw", "LJ": "jaw", "MAND": "jaw",
    "REF": "reference", "NOSE": "reference", "NASION": "reference", "BN": "reference", "UI": "reference",
    "LMA": "reference", "RMA": "reference", "HEAD": "reference", "FOREHEAD": "reference", "MAX": "reference",
    "TT": "tongue", "TB": "tongue", "TD": "tongue", "TR": "tongue", "TM": "tongue", "TBL": "tongue",
    "TIP": "tongue", "TONGUE": "tongue", "V": "other", "VEL": "other",
}


def guess_roles(names) -> list[str]:
    """Roles from conventional sensor names (UL, LL, ML/LC, MR/RC, JAW/LI, REF/NOSE/BN/UI, TT/TB/TD ...).

    Unknown names get "". Names like ``T1``..``T9`` are tongue sensors.
    """
    out = []
    for n in names:
        key = "".join(ch for ch in str(n).upper() if ch.isalpha())
        role = _NAME_ROLES.get(key, "")
        if not role and key == "T" and any(ch.isdigit() for ch in str(n)):
            role = "tongue"
        out.append(role)
    return out


def get_layout(spec) -> Layout:
    """A :class:`Layout` from a built-in name, a user layout file path, or a Layout."""
    if isinstance(spec, Layout):
        return spec
    s = str(spec)
    if s.lower() in BUILTIN:
        return BUILTIN[s.lower()]
    p = Path(s)
    if p.is_file():
        return read_layout(p)
    raise LayoutError(f"layout {s!r} is neither a built-in layout ({', '.join(BUILTIN)}) nor an existing layout file")


def read_layout(path) -> Layout:
    """Read a user layout file (format in the module docstring).

    Raises
    ------
    LayoutError
        Naming the file and line of the first fault.
    FileNotFoundError
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such layout file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise LayoutError(f"{path}: byte {exc.start} is not UTF-8 text; a layout file is plain text") from None
    fields, sensors, roles = {}, [], []
    for ln, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        where = f"{path}, line {ln}"
        if line.lower().startswith("sensor ") or line.lower() == "sensor":
            parts = line.split()
            if len(parts) not in (2, 3):
                raise LayoutError(f"{where}: {raw.strip()!r}; expected 'sensor NAME [ROLE]'")
            role = parts[2].lower() if len(parts) == 3 else ""
            if role and role not in ROLES:
                raise LayoutError(f"{where}: role {parts[2]!r}; expected one of {', '.join(ROLES)}")
            sensors.append(parts[1])
            roles.append(role)
            continue
        if ":" not in line:
            raise LayoutError(f"{where}: {raw.strip()!r}; expected 'key: value' (name, base, values, xyz, rate) "
                              "or 'sensor NAME [ROLE]'")
        key, val = (x.strip() for x in line.split(":", 1))
        key = key.lower()
        if key not in ("name", "base", "values", "xyz", "rate", "quality"):
            raise LayoutError(f"{where}: unknown key {key!r}; expected name, base, values, xyz, rate, quality or "
                              "sensor lines")
        fields[key] = (val, where)
    base = None
    if "base" in fields:
        val, where = fields["base"]
        base = BUILTIN.get(val.lower())
        if base is None:
            raise LayoutError(f"{where}: base {val!r}; expected one of {', '.join(BUILTIN)}")

    def number(key, cast, default):
        if key not in fields:
            return default
        val, where = fields[key]
        try:
            return cast(val)
        except ValueError:
            raise LayoutError(f"{where}: {key} {val!r} is not a number") from None

    values = number("values", int, base.values if base else 6)
    rate = number("rate", float, base.rate if base else None)
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise LayoutError(f"{fields['rate'][1]}: rate {rate}; expected a positive number of Hz")
    xyz: tuple[int, ...] = base.xyz if base else (0, 1, 2)
    if "xyz" in fields:
        val, where = fields["xyz"]
        try:
            xyz = tuple(int(v) for v in val.replace(",", " ").split())
        except ValueError:
            raise LayoutError(f"{where}: xyz {val!r}; expected three 0-based integers such as '0 1 2'") from None
    if not sensors:
        if base is None:
            raise LayoutError(f"{path}: no 'sensor NAME ROLE' lines; name the sensors in column order")
        sensors, roles = list(base.sensors), list(base.roles)
    name = fields["name"][0] if "name" in fields else path.stem
    quality = base.quality if base and values == base.values else None
    if "quality" in fields:
        val, where = fields["quality"]
        if val.lower() in ("none", "-", ""):
            quality = None
        else:
            try:
                quality = int(val)
            except ValueError:
                raise LayoutError(f"{where}: quality {val!r}; expected the 0-based position of the rms value "
                                  "(e.g. 5) or none") from None
    try:
        return Layout(name, tuple(sensors), tuple(roles), values, tuple(xyz), rate,  # type: ignore[arg-type]  # Layout checks it has 3
                      base.format if base else "matrix", f"user layout {path.name}", quality)
    except LayoutError as exc:
        raise LayoutError(f"{path}: {exc}") from None


def roles_from_spec(spec: str, n_points: int, names=None, base=None) -> list[str]:
    """Point roles from a ``role=point,point;role=...`` string (``lipspace import --roles``).

    Points are named (``point_names``, case-insensitive) or 0-based indices, so mesh
    vertices on the lip contours can be marked too, e.g.
    ``"upper_lip=UL;lower_lip=LL;left_corner=ML"`` or ``"upper_lip=812,813;lower_lip=1402"``.
    Points not named keep their role in ``base`` (or get "").

    Raises
    ------
    LayoutError
        Naming the unknown role or point and what is allowed.
    """
    roles = list(base) if base is not None else [""] * n_points
    upper = {str(n).upper(): i for i, n in enumerate(names or [])}
    for part in (p.strip() for p in str(spec).split(";")):
        if not part:
            continue
        if "=" not in part:
            raise LayoutError(f"--roles {part!r}: expected ROLE=POINT[,POINT...] (roles: {', '.join(ROLES)})")
        role, pts = (x.strip() for x in part.split("=", 1))
        role = role.lower()
        if role not in ROLES:
            raise LayoutError(f"--roles: unknown role {role!r}; expected one of {', '.join(ROLES)}")
        for tok in (t.strip() for t in pts.split(",") if t.strip()):
            if tok.upper() in upper:
                i = upper[tok.upper()]
            elif tok.isdigit() and int(tok) < n_points:
                i = int(tok)
            else:
                known = f"names {', '.join(list(names)[:12])} or " if names else ""
                raise LayoutError(f"--roles: no point {tok!r}; expected {known}an index 0..{n_points - 1}")
            roles[i] = role
    return roles
