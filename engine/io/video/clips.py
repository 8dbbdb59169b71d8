"""Video of a talking face -> lip landmarks in mm, head pose removed (``.mp4``, ``.mov``, ...).

:func:`read_video` decodes the frames one at a time with PyAV (never holding more than
the current frame), tracks the face with MediaPipe FaceMesh in video mode
(:class:`engine.io.video.facemesh.FaceTracker`), keeps the 80 refined lip landmarks and the 17
rigid reference landmarks per frame, removes head pose by a similarity Procrustes fit of
the reference landmarks to the video's speaker template in mm (:mod:`engine.recordings.headpose`),
and returns a corpus at the video's frame rate with the FaceMesh lip triangles as faces.

Frames without a face are never invented silently. Every run of them is reported (frame
indices and times) in ``Corpus.history``: a run inside the utterance of at most
``bridge_s`` seconds (default 0.1 s, shorter than a bilabial closure) is bridged by linear
interpolation of the head-pose-free lip landmarks; a longer run splits the utterance
(``<stem>_1``, ``<stem>_2``, ...); runs at the start or end are cut off. Phone times
and the audio follow each part.

The audio track (when the video has one and ``audio_dir`` is given) is decoded,
mixed to mono, resampled to ``audio_rate`` (16 kHz) and written as 16-bit PCM WAV per
utterance (``audio_dir/<utterance>.wav``), the form the other corpora store audio in.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from engine.files.atomic import write_wav_atomic
from engine.io.errors import ImportFormatError

__all__ = ["read_video", "read_videos", "head_pose_model", "iter_video_frames", "track_video", "VIDEO_EXTENSIONS",
           "DEFAULT_BRIDGE_S", "AUDIO_RATE", "find_gaps", "segments", "read_audio_track", "video_rate", "video_info"]

VIDEO_EXTENSIONS = (".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv")
#: longest run of face-less frames bridged by interpolation (s)
DEFAULT_BRIDGE_S = 0.1
#: sample rate of the stored audio (Hz)
AUDIO_RATE = 16000


def _require_av():
    try:
        import av
    except ImportError as exc:  # pragma: no cover - av is a core dependency
        raise ImportError(f"video import needs PyAV ({exc}); install it with: pip install -e '.[video]'") from None
    return av


def _open(path):
    av = _require_av()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if not path.is_file():
        raise ImportFormatError(path, "is not a regular file; expected a video file (.mp4, .mov, .avi, .mkv, ...)")
    if path.stat().st_size == 0:
        raise ImportFormatError(path, "is empty (0 bytes); expected a video file")
    try:
        container = av.open(str(path), mode="r")
    except (av.error.FFmpegError, UnicodeDecodeError) as exc:
        raise ImportFormatError(path, f"cannot be read as a video ({exc}); expected a video file such as "
                                ".mp4, .mov, .avi or .mkv") from None
    if not container.streams.video:
        container.close()
        raise ImportFormatError(path, "holds no video stream; expected a video of a face")
    return container


def _frames(container, path, audio=None):
    """Yield ``(index, rgb (H, W, 3) uint8)`` for each frame of the open ``container``'s video stream.

    With ``audio`` (an :class:`_AudioTrack` of the same container), its stream's packets
    are decoded in the same pass. Decoding errors become an :class:`ImportFormatError`
    naming the frame (video) or saying the audio is damaged.
    """
    av = _require_av()
    stream = container.streams.video[0]
    stream.thread_type = "AUTO"
    streams = [stream] + ([audio.stream] if audio is not None and audio.stream is not None else [])
    k = 0
    try:
        for packet in container.demux(*streams):
            if packet.stream.index != stream.index:
                audio.add(packet, path)
                continue
            for frame in packet.decode():
                yield k, frame.to_ndarray(format="rgb24")
                k += 1
    except av.error.FFmpegError as exc:
        raise ImportFormatError(path, f"video data is damaged ({exc}); {k} frames could be decoded",
                                frame=k) from None


def iter_video_frames(path):
    """Yield ``(index, rgb (H, W, 3) uint8)`` for each frame of ``path``, decoding one at a time.

    The rate is :func:`video_rate`. Decoding errors become an
    :class:`ImportFormatError` naming the frame.
    """
    container = _open(path)
    try:
        yield from _frames(container, path)
    finally:
        container.close()


def _stream_info(container, path) -> tuple[float, int]:
    """:func:`video_info` of an open container."""
    st = container.streams.video[0]
    r = st.average_rate or st.guessed_rate or st.base_rate
    n = int(st.frames or 0)
    if not n and st.duration and st.time_base and r:
        n = int(float(st.duration * st.time_base) * float(r))
    if not r or float(r) <= 0:
        raise ImportFormatError(path, "the video stream states no frame rate; expected a constant-rate video")
    rate = float(r)
    k = round(rate)
    return (float(k) if abs(rate - k) < 1e-3 * k else rate), n


def video_info(path) -> tuple[float, int]:
    """``(rate, frames)``: the video stream's frame rate (Hz; its average rate, else its guessed
    rate) and its stated frame count (else duration x rate; 0 when unknown, for progress only)."""
    container = _open(path)
    try:
        return _stream_info(container, path)
    finally:
        container.close()


def video_rate(path) -> float:
    """The video stream's frame rate (Hz), see :func:`video_info`."""
    return video_info(path)[0]


def _track(frames, path, total, tracker, progress):
    """:func:`track_video` over ``frames`` (``(index, rgb)`` pairs); ``total``: the stated frame count."""
    from engine.io.video.facemesh import TRACKED_POINTS, FaceTracker
    from engine.progress import report

    own = tracker is None
    tracker = tracker or FaceTracker()
    rows, found = [], []
    nan = np.full((len(TRACKED_POINTS), 3), np.nan, dtype=np.float32)
    try:
        for k, rgb in frames:
            lm = tracker.track(rgb)
            rows.append(nan if lm is None else lm)
            found.append(lm is not None)
            if progress is not None and k % 10 == 0:
                report(progress, f"tracking the face in {Path(path).name}", k, max(total, k + 1))
    finally:
        if own:
            tracker.close()
    if not rows:
        raise ImportFormatError(path, "holds no decodable video frames; expected a video of a face")
    report(progress, f"tracking the face in {Path(path).name}", len(rows), len(rows))
    return np.stack(rows), np.asarray(found, dtype=bool)


def track_video(path, *, tracker=None, progress=None):
    """Track the face in every frame of ``path``.

    Returns
    -------
    landmarks : ndarray (N, P, 3) float32
        :data:`engine.io.video.facemesh.TRACKED_POINTS` per frame (NaN where no face was found).
    found : ndarray (N,) bool
    """
    container = _open(path)
    try:
        total = _stream_info(container, path)[1] if progress is not None else 0
        return _track(_frames(container, path), path, total, tracker, progress)
    finally:
        container.close()


def find_gaps(found) -> list[tuple[int, int]]:
    """``[start, stop)`` frame ranges of consecutive False in ``found``."""
    f = np.asarray(found, dtype=bool)
    d = np.diff(np.concatenate([[1], f.astype(np.int8), [1]]))
    return list(zip(np.flatnonzero(d == -1).tolist(), np.flatnonzero(d == 1).tolist()))


def segments(found, max_bridge: int) -> tuple[list[tuple[int, int]], list[tuple[int, int, str]]]:
    """Utterance parts and what happens to each run of face-less frames.

    Parameters
    ----------
    found : (N,) bool
    max_bridge : int
        Longest interior run (frames) bridged by interpolation.

    Returns
    -------
    parts : list of [start, stop) frame ranges kept (gaps inside them are bridged)
    gaps : list of (start, stop, action), action in {"bridged", "split", "cut"}
    """
    f = np.asarray(found, dtype=bool)
    n = f.size
    gaps = []
    parts = []
    cur = None
    for a, b in find_gaps(f):
        if a == 0 or b == n:
            gaps.append((a, b, "cut"))
            continue
        if b - a <= max_bridge:
            gaps.append((a, b, "bridged"))
            continue
        gaps.append((a, b, "split"))
    if f.any():
        first, last = int(np.argmax(f)), int(n - np.argmax(f[::-1]))
        cur = first
        for a, b, act in gaps:
            if act == "split":
                parts.append((cur, a))
                cur = b
        parts.append((cur, last))
    return parts, gaps


class _AudioTrack:
    """The first audio stream of an open container (``stream``, None when it has none), decoded
    packet by packet to mono int16 at ``rate`` Hz."""

    def __init__(self, container, rate: int):
        av = _require_av()
        self.stream = container.streams.audio[0] if container.streams.audio else None
        self._resampler = av.AudioResampler(format="s16", layout="mono", rate=int(rate))
        self._chunks: list[np.ndarray] = []

    def _keep(self, frame):
        for out in self._resampler.resample(frame):
            self._chunks.append(out.to_ndarray().reshape(-1))

    def add(self, packet, path) -> None:
        """Decode one packet of :attr:`stream`."""
        av = _require_av()
        try:
            for frame in packet.decode():
                self._keep(frame)
        except av.error.FFmpegError as exc:
            raise ImportFormatError(path, f"audio data is damaged ({exc})") from None

    def samples(self, path) -> np.ndarray | None:
        """All samples decoded (the resampler flushed), or None when there is no audio stream."""
        if self.stream is None:
            return None
        av = _require_av()
        try:
            self._keep(None)
        except av.error.FFmpegError as exc:
            raise ImportFormatError(path, f"audio data is damaged ({exc})") from None
        return np.concatenate(self._chunks).astype(np.int16) if self._chunks else np.zeros(0, np.int16)

    def read(self, container, path) -> np.ndarray | None:
        """Decode the whole stream from ``container`` (nothing else decoded) and return :meth:`samples`."""
        if self.stream is None:
            return None
        av = _require_av()
        try:
            for packet in container.demux(self.stream):
                self.add(packet, path)
        except av.error.FFmpegError as exc:
            raise ImportFormatError(path, f"audio data is damaged ({exc})") from None
        return self.samples(path)


def read_audio_track(path, rate: int = AUDIO_RATE) -> np.ndarray | None:
    """The video's first audio stream as mono int16 at ``rate`` Hz, or None when it has none."""
    container = _open(path)
    try:
        return _AudioTrack(container, rate).read(container, path)
    finally:
        container.close()


def _span(a, b, rate):
    frames = f"frame {a}" if b - a == 1 else f"frames {a}-{b - 1}"
    return f"{frames} ({a / rate:.3f}-{b / rate:.3f} s)"


def head_pose_model(interocular_mm: float = 63.0):
    """An unfitted :class:`engine.recordings.headpose.HeadPose` for
    :data:`engine.io.video.facemesh.REFERENCE_POINTS`."""
    from engine.io.video.facemesh import EYE_CORNERS, REFERENCE_POINTS
    from engine.recordings.headpose import HeadPose

    pos = {p: k for k, p in enumerate(REFERENCE_POINTS)}
    eyes = tuple((pos[a], pos[b]) for a, b in EYE_CORNERS)
    return HeadPose(interocular_mm=interocular_mm, eye_points=eyes, up_point=pos[10])


def read_videos(paths, *, rate=None, alignment=None, tier=None, interocular_mm: float = 63.0,
                bridge_s: float = DEFAULT_BRIDGE_S, audio_dir=None, audio_rate: int = AUDIO_RATE, progress=None,
                resample: float | None = None, skip_bad: bool = False):
    """Several videos of one speaker (e.g. a folder), one utterance each, with one pooled template.

    Every video is tracked first (only its landmarks are kept); the speaker template is then
    fitted to the reference landmarks of all of them together, and each video is read
    through it (:func:`read_video` with ``landmarks=`` and ``pose=``). ``alignment`` is None
    (each video's own ``<stem>.TextGrid`` / ``.lab``), False, or one path / phone list per
    video. ``resample``: the frame rate (Hz) each video is resampled to before they are
    joined (videos at different rates can be joined only so); None keeps their rate, which
    must then be the same for all. ``skip_bad``: a video that cannot be read (damaged, no face) is
    left out and said in the corpus history (``lipspace import --skip-bad``), instead of stopping
    the import. Other parameters as :func:`read_video`.

    Returns
    -------
    Corpus of the videos in order (joined by :func:`engine.io.concat`).
    """
    from engine.io.combine import concat
    from engine.io.video.facemesh import LIP_POINTS
    from engine.recordings.headpose import check_interocular

    check_interocular(interocular_mm)
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("read_videos: no video files given")
    if isinstance(alignment, (list, tuple)) and len(alignment) == len(paths) and \
            all(a is False or a is None or isinstance(a, (str, Path)) for a in alignment):
        aligns = list(alignment)
    elif isinstance(alignment, (str, Path)):
        raise ValueError(f"one alignment file for {len(paths)} videos; give one per video or put each video's "
                         "<stem>.TextGrid / .lab beside it")
    else:
        aligns = [alignment] * len(paths)
    skipped = []  # (path, why): left out with skip_bad

    def readable(p, read):
        try:
            return read()
        except ImportFormatError as exc:
            if not skip_bad:
                raise
            skipped.append((p, exc.detail))
            return None

    if skip_bad:  # the unreadable ones are found while tracking, said once all are read
        infos = [readable(p, lambda p=p: video_info(p)) for p in paths]
        keep = [k for k, i in enumerate(infos) if i is not None]
        paths, aligns = [paths[k] for k in keep], [aligns[k] for k in keep]
    if resample is None:  # refuse before minutes of tracking
        rates = [video_info(p)[0] for p in paths]
        if len({round(r, 6) for r in rates}) > 1:
            desc = ", ".join(f"{p.name} {r:.4g} Hz" for p, r in zip(paths, rates))
            raise ImportFormatError(paths[0].parent, f"its videos have different frame rates ({desc}); they can be "
                                    "joined only at one rate: resample them to one while reading (lipspace import "
                                    "--resample 60, the analysis rate, or another rate)")
    # a fresh tracker per video (video mode tracks from the previous frame: never across two files)
    tracked = [readable(p, lambda p=p: track_video(p, progress=progress)) for p in paths]
    n_lip = len(LIP_POINTS)
    refs = [t[0][t[1], n_lip:] for t in tracked if t is not None and t[1].any()]
    if not refs:
        raise ImportFormatError(paths[0].parent if paths else "the folder",
                                f"no face found in any frame of its {len(tracked)} readable videos; expected videos "
                                "of one face seen from the front")
    pose = head_pose_model(interocular_mm).fit(np.concatenate(refs))
    parts = [readable(p, lambda p=p, a=a, t=t: read_video(
        p, rate=rate, alignment=a, tier=tier, interocular_mm=interocular_mm, bridge_s=bridge_s, audio_dir=audio_dir,
        audio_rate=audio_rate, landmarks=t, pose=pose, resample=resample))
        for p, a, t in zip(paths, aligns, tracked) if t is not None]
    parts = [c for c in parts if c is not None]
    if not parts:
        raise ImportFormatError(paths[0].parent, f"none of its {len(paths) + len(skipped)} videos could be read")
    corpus = concat(parts)
    for p, why in skipped:  # in the history, printed by lipspace import
        corpus.history.append(f"{p}: skipped (--skip-bad): {why}")
    return corpus


def read_video(path, *, rate=None, alignment=None, tier=None, interocular_mm: float = 63.0,
               bridge_s: float = DEFAULT_BRIDGE_S, audio_dir=None, audio_rate: int = AUDIO_RATE,
               tracker=None, progress=None, landmarks=None, pose=None, resample: float | None = None):
    """Read a video of one talking face as a corpus of lip landmarks (mm, head pose removed).

    Parameters
    ----------
    path : str or Path
        Video file (anything FFmpeg decodes: .mp4, .mov, .avi, .mkv, .webm ...), one
        speaker facing the camera.
    rate : float, optional
        Must agree with the video's frame rate when given (frames are kept at that rate).
    alignment : None, False, path or sequence of PhoneInterval
        None: ``<stem>.TextGrid`` / ``.lab`` beside the video, if any.
    tier : str, optional
        TextGrid tier of the phones.
    interocular_mm : float, default 63
        Assumed distance between the eye centres (mm): the scale of the output.
    bridge_s : float, default 0.1
        Longest run of face-less frames inside the utterance bridged by interpolation;
        longer runs split it.
    audio_dir : str or Path, optional
        Where to write each utterance's audio (``<utterance>.wav``); None: not stored.
    audio_rate : int, default 16000
        Sample rate (Hz) of the stored audio.
    tracker : FaceTracker, optional
        Reuse a tracker (default: a new one, closed at the end).
    progress : callable, optional
        ``progress(stage, done, total)``; raise ``engine.progress.Cancelled`` to stop.
    landmarks : (ndarray (N, 97, 3), ndarray (N,) bool), optional
        This video's :func:`track_video` result, when already tracked.
    pose : HeadPose, optional
        A fitted speaker template (:func:`head_pose_model`) to use instead of fitting one
        to this video's frames (:func:`read_videos` pools one over a speaker's videos).
    resample : float, optional
        Frame rate (Hz) the result is resampled to (:func:`engine.io.resample`, per
        utterance); None keeps the video's rate.

    Returns
    -------
    Corpus
        Frames (n, 240) float32: the 80 lip landmarks of :data:`engine.io.video.facemesh.LIP_POINTS`
        (x right, y up, z toward the camera, mm, origin between the eyes), faces
        :data:`engine.io.video.facemesh.LIP_FACES`, point roles, ``registration`` and ``history``
        describing the head-pose fit, the scale assumption and every face-less run.

    Raises
    ------
    ImportFormatError
        Empty, damaged or non-video file; no face in any frame; too few frames with a face.
    """
    from engine.io._util import check_rate, fit_phones
    from engine.io.readers.alignment import resolve_alignment
    from engine.io.video.facemesh import LIP_FACES, LIP_NAMES, LIP_POINTS, LIP_ROLES, REFERENCE_POINTS
    from engine.recordings.corpus import Corpus, CorpusError, Utterance
    from engine.recordings.headpose import check_interocular

    path = Path(path)
    check_interocular(interocular_mm)  # before minutes of tracking
    bridge_s = float(bridge_s)
    if not np.isfinite(bridge_s) or bridge_s < 0:
        raise ValueError(f"bridge_s={bridge_s!r}; expected a duration in seconds >= 0 (default {DEFAULT_BRIDGE_S})")
    container = _open(path)  # once: the rate, the frames tracked and the audio track in one pass
    try:
        native, total = _stream_info(container, path)
        native = check_rate(path, native, rate)
        track = _AudioTrack(container, audio_rate) if audio_dir is not None else None
        if landmarks is None:
            lm, found = _track(_frames(container, path, track), path, total, tracker, progress)
            pcm = track.samples(path) if track is not None else None
        else:
            lm, found = landmarks
            pcm = track.read(container, path) if track is not None else None
    finally:
        container.close()
    n = len(found)
    if not found.any():
        raise ImportFormatError(path, f"no face found in any of its {n} frames; expected a video of one face seen "
                                "from the front, lit well enough to see the lips")
    n_lip = len(LIP_POINTS)
    ref = lm[found, n_lip:]
    pooled = pose is not None
    if pose is None:
        pose = head_pose_model(interocular_mm).fit(ref)
    lips = np.full((n, n_lip, 3), np.nan)
    lips[found] = pose.transform(ref, lm[found, :n_lip])
    max_bridge = int(np.floor(bridge_s * native + 1e-9))
    parts, gaps = segments(found, max_bridge)
    history = [f"read {path.name}: {n} frames at {native:g} Hz, face found in {int(found.sum())}"]
    for a, b, act in gaps:
        what = {"bridged": f"bridged by linear interpolation (<= {bridge_s:g} s)",
                "split": f"longer than {bridge_s:g} s: the utterance is split there",
                "cut": "at the start or end of the video: cut off"}[act]
        history.append(f"{path.name}: no face in {_span(a, b, native)}: {what}")
        if act == "bridged":
            w = (np.arange(a, b) - (a - 1)) / (b - a + 1)
            lips[a:b] = (1 - w)[:, None, None] * lips[a - 1] + w[:, None, None] * lips[b]
    kept = [(a, b) for a, b in parts if b - a >= 2]
    for a, b in parts:
        if b - a < 2:
            history.append(f"{path.name}: {_span(a, b, native)} dropped: a part of fewer than 2 frames")
    if not kept:
        raise ImportFormatError(path, f"a face was found in only {int(found.sum())} of {n} frames, never in 2 "
                                "consecutive ones; expected a video where the face stays in view")
    desc = (f"head pose removed per frame: similarity Procrustes (rotation, translation, scale) of "
            f"{len(REFERENCE_POINTS)} FaceMesh reference landmarks (forehead, nose bridge, temples, eye corners) to "
            f"the speaker template{f' pooled over {pose.n_frames_} frames' if pooled else ''}, residual "
            f"{pose.residual_mm_:.2g} mm rms; mm from an assumed inter-ocular distance of "
            f"{float(pose.interocular_mm):g} mm")
    history.append(f"registration: {desc}")
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    if audio_dir is not None and pcm is None:
        history.append(f"{path.name}: no audio track")
    utts, rows = [], []
    start = 0
    for j, (a, b) in enumerate(kept):
        uid = path.stem if len(kept) == 1 else f"{path.stem}_{j + 1}"
        t0, t1 = a / native, b / native
        ph = [type(p)(p.start - t0, p.end - t0, p.label) for p in phones if p.end > t0 and p.start < t1]
        cut = t1 - t0 if b < n else np.inf  # a part ended by a gap: its phones end there (no overrun)
        ph = [type(p)(max(p.start, 0.0), min(p.end, cut), p.label) for p in ph]
        wav = None
        if pcm is not None:
            s0, s1 = int(round(t0 * audio_rate)), int(round(t1 * audio_rate))
            wav = str(write_wav_atomic(Path(audio_dir) / f"{uid}.wav", pcm[s0:s1], audio_rate).resolve())
        utts.append(Utterance(uid, start, start + b - a, fit_phones(ph, b - a, native), wav, ""))
        rows.append(lips[a:b])
        start += b - a
    frames = np.concatenate(rows).reshape(start, -1).astype(np.float32)
    try:
        c = Corpus(frames=frames, rate=native, utterances=utts, dims=3, faces=LIP_FACES.copy(),
                   point_names=list(LIP_NAMES), name=path.stem, point_roles=list(LIP_ROLES),
                   registration=desc, history=history)
    except CorpusError as exc:
        raise ImportFormatError(path, str(exc)) from None
    if resample is not None and abs(float(resample) - native) > 1e-9 * native:
        from engine.io.rates import resample as resample_corpus

        try:
            c = resample_corpus(c, float(resample))
        except CorpusError as exc:
            raise ImportFormatError(path, str(exc)) from None
    return c
