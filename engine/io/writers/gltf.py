"""glTF 2.0 export of a lip trajectory as a morph-target animation (``.glb`` / ``.gltf``).

The shape space X is linear, ``F = mean + F^x X^T`` (:class:`engine.manifold.shape.ShapeSpace`),
and so is a glTF morph: ``position = base + sum_k w_k * target_k``. The file therefore
holds the trajectory exactly, in a form animation tools play directly:

* one mesh whose base (``POSITION``) is the mean lip shape, ``(V, 3)`` float32;
* two morph targets per shape component, ``X1+`` = ``s_1 X_1`` and ``X1-`` = ``-s_1 X_1``
  (the rows of X as point displacements, named in ``mesh.extras.targetNames``, which
  Blender turns into shape key names; ``mesh.extras.targetScale`` holds ``±s_k`` and
  ``targetComponent`` k);
* one animation whose sampler runs over the frame times ``k / rate`` (seconds) and whose
  output is, frame by frame, ``max(F^x_k, 0) / s_k`` and ``max(-F^x_k, 0) / s_k`` (the
  morph weights), with ``LINEAR`` or ``STEP`` interpolation. ``s_k`` is the largest
  ``|F^x_k|`` of the trajectory, so every weight lies in [0, 1], the range every tool
  takes: F^x itself runs to tens (millimetres) and changes sign, Blender's shape-key
  sliders stop at ±10, and Blender 3.4's importer clamps at 0 any weight below the
  first frame's. Linear interpolation of the two halves is still linear in F^x
  (their difference is), so nothing is lost between keys. ``two_sided=False`` writes
  one target per component with signed weights in [-1, 1] instead.

With faces the primitive is a triangle list; without them (a marker set) it is a
``POINTS`` primitive, which glTF viewers draw as points and Blender imports as loose
vertices that carry the shape keys. No normals are stored: the standard tells viewers
to compute flat normals, which follow the deformed surface, whereas stored base normals
would not move with the morph. The lip surface is an open sheet, so the material is
double-sided. 2-D points get z = 0. Coordinates are written unchanged (in the corpus's
own unit); the node's uniform ``scale`` (e.g. 0.001 for millimetres) maps them to
glTF's metres. Audio is not part of glTF 2.0: a sidecar file name can be recorded in
``scene.extras["audio"]``.

Written with the maintained ``pygltflib`` library, atomically.
"""
from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write

__all__ = ["write_gltf_morph", "read_gltf_morph", "INTERPOLATIONS"]

INTERPOLATIONS = ("LINEAR", "STEP")
_FLOAT, _UINT16, _UINT32 = 5126, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_POINTS, _TRIANGLES = 0, 4
_DTYPES = {_FLOAT: np.float32, _UINT16: np.uint16, _UINT32: np.uint32}
_WIDTH = {"SCALAR": 1, "VEC3": 3}
LIP_COLOUR = (0.86, 0.45, 0.45, 1.0)


def _points3(a, dims):
    """(..., dims * V) -> (..., V, 3) float32 (z = 0 for 2-D)."""
    from engine.recordings.corpus import frame_points

    return np.ascontiguousarray(frame_points(np.asarray(a, np.float32), dims), dtype=np.float32)


def _check(mean, components, weights, rate, faces, dims, interpolation, scale):
    if dims not in (2, 3):
        raise ValueError(f"dims={dims!r}; expected 2 or 3 coordinates per point")
    mean = np.asarray(mean, np.float32).ravel()
    C = mean.size
    if C == 0 or C % dims:
        raise ValueError(f"the mean shape has {C} values, not a positive multiple of dims={dims}")
    components = np.atleast_2d(np.asarray(components, np.float32))
    if components.ndim != 2 or components.shape[1] != C:
        raise ValueError(f"components must have shape (m, {C}) to match the mean shape, got {components.shape}")
    weights = np.asarray(weights, np.float32)
    if weights.ndim != 2 or weights.shape[1] != components.shape[0]:
        raise ValueError(f"weights (F^x) must have shape (n_frames, {components.shape[0]}) for "
                         f"{components.shape[0]} components, got {weights.shape}")
    if weights.shape[0] < 1:
        raise ValueError("the trajectory has no frames; nothing to animate")
    if not np.isfinite(mean).all():
        raise ValueError("the mean shape holds NaN or infinite values; glTF needs finite numbers")
    for a, what in ((components, "components"), (weights, "weights (F^x)")):
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if bad.size:
            raise ValueError(f"{what} row {int(bad[0])} holds NaN or infinite values; glTF needs finite numbers")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate={rate!r}; the frame rate must be a positive number of frames per second")
    if interpolation not in INTERPOLATIONS:
        raise ValueError(f"interpolation={interpolation!r}; expected one of {INTERPOLATIONS}")
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale={scale!r}; the node scale must be a positive number (e.g. 0.001 for mm)")
    V = C // dims
    if faces is not None and len(faces):
        faces = np.asarray(faces)
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.min() < 0 or faces.max() >= V:
            raise ValueError(f"faces must be (F, 3) indices into {V} points, got shape {faces.shape}"
                             + (f" with indices {faces.min()}..{faces.max()}" if faces.size else ""))
    else:
        faces = None
    return mean, components, weights, faces


class _Blob:
    """The one binary buffer: 4-byte aligned views, one accessor each."""

    def __init__(self, gltf):
        self.gltf = gltf
        self.parts = []
        self.size = 0

    def add(self, arr, *, type_, component, target=None, minmax=False, name=None):
        import pygltflib as g

        data = np.ascontiguousarray(arr).tobytes()
        pad = -self.size % 4
        if pad:
            self.parts.append(b"\0" * pad)
            self.size += pad
        view = g.BufferView(buffer=0, byteOffset=self.size, byteLength=len(data), target=target)
        self.parts.append(data)
        self.size += len(data)
        self.gltf.bufferViews.append(view)
        width = {"SCALAR": 1, "VEC3": 3}[type_]
        flat = np.asarray(arr).reshape(-1, width)
        acc = g.Accessor(bufferView=len(self.gltf.bufferViews) - 1, componentType=component, count=int(flat.shape[0]),
                         type=type_, name=name)
        if minmax:
            acc.min = [float(v) for v in flat.min(axis=0)]
            acc.max = [float(v) for v in flat.max(axis=0)]
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def bytes(self):
        return b"".join(self.parts)


def write_gltf_morph(path, mean, components, weights, *, rate: float, faces=None, dims: int = 3,
                     target_names=None, target_scale=None, two_sided: bool = True, interpolation: str = "LINEAR",
                     scale: float = 1.0,
                     audio: str | None = None, name: str = "lips", extras: dict | None = None) -> Path:
    """Write a lip trajectory as a glTF 2.0 morph-target animation.

    Parameters
    ----------
    path : str or Path
        ``.glb`` (binary, one file) or ``.gltf`` (JSON with the buffer embedded as a data URI).
    mean : array of shape (C,)
        Base shape (the mean lip shape), ``C = dims * V``.
    components : array of shape (m, C)
        Morph targets: the shape components (rows of X), as displacements.
    weights : array of shape (n_frames, m)
        F^x per frame; the animated morph weights are its positive and negative parts
        over ``target_scale`` (see the module notes).
    rate : float
        Frames per second; frame ``k`` is keyed at ``k / rate`` seconds.
    faces : array of shape (F, 3) int, optional
        Triangles; without them the points are written as a ``POINTS`` primitive.
    dims : {2, 3}
        Coordinates per point in ``mean`` / ``components``.
    target_names : sequence of str, optional
        One name per component (default ``X1 .. Xm``).
    target_scale : array of shape (m,), optional
        Positive ``s_k``: target k is ``s_k`` times component k and its weight is divided
        by ``s_k`` (the product, hence the shape, is unchanged). Default: the largest
        ``|weights[:, k]|`` (1 where a column is all zero), so the weights lie in [0, 1].
    two_sided : bool
        Two targets per component (``+s_k X_k`` and ``-s_k X_k``, weights >= 0; default),
        or one with signed weights.
    interpolation : {"LINEAR", "STEP"}
        Between keyed frames.
    scale : float
        Uniform scale of the node (coordinates themselves are written unchanged).
    audio : str, optional
        File name of a sidecar audio file, recorded in ``scene.extras["audio"]``.
    name : str
        Name of the node, mesh and animation.
    extras : dict, optional
        JSON-serialisable values added to ``scene.extras`` (e.g. the corpus rate, source).

    Returns
    -------
    Path
        ``path``, written atomically.
    """
    import pygltflib as g

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".glb", ".gltf"):
        raise ValueError(f"{path}: a glTF file must end in .glb (binary) or .gltf (JSON)")
    mean, components, weights, faces = _check(mean, components, weights, rate, faces, dims, interpolation, scale)
    m, n = components.shape[0], weights.shape[0]
    names = [f"X{k + 1}" for k in range(m)] if target_names is None else [str(s) for s in target_names]
    if len(names) != m:
        raise ValueError(f"{len(names)} target names for {m} components")
    if target_scale is None:
        sk = np.abs(weights).max(axis=0).astype(np.float64)
        sk[sk == 0] = 1.0
    else:
        sk = np.asarray(target_scale, np.float64).ravel()
        if sk.shape != (m,) or not np.all(np.isfinite(sk) & (sk > 0)):
            raise ValueError(f"target_scale must be {m} positive finite numbers, got {target_scale!r}")
    base = _points3(mean, dims)
    V = base.shape[0]

    gltf = g.GLTF2(asset=g.Asset(generator="lipspace (pygltflib)", version="2.0"))
    blob = _Blob(gltf)
    pos = blob.add(base, type_="VEC3", component=_FLOAT, target=_ARRAY_BUFFER, minmax=True, name="mean shape")
    targets = []
    signs = (1.0, -1.0) if two_sided else (1.0,)
    t_names, t_scale, t_comp = [], [], []
    for k in range(m):
        for sign in signs:
            t_names.append(names[k] + ("+" if sign > 0 else "-") if two_sided else names[k])
            t_scale.append(float(sign * sk[k]))
            t_comp.append(k)
            d = _points3(components[k].astype(np.float64) * (sign * sk[k]), dims)
            targets.append(g.Attributes(POSITION=blob.add(d, type_="VEC3", component=_FLOAT, target=_ARRAY_BUFFER,
                                                          minmax=True, name=t_names[-1])))
    W = weights.astype(np.float64) / sk
    W = np.stack([np.maximum(W, 0.0), np.maximum(-W, 0.0)], axis=2).reshape(n, 2 * m) if two_sided else W
    prim = g.Primitive(attributes=g.Attributes(POSITION=pos), targets=targets, material=0,
                       mode=_TRIANGLES if faces is not None else _POINTS)
    if faces is not None:
        idx = faces.astype(np.uint16 if V <= 65535 else np.uint32).ravel()
        prim.indices = blob.add(idx, type_="SCALAR", component=_UINT16 if idx.dtype == np.uint16 else _UINT32,
                                target=_ELEMENT_ARRAY_BUFFER, name="faces")
    times = (np.arange(n, dtype=np.float64) / float(rate)).astype(np.float32)
    t_acc = blob.add(times, type_="SCALAR", component=_FLOAT, minmax=True, name="time (s)")
    w_acc = blob.add(W.astype(np.float32).ravel(), type_="SCALAR", component=_FLOAT, name="F^x / target scale")

    gltf.materials.append(g.Material(name="lip", doubleSided=True, pbrMetallicRoughness=g.PbrMetallicRoughness(
        baseColorFactor=list(LIP_COLOUR), metallicFactor=0.0, roughnessFactor=0.6)))
    gltf.meshes.append(g.Mesh(name=name, primitives=[prim], weights=[0.0] * len(targets),
                              extras={"targetNames": t_names, "targetScale": t_scale, "targetComponent": t_comp}))
    gltf.nodes.append(g.Node(name=name, mesh=0, scale=None if scale == 1.0 else [float(scale)] * 3))
    scene_extras = dict(extras or {})
    scene_extras.update({"rate": float(rate), "frames": int(n)})
    if audio:
        scene_extras["audio"] = str(audio)
    gltf.scenes.append(g.Scene(name=name, nodes=[0], extras=scene_extras))
    gltf.scene = 0
    gltf.animations.append(g.Animation(
        name=name, samplers=[g.AnimationSampler(input=t_acc, output=w_acc, interpolation=interpolation)],
        channels=[g.AnimationChannel(sampler=0, target=g.AnimationChannelTarget(node=0, path="weights"))]))
    data = blob.bytes()
    gltf.buffers.append(g.Buffer(byteLength=len(data)))
    with atomic_write(path) as tmp:
        if suffix == ".glb":
            gltf.set_binary_blob(data)
            if not gltf.save_binary(str(tmp)):
                raise OSError(f"{path}: pygltflib could not write the binary glTF")
        else:
            gltf.buffers[0].uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode("ascii")
            gltf.save_json(str(tmp))
    return path


def read_gltf_morph(path) -> dict:
    """Read back a morph-target animation written by :func:`write_gltf_morph` (with pygltflib).

    Only the first mesh, its first primitive and the first animation's weight channel
    are read; sparse accessors are not supported.

    Returns
    -------
    dict
        ``base`` (V, 3) float32, ``targets`` (m, V, 3) float32, ``times`` (n,) float32
        seconds, ``weights`` (n, t) float32 (the morph weights of the t targets), ``Fx``
        (n, m) float32 (per component, the sum of its targets' weights times their
        ``targetScale``; a file without these extras gives its weights), ``faces`` (F, 3)
        int64 or None,
        ``target_names`` list of str, ``interpolation`` str, ``scale`` float and
        ``extras`` (the scene's extras). ``base + weights[k] @ targets`` is frame k.
    """
    import pygltflib as g

    path = Path(path)
    try:
        gltf = g.GLTF2().load(str(path))
    except Exception as exc:  # noqa: BLE001 - pygltflib raises many kinds on damaged files
        raise ValueError(f"{path}: not a readable glTF file ({exc})") from None
    if gltf is None or not gltf.meshes or not gltf.animations or not gltf.buffers:
        raise ValueError(f"{path}: expected a glTF file with a mesh, an animation and a buffer")
    buf = gltf.buffers[0]
    blob = gltf.binary_blob() if buf.uri is None else gltf.get_data_from_buffer_uri(buf.uri)

    def accessor(i):
        a = gltf.accessors[i]
        v = gltf.bufferViews[a.bufferView]
        w = _WIDTH[a.type]
        offset = (v.byteOffset or 0) + (a.byteOffset or 0)
        if offset + a.count * w * np.dtype(_DTYPES[a.componentType]).itemsize > len(blob):
            raise ValueError(f"{path}: accessor {i} ({a.name}) runs past the end of the buffer")
        return np.frombuffer(blob, _DTYPES[a.componentType], count=a.count * w, offset=offset).reshape(a.count, w)

    def position(attr):
        return attr["POSITION"] if isinstance(attr, dict) else attr.POSITION

    mesh = gltf.meshes[0]
    prim = mesh.primitives[0]
    base = accessor(position(prim.attributes)).astype(np.float32)
    targets = np.stack([accessor(position(t)) for t in prim.targets]).astype(np.float32) if prim.targets else \
        np.zeros((0,) + base.shape, np.float32)
    anim = gltf.animations[0]
    chans = [c for c in anim.channels if c.target.path == "weights"]
    if not chans:
        raise ValueError(f"{path}: the animation has no morph-weight channel")
    sampler = anim.samplers[chans[0].sampler]
    times = accessor(sampler.input).ravel().astype(np.float32)
    weights = accessor(sampler.output).reshape(len(times), len(targets)).astype(np.float32)
    faces = None if prim.indices is None else accessor(prim.indices).reshape(-1, 3).astype(np.int64)
    node = gltf.nodes[0] if gltf.nodes else None
    scale = float(node.scale[0]) if node is not None and node.scale else 1.0
    names = list((mesh.extras or {}).get("targetNames", [f"X{k + 1}" for k in range(len(targets))]))
    sk = np.asarray((mesh.extras or {}).get("targetScale", np.ones(len(targets))), np.float64)
    comp = np.asarray((mesh.extras or {}).get("targetComponent", np.arange(len(targets))), np.int64)
    Fx = np.zeros((len(times), int(comp.max()) + 1 if comp.size else 0))
    np.add.at(Fx.T, comp, (weights * sk).T)
    extras = dict(gltf.scenes[0].extras or {}) if gltf.scenes else {}
    return {"base": base, "targets": targets, "times": times, "weights": weights,
            "Fx": Fx.astype(np.float32), "target_scale": sk, "faces": faces,
            "target_names": names, "interpolation": sampler.interpolation or "LINEAR", "scale": scale,
            "extras": extras}
