"""An MP4 of a lip trajectory: the lip view rendered off-screen frame by frame, muxed with its audio.

The picture is drawn with the same scene builders as the explorer (:mod:`app.scene`)
on a ``pyvista.Plotter(off_screen=True)``: the lips (optionally the original utterance
beside them, as in the lip view's playback), and optionally a second panel with the
manifold's point cloud, the trajectory through it and a marker at the current frame.
Frames are encoded with H.264 (yuv420p) at the corpus rate through PyAV, whose wheel
carries FFmpeg's libraries (no system ffmpeg); the audio, when there is any, is encoded
as AAC and cut to the video's length. The file is written atomically: an error or
Ctrl-C leaves no half file and an existing file intact.
"""
from __future__ import annotations

import queue
import threading
from fractions import Fraction
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write

__all__ = ["render_video", "decode_audio", "AAC_RATES", "MAIN_COLOUR", "SYNTH_COLOUR", "MAX_CLOUD_POINTS"]

MAIN_COLOUR = (0.86, 0.55, 0.55)   # the lip view's original (left)
SYNTH_COLOUR = (0.95, 0.15, 0.1)   # the lip view's synthetic (right, red)
MAX_CLOUD_POINTS = 5000            # the manifold panel draws at most this many corpus points
MULTI_SAMPLES = 0                  # no MSAA: software GL renders 3-4x faster, H.264 softens edges anyway
PRESET = "ultrafast"                # x264 speed preset: the encoder costs less than the software renderer
BACKGROUND = "white"


#: sample rates the AAC encoder takes; others are resampled to 48 kHz for the MP4
AAC_RATES = (96000, 88200, 64000, 48000, 44100, 32000, 24000, 22050, 16000, 12000, 11025, 8000, 7350)


def decode_audio(path, *, rate: int | None = None):
    """All samples of an audio file as float32 ``(channels, n)`` in [-1, 1] and the sample rate.

    Any format FFmpeg (inside PyAV) reads; a file that holds no audio stream is an error.
    ``rate`` resamples to that many samples per second (default: the file's own rate).
    """
    import av

    path = Path(path)
    try:
        container = av.open(str(path))
    except (av.FFmpegError, OSError) as exc:
        raise ValueError(f"{path}: cannot read audio ({exc})") from None
    with container:
        if not container.streams.audio:
            raise ValueError(f"{path}: holds no audio stream")
        stream = container.streams.audio[0]
        rate = int(rate or stream.codec_context.sample_rate)
        layout = stream.codec_context.layout.name
        resampler = av.AudioResampler(format="fltp", layout=layout, rate=rate)
        chunks = []
        for frame in container.decode(stream):
            for f in resampler.resample(frame):
                chunks.append(f.to_ndarray())
        for f in resampler.resample(None):
            chunks.append(f.to_ndarray())
    if not chunks:
        raise ValueError(f"{path}: the audio stream holds no samples")
    return np.concatenate(chunks, axis=1).astype(np.float32), rate


def _even(n):
    return int(n) + (int(n) % 2)


def _frames3(frames, dims, what):
    from engine.recordings.corpus import frame_points

    A = np.asarray(frames, np.float32)
    if A.ndim != 2 or A.shape[0] < 1:
        raise ValueError(f"{what} must be (n_frames, dims * V) with n_frames >= 1, got shape {A.shape}")
    return frame_points(A, dims)


def _frame_rate(rate):
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate={rate!r}; the frame rate must be a positive number of frames per second")
    return Fraction(float(rate)).limit_denominator(1001)


def _mover(handle, faces):
    """``move(points)`` for a lip handle, a third of ``update``'s cost per frame for a triangle mesh.

    The mesh is drawn flat-shaded (as in the lip view), so VTK takes the normals from the
    triangles themselves; with smooth shading the vertex normals are recomputed in numpy
    (:func:`app.scene.lips.point_normals`, the normals ``compute_normals`` gives). Markers
    and sensors use the handle's own ``update``.
    """
    from app.scene.lips import point_normals

    mesh = getattr(handle, "mesh", None)
    if mesh is None or faces is None or not len(faces) or "Normals" not in mesh.point_data:
        return handle.update
    overlay = getattr(handle, "overlay", None)
    smooth = handle.actor.GetProperty().GetInterpolationAsString() != "Flat"
    F = np.asarray(faces, np.int64)
    n_points = mesh.n_points
    offset = np.asarray(handle.offset, np.float32)

    def move(points):
        P = np.asarray(points, np.float32).reshape(-1, 3)
        if P.shape[0] != n_points:
            raise ValueError(f"frame has {P.shape[0]} points, the mesh has {n_points}")
        P = P + offset
        mesh.points[:] = P
        if smooth:
            mesh.point_data["Normals"][:] = point_normals(P, F)
        mesh.Modified()
        if overlay is not None:  # the aperture over the surface
            overlay.update(P - offset)

    return move


class _Scene:
    """The off-screen plotter and the handles moved every frame."""

    def __init__(self, frames, original, faces, Y, Y_original, cloud, size, drawing):
        import pyvista as pv

        w, h = _even(size[0]), _even(size[1])
        panel = Y is not None
        self.plotter = p = pv.Plotter(off_screen=True, shape=(1, 2) if panel else (1, 1), border=False,
                                      window_size=(2 * w if panel else w, h), lighting="none")
        try:
            self._build(p, frames, original, faces, Y, Y_original, cloud, h, drawing)
        except BaseException:
            p.close()
            raise

    def _build(self, p, frames, original, faces, Y, Y_original, cloud, h, drawing):
        import pyvista as pv

        from app import scene

        panel = Y is not None
        p.add_light(pv.Light(light_type="headlight"))  # one light: a third cheaper than the light kit in llvmpipe
        p.render_window.SetMultiSamples(MULTI_SAMPLES)
        p.set_background(BACKGROUND)
        p.subplot(0, 0)
        allpts = frames if original is None else np.concatenate([frames, original])
        ext = allpts.reshape(-1, 3).max(0) - allpts.reshape(-1, 3).min(0)
        offset = np.array([1.25 * max(float(ext[0]), 1e-6), 0.0, 0.0], np.float32)
        self.second = None
        # markers without faces: a few sensors need big dots to be seen in a whole panel
        dot = max(8.0, min(24.0, h / 20.0)) if frames.shape[1] <= 50 else 8.0
        if original is None:
            self.main = scene.add_lips(p, frames[0], faces, color=SYNTH_COLOUR, point_size=dot, name="lips_main",
                                       drawing=drawing)
            bounds_pts = frames.reshape(-1, 3)
        else:
            self.main = scene.add_lips(p, original[0], faces, color=MAIN_COLOUR, point_size=dot, name="lips_main",
                                       drawing=drawing)
            self.second = scene.add_lips(p, frames[0], faces, color=SYNTH_COLOUR, offset=offset, point_size=dot,
                                         name="lips_second", drawing=drawing, labels=False)
            bounds_pts = np.concatenate([original.reshape(-1, 3), frames.reshape(-1, 3) + offset])
        lo, hi = bounds_pts.min(0), bounds_pts.max(0)
        if drawing is not None and drawing.kind == "sensors":  # the labels stand beside the sensors
            pad = 0.3 * float(np.ptp(bounds_pts[:, :2], axis=0).max())
            lo, hi = lo - [pad, pad, 0], hi + [pad, pad, 0]
        self.move_main = _mover(self.main, faces)
        self.move_second = None if self.second is None else _mover(self.second, faces)
        p.view_xy(render=False)
        p.reset_camera(render=False, bounds=[lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]])
        labelled = drawing is not None and drawing.kind == "sensors"
        # a surface, or sensors with their labels beside them, or bare dots: each needs its margin
        p.camera.zoom(1.3 if (faces is not None and len(faces)) else 1.0 if labelled else 1.05)
        self.text = p.add_text("", position=(8, 6), font_size=10, color="black")
        self.marker = None
        if panel:
            p.subplot(0, 1)
            if cloud is not None and len(cloud):
                dots = scene.add_point_markers(p, cloud, (0.72, 0.72, 0.75), point_size=2.0, name="cloud")
                dots.actor.prop.render_points_as_spheres = False  # flat dots: sprites cost a shader pass each
            if Y_original is not None:
                scene.add_trajectory(p, Y_original, scene.ORIGINAL_COLOUR, line_width=3.0, name="original")
            scene.add_trajectory(p, Y, scene.SYNTHETIC_COLOUR, line_width=3.0, name="synthetic")
            Yall = np.asarray(Y)[:, :3] if cloud is None or not len(cloud) else np.asarray(cloud)[:, :3]
            self.marker = scene.add_marker(p, np.asarray(Y)[0, :3], radius=0.04 * scene.scene_scale(Yall),
                                           color=(1.0, 0.8, 0.0))
            p.view_isometric(render=False)
            p.reset_camera(render=False)
            p.camera.zoom(1.6)

    def draw(self, main, second, y, caption):
        self.move_main(main)
        if second is not None:
            self.move_second(second)
        if self.marker is not None:
            self.marker.move(y)
        self.text.SetInput(caption)
        self.plotter.render()  # a no-op before the first screenshot, which shows the window once
        return self.plotter.screenshot(return_img=True)

    def close(self):
        self.plotter.close()


class _QuietWithoutDisplay:
    """Without an X display VTK tries X first and logs "bad X server connection" before it
    falls back to EGL; that warning says nothing to the user, so VTK's stderr log is held at
    errors while rendering (and only then)."""

    def __init__(self):
        import os
        import sys

        self.old = None
        if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            from vtkmodules.vtkCommonCore import vtkLogger

            self.old = vtkLogger.GetCurrentVerbosityCutoff()
            vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)

    def restore(self):
        if self.old is not None:
            from vtkmodules.vtkCommonCore import vtkLogger

            vtkLogger.SetStderrVerbosity(self.old)
            self.old = None


class _Encoder:
    """H.264 encoding and muxing in a second thread, so it overlaps the next frame's rendering
    (FFmpeg and VTK's renderer both run without holding the GIL)."""

    def __init__(self, out, stream, fps):
        import av

        self._av, self.out, self.stream, self.fps = av, out, stream, fps
        self.queue = queue.Queue(maxsize=4)
        self.error = None
        self.stop = False
        self.thread = threading.Thread(target=self._run, name="mp4-encoder", daemon=True)
        self.thread.start()

    def _run(self):
        av = self._av
        try:
            while True:
                item = self.queue.get()
                if item is None or self.stop:
                    return
                k, img = item
                vf = av.VideoFrame.from_ndarray(img, format="rgb24")
                vf.pts = k
                vf.time_base = 1 / self.fps
                self.out.mux(self.stream.encode(vf))
        except BaseException as exc:  # noqa: BLE001 - handed to the rendering thread
            self.error = exc

    def put(self, k, img):
        if self.error is not None:
            raise self.error
        self.queue.put((k, img))

    def finish(self):
        """Encode what is queued, flush the encoder; re-raise an encoder error."""
        self.queue.put(None)
        self.thread.join()
        if self.error is not None:
            raise self.error
        self.out.mux(self.stream.encode(None))

    def abort(self):
        self.stop = True
        while True:  # unblock the thread (it may wait on a full queue's consumer side)
            try:
                self.queue.get_nowait()
            except queue.Empty:
                break
        self.queue.put(None)
        self.thread.join()


def render_video(path, frames, *, rate: float, faces=None, dims: int = 3, roles=None, names=None, original=None,
                 Y=None, Y_original=None, cloud=None, audio=None, size=(640, 480), title: str = "", crf: int = 20,
                 progress=None, orientation=None, unit: str = "mm") -> Path:
    """Render a lip trajectory to an MP4 (H.264 + AAC), one video frame per trajectory frame.

    Parameters
    ----------
    path : str or Path
        Must end in ``.mp4``.
    frames : array of shape (n, dims * V)
        Lip frames of the trajectory (drawn red).
    rate : float
        Frames per second (the corpus rate); the video runs at this rate.
    faces : array of shape (F, 3), optional
        Triangles; without them the points are drawn as spheres.
    dims : {2, 3}
        Coordinates per point in ``frames``.
    roles, names : sequence of str, optional
        ``Corpus.point_roles`` / ``point_names``: sensors are drawn as the lip view draws them
        (:func:`app.models.lip_drawing.drawing_of`: spheres joined by straight lines, labelled, the lip
        aperture with its value).
    original : array of shape (n0, dims * V), optional
        The original utterance, drawn beside the trajectory on the left (as in the lip
        view's playback); the shorter sequence holds its last frame.
    Y : array of shape (n, >=3), optional
        The trajectory in F^y: adds a manifold panel with a marker at the current frame.
    Y_original : array of shape (n0, >=3), optional
        The original's path in F^y (black) in the manifold panel.
    cloud : array of shape (N, >=3), optional
        Corpus points drawn grey in the manifold panel (at most
        :data:`MAX_CLOUD_POINTS`, evenly subsampled).
    audio : str or Path, optional
        Audio file muxed as AAC (cut to the video's duration).
    size : (int, int)
        Pixels of one panel (rounded up to even numbers).
    title : str
        Caption prefix drawn with the time on every frame.
    crf : int
        H.264 constant rate factor (lower = better, 0..51).
    progress : callable, optional
        ``progress("render", done, total)``; raising from it (e.g. Ctrl-C) aborts and
        writes nothing.
    orientation : engine.recordings.orientation.AnatomicalFrame, optional
        The talker's frame (:func:`engine.recordings.orientation.anatomical_frame`): the lips are drawn
        in it, seen from the front (upper lip up, the talker's left on the right). None
        draws the data's x right, y up.
    unit : str
        The coordinates' unit, written with the lip aperture.

    Returns
    -------
    Path
    """
    import av

    path = Path(path)
    if path.suffix.lower() != ".mp4":
        raise ValueError(f"{path}: the video file must end in .mp4")
    fps = _frame_rate(rate)
    if not 0 <= int(crf) <= 51:
        raise ValueError(f"crf={crf!r}; expected 0..51 (20 is visually lossless for this content)")
    if len(size) != 2 or min(size) < 16 or max(size) > 4096:
        raise ValueError(f"size={size!r}; expected (width, height) in pixels, each 16..4096")
    if orientation is not None:  # the talker's frame: front view along -z, up +y
        frames = orientation.view_frames(np.asarray(frames))
        original = None if original is None else orientation.view_frames(np.asarray(original))
    F = _frames3(frames, dims, "frames")
    Fo = None if original is None else _frames3(original, dims, "original frames")
    if Fo is not None and Fo.shape[1] != F.shape[1]:
        raise ValueError(f"the original has {Fo.shape[1]} points per frame, the trajectory {F.shape[1]}")
    n = max(len(F), len(Fo) if Fo is not None else 0)
    if Y is not None:
        Y = np.asarray(Y, np.float64)
        if Y.ndim != 2 or Y.shape[1] < 3 or len(Y) != len(F):
            raise ValueError(f"Y must be ({len(F)}, >=3), one row per trajectory frame; got shape {Y.shape}")
    if cloud is not None and len(cloud) > MAX_CLOUD_POINTS:
        cloud = np.asarray(cloud)[np.linspace(0, len(cloud) - 1, MAX_CLOUD_POINTS).astype(np.int64)]
    samples = sample_rate = None
    if audio is not None:
        samples, sample_rate = decode_audio(audio)
        if sample_rate not in AAC_RATES:
            samples, sample_rate = decode_audio(audio, rate=48000)
        samples = samples[:, : int(round(n / float(fps) * sample_rate))]

    quiet = _QuietWithoutDisplay()
    try:
        drawing = None
        if roles is not None or names is not None or faces is not None:
            from app.models.lip_drawing import drawing_of

            drawing = drawing_of(F.mean(axis=0), dims=dims, faces=faces, roles=roles, names=names, unit=unit,
                                 facing_known=orientation is not None and orientation.source != "none")
        scene = _Scene(F, Fo, faces, Y, Y_original, cloud, size, drawing)
    except BaseException:
        quiet.restore()
        raise
    try:
        with atomic_write(path) as tmp:
            with av.open(str(tmp), mode="w", format="mp4") as out:
                h, w = scene.plotter.window_size[1], scene.plotter.window_size[0]
                vs = out.add_stream("libx264", rate=fps)
                vs.width, vs.height, vs.pix_fmt = w, h, "yuv420p"
                vs.options = {"crf": str(int(crf)), "preset": PRESET}
                vs.codec_context.time_base = 1 / fps
                aus = None
                if samples is not None and samples.shape[1]:
                    aus = out.add_stream("aac", rate=sample_rate)
                    aus.layout = "mono" if samples.shape[0] == 1 else "stereo"
                    samples = samples[:2]
                encoder = _Encoder(out, vs, fps)
                try:
                    for k in range(n):
                        main_k = F[min(k, len(F) - 1)] if Fo is None else Fo[min(k, len(Fo) - 1)]
                        second_k = None if Fo is None else F[min(k, len(F) - 1)]
                        y_k = None if Y is None else Y[min(k, len(Y) - 1), :3]
                        img = scene.draw(main_k, second_k, y_k, f"{title}  {k / float(fps):5.2f} s".strip())
                        if img.shape[:2] != (h, w):
                            raise RuntimeError(f"the renderer returned a {img.shape[1]}x{img.shape[0]} image "
                                               f"for a {w}x{h} window")
                        encoder.put(k, np.ascontiguousarray(img[..., :3]))
                        if progress is not None:
                            progress("render", k + 1, n)
                except BaseException:
                    encoder.abort()
                    raise
                encoder.finish()
                if aus is not None:
                    af = av.AudioFrame.from_ndarray(np.ascontiguousarray(samples), format="fltp",
                                                    layout=aus.layout.name)
                    af.sample_rate = sample_rate
                    af.pts = 0
                    af.time_base = Fraction(1, sample_rate)
                    out.mux(aus.encode(af))
                    out.mux(aus.encode(None))
    finally:
        scene.close()
        quiet.restore()
    return path
