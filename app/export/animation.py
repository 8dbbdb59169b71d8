"""A trajectory as a glTF morph-target animation, its audio as a WAV file beside it.

Used by ``lipspace synthesize -o speech.glb`` and the window's File › Export animation.
"""
from __future__ import annotations

import contextlib
import shutil
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write
from engine.io.writers.gltf import write_gltf_morph

__all__ = ["export_animation", "write_audio_beside", "utterance_audio", "DEFAULT_SCALE"]

#: node scale of the exported glTF: corpus coordinates are millimetres, glTF's unit is the metre
DEFAULT_SCALE = 0.001


def utterance_audio(manifold, uid, near=None) -> tuple[Path | None, str]:
    """The audio file of corpus utterance ``uid``, or None and why not.

    A relative path in the corpus is taken relative to the folder of ``near`` (the
    corpus or manifold file the user opened), else to the working directory. A path stored
    in a file is followed only inside that folder (or Lipspace's cache, where the synthetic
    talker's speech is): ``../private/secret.txt`` in a manifold someone sent is never
    copied beside an export. A ``.wav`` must be a WAV file (its header is checked).

    Returns
    -------
    (Path or None, str)
        The file, and '' or the reason there is none (for a warning).
    """
    from app.audio import resolve_audio_path
    from app.files.cache import cache_dir
    from engine.files.validate import FieldError, check_inside, wav_info

    u = manifold.corpus_.utterance(uid)
    if not u.audio:
        return None, f"utterance {uid} has no audio"
    p = resolve_audio_path(u.audio, near)
    if p is None:
        return None, f"utterance {uid}: audio file {u.audio} not found"
    base = Path(near).resolve().parent if near else None  # without a file the path was not read from one
    for root in (base, cache_dir()) if base is not None else ():
        try:
            p = check_inside(str(p), root, source=near, field="audio")
            break
        except FieldError:
            continue
    else:
        if base is not None:
            return None, (f"utterance {uid}: its audio {u.audio} is outside the folder of {Path(near).name} "
                          f"({base}); a path stored in a file is followed only inside its folder, so it was not used "
                          "(name the sound file yourself to use it: --audio)")
    if p.suffix.lower() == ".wav":
        try:
            wav_info(p)
        except (OSError, ValueError) as exc:
            return None, f"utterance {uid}: {exc}"
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
        from engine.files.validate import wav_info

        wav_info(src)  # ValueError for anything but sound (a text file named .wav is never copied)
        with atomic_write(dst) as tmp:
            shutil.copyfile(src, tmp)
        return dst
    from app.export.video import decode_audio
    from engine.files.atomic import write_wav_atomic

    samples, rate = decode_audio(src)  # (channels, n) floats
    return write_wav_atomic(dst, samples.T if samples.shape[0] > 1 else samples[0], rate)


def export_animation(manifold, Fx, path, *, rate: float, audio=None, scale: float = DEFAULT_SCALE,
                     interpolation: str = "LINEAR", name: str = "lips", source: str = "",
                     outputs=None) -> list[Path]:
    """Write F^x frames as a glTF 2.0 morph animation over the manifold's shape space.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
        Fitted; its mean shape is the base, its shape components the morph targets, its
        corpus gives faces and point dimensions. Points are written in the talker's frame
        (:func:`engine.recordings.orientation.anatomical_frame`), which is glTF's: +Y up, the model
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
        See :func:`engine.io.writers.gltf.write_gltf_morph`.
    source : str
        What the trajectory is (recorded in ``scene.extras["source"]``).
    outputs : engine.files.staging.Outputs, optional
        Stage both files there (the command's transaction). Without it the two are written
        as one transaction here: ``path`` replaced (its save dialog asked), an existing WAV
        beside it replaced only along with an existing ``path`` (an earlier export), else
        refused (nobody asked about it).

    Returns
    -------
    list of Path
        The files written (the glTF, then the WAV if any), both or neither.
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
    from engine.files.staging import Outputs

    # the talker's frame (engine.recordings.orientation) is glTF's: +Y up, the asset facing +Z, its left +X
    from engine.recordings.orientation import anatomical_frame

    frame = anatomical_frame(c, shape.mean_)
    mean = frame.view_frames(np.asarray(shape.mean_)[None])[0]
    comps = frame.view_frames(np.asarray(shape.components_[:m]))
    faces = c.faces[:, ::-1] if frame.mirrored and c.faces is not None else c.faces  # a mirror turns the winding
    extras = {"source": source, "orientation": frame.describe()} if source else {"orientation": frame.describe()}
    own = outputs is None
    if own:
        outputs = Outputs(hint="Choose another name, or move the existing WAV away first")
    with outputs if own else contextlib.nullcontext():
        staged = outputs.file(path, option="-o", force=True if own else None)
        same = wav is not None and Path(audio).resolve() == wav.resolve()  # the audio is already beside it
        # the window: a WAV beside replaced only with the animation it belongs to (the dialog asked about that)
        staged_wav = outputs.file(wav, option="the audio beside it", force=True if own and path.exists() else None) \
            if wav is not None and not same else None
        write_gltf_morph(staged, mean, comps, Fx, rate=rate, faces=faces, dims=c.dims,
                         interpolation=interpolation, scale=scale, name=name,
                         audio=wav.name if wav is not None else None, extras=extras)
        if staged_wav is not None:
            write_audio_beside(audio, staged_wav)
    return [path] + ([wav] if wav is not None else [])
