"""Videos of a still image under known head motion: test and benchmark material.

:func:`moving_image_frames` moves an image by a known 2-D similarity per frame (rotation
about the image centre, uniform scale, translation), as a head turning in the image
plane, nearing the camera and moving sideways does; :func:`write_video` writes frames
(and optionally a mono audio track) to an H.264/AAC MP4 with PyAV, one frame at a time.
"""
from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = ["Motion", "moving_image_frames", "write_video", "default_motion"]


def default_motion(n_frames: int, *, rate: float = 30.0, angle_deg: float = 8.0, scale: float = 0.08,
                   shift_px: float = 12.0) -> np.ndarray:
    """A smooth head motion: (n_frames, 4) rows of (angle_deg, scale, dx_px, dy_px).

    Frame 0 is the still image (no motion); later frames sway by up to ``angle_deg``
    degrees, ``1 ± scale`` and ``shift_px`` pixels at incommensurate periods (1.9, 2.7,
    3.1 and 2.3 s).
    """
    t = np.arange(int(n_frames)) / float(rate)
    return np.stack([angle_deg * np.sin(2 * np.pi * t / 1.9),
                     1.0 + scale * np.sin(2 * np.pi * t / 2.7),
                     shift_px * np.sin(2 * np.pi * t / 3.1),
                     shift_px * np.sin(2 * np.pi * t / 2.3)], axis=1)


class Motion:
    """One frame's similarity: ``angle_deg`` about the image centre, ``scale``, shift ``(dx, dy)`` px."""

    def __init__(self, angle_deg, scale, dx, dy):
        self.angle_deg, self.scale, self.dx, self.dy = float(angle_deg), float(scale), float(dx), float(dy)

    def matrix(self, height, width):
        """(A, c, d): output pixel o (row, col) shows input pixel ``A @ (o - c - d) + c``."""
        a = np.deg2rad(self.angle_deg)
        # rotate the picture counter-clockwise on screen: in (row, col) with rows down
        R = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
        c = np.array([(height - 1) / 2.0, (width - 1) / 2.0])
        d = np.array([self.dy, self.dx])
        return np.linalg.inv(self.scale * R), c, d


def moving_image_frames(image, motion):
    """Yield the image moved by each row of ``motion`` (n, 4): (angle_deg, scale, dx, dy).

    Pixels moved in from outside the image repeat its edge.
    """
    from scipy.ndimage import affine_transform

    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError(f"image of shape {img.shape}; expected (height, width, 3) RGB")
    h, w = img.shape[:2]
    for row in np.asarray(motion, dtype=float):
        A, c, d = Motion(*row).matrix(h, w)
        offset = c - A @ (c + d)
        out = np.empty_like(img)
        for ch in range(3):
            out[..., ch] = affine_transform(img[..., ch].astype(np.float32), A, offset=offset, order=1,
                                            mode="nearest").round().clip(0, 255).astype(np.uint8)
        yield out


def write_video(path, frames, rate: float, *, audio=None, audio_rate: int = 16000, crf: int = 18):
    """Write RGB frames (an iterable of (H, W, 3) uint8, H and W even) to an H.264 MP4.

    Parameters
    ----------
    path : str or Path
    frames : iterable of ndarray
        Consumed one at a time (never held).
    rate : float
        Frame rate (Hz); an integer rate gives exact frame times.
    audio : ndarray (n,) float in [-1, 1], optional
        Mono audio written as an AAC track at ``audio_rate``.
    crf : int
        x264 quality (lower = better; 18 is visually lossless).

    Returns
    -------
    int : number of frames written.
    """
    import av

    from engine.files.atomic import atomic_write

    n = 0
    fps = Fraction(rate).limit_denominator(1001)
    with atomic_write(path) as tmp:
        with av.open(str(tmp), mode="w", format="mp4") as out:
            vs = None
            for img in frames:
                img = np.ascontiguousarray(img, dtype=np.uint8)
                if vs is None:
                    vs = out.add_stream("libx264", rate=fps)
                    vs.height, vs.width = img.shape[:2]
                    vs.pix_fmt = "yuv420p"
                    vs.options = {"crf": str(int(crf)), "preset": "veryfast"}
                    vs.codec_context.time_base = 1 / fps
                    if audio is not None:  # every stream before the first packet
                        aus = out.add_stream("aac", rate=int(audio_rate))
                        aus.layout = "mono"
                vf = av.VideoFrame.from_ndarray(img, format="rgb24")
                vf.pts = n
                vf.time_base = 1 / fps
                out.mux(vs.encode(vf))
                n += 1
            if vs is not None:
                out.mux(vs.encode(None))
            if audio is not None and vs is not None:
                x = np.asarray(audio, dtype=np.float32).reshape(1, -1)
                af = av.AudioFrame.from_ndarray(np.ascontiguousarray(x), format="fltp", layout="mono")
                af.sample_rate = int(audio_rate)
                af.pts = 0
                af.time_base = Fraction(1, int(audio_rate))
                out.mux(aus.encode(af))
                out.mux(aus.encode(None))
    return n
