"""A trajectory as a glTF morph-target animation, its audio as a WAV file beside it.

Used by ``lipspace synthesize -o speech.glb`` and the window's File › Export animation.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from engine._atomic import atomic_write
from engine.io.gltf import write_gltf_morph

__all__ = ["export_animation", "write_audio_beside", "utterance_audio", "DEFAULT_SCALE"]

#: node scale of the exported glTF: corpus coordinates are millimetres, glTF's unit is the metre
DEFAULT_SCALE = 0.001


def utterance_audio(manifold, uid, near=None) -> tuple[Path | None, str]:
    """The audio file of corpus utterance ``uid``, or None and why not.

    A relative path in the corpus is taken relative to the folder of ``near`` (the
    corpus or manifold file the user opened), else to the working directory.

    Returns
    -------
    (Path or None, str)
        The file, and '' or the reason there is none (for a warning).
    """
    from app.audio import resolve_audio_path

    u = manifold.corpus_.utterance(uid)
    if not u.audio:
        return None, f"utterance {uid} has no audio"
    p = resolve_audio_path(u.audio, near)
    if p is None:
        return None, f"utterance {uid}: audio file {u.audio} not found"
    return p, ""


def write_audio_beside(audio, path) -> Path:
    """Copy (or, if not a WAV, decode to 16-bit PCM) ``audio`` to ``path``, atomically.

    Parameters
    ----------
    audio : str or Path
        An existing audio file (WAV is copied byte for byte; other formats PyAV reads are
        converted).
    path : str or Path
        The ``.wav`` to write.
    """
    src, dst = Path(audio), Path(path)
    if not src.is_file():
        raise FileNotFoundError(f"{src}: no such audio file")
    if src.resolve() == dst.resolve():
        return dst
    if src.suffix.lower() == ".wav":
        with atomic_write(dst) as tmp:
            shutil.copyfile(src, tmp)
        return dst
    from app.export.video import decode_audio
    from engine._atomic import write_wav_atomic

    samples, rate = decode_audio(src)  # (channels, n) floats
    return write_wav_atomic(dst, samples.T if samples.shape[0] > 1 else samples[0], rate)


def export_animation(manifold, Fx, path, *, rate: float, audio=None, scale: float = DEFAULT_SCALE,
                     interpolation: str = "LINEAR", name: str = "lips", source: str = "") -> list[Path]:
    """Write F^x frames as a glTF 2.0 morph animation over the manifold's shape space.

    Parameters
    ----------
    manifold : engine.manifold.Manifold
        Fitted; its mean shape is the base, its shape components the morph targets, its
        corpus gives faces and point dimensions. Points are written in the talker's frame
        (:func:`engine.orientation.anatomical_frame`), which is glTF's: +Y up, the model
        facing +Z, its left +X; ``scene.extras["orientation"]`` says how it was found.
    Fx : array of shape (n_frames, m') with m' <= the number of components
        The trajectory in X (the animated weights); only the first m' components become
        targets.
    path : str or Path
        ``.glb`` or ``.gltf``.
    rate : float
        Frames per second.
    audio : str or Path, optional
        The utterance's audio; written as ``<stem>.wav`` beside ``path`` and named in
        the file's ``scene.extras["audio"]``.
    scale, interpolation, name
        See :func:`engine.io.gltf.write_gltf_morph`.
    source : str
        What the trajectory is (recorded in ``scene.extras["source"]``).

    Returns
    -------
    list of Path
        The files written (the glTF, then the WAV if any), each atomically.
    """
    shape, c = manifold.shape_, manifold.corpus_
    Fx = np.atleast_2d(np.asarray(Fx, np.float32))
    m = Fx.shape[1]
    if m > shape.n_components_:
        raise ValueError(f"F^x has {m} columns but the shape space has {shape.n_components_} components")
    path = Path(path)
    wav = path.with_suffix(".wav") if audio is not None else None
    if wav is not None and not Path(audio).is_file():
        raise FileNotFoundError(f"{audio}: no such audio file")
    # the talker's frame (engine.orientation) is glTF's: +Y up, the asset facing +Z, its left +X
    from engine.orientation import anatomical_frame

    frame = anatomical_frame(c, shape.mean_)
    mean = frame.view_frames(np.asarray(shape.mean_)[None])[0]
    comps = frame.view_frames(np.asarray(shape.components_[:m]))
    faces = c.faces[:, ::-1] if frame.mirrored and c.faces is not None else c.faces  # a mirror turns the winding
    out = [write_gltf_morph(path, mean, comps, Fx, rate=rate, faces=faces, dims=c.dims,
                            interpolation=interpolation, scale=scale, name=name,
                            audio=wav.name if wav is not None else None,
                            extras={"source": source, "orientation": frame.describe()} if source else
                            {"orientation": frame.describe()})]
    if wav is not None:
        out.append(write_audio_beside(audio, wav))
    return out
