"""Live mirror, Qt-free part: frames of a camera (or a video played as a stream) projected
into an already-built manifold as they arrive.

* :class:`LiveProjector` — one face frame's tracked landmarks -> the manifold's F^y and
  state: head pose removed against the speaker template learnt from the first
  ``calibration_frames`` frames with a face (:class:`engine.recordings.headpose.HeadPose`, same
  canonical frame and mm scale as ``lipspace import`` gives video corpora), the shape
  space, the velocity from the previous live frame (scaled to the manifold's frame
  rate), the dynamic features, the embedding's out-of-sample transform and the nearest
  state. A frame without a face restarts the velocity.
* :class:`LatestFrame` — a one-frame mailbox between the reader and the tracker: a new
  frame replaces one not yet taken, which is counted as dropped. So the mirror never
  falls behind the camera; when tracking is slower than the video it drops frames and
  says how many.
* :class:`LiveSession` — a reader thread (PyAV: ``/dev/videoN`` for a camera number, or
  a file paced at its own frame rate) and a tracking thread; ``poll()`` returns the
  samples projected since the last call and :class:`LiveStats` (received, processed,
  dropped, without face, processing fps).
"""
from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["LiveProjector", "LiveSample", "LiveStats", "LatestFrame", "LiveSession", "camera_source",
           "check_video_manifold", "FUTURE_HOPS"]

#: hops of the future hemisphere drawn (states further away are shown as unreachable-in-view)
FUTURE_HOPS = 12


def check_video_manifold(manifold) -> None:
    """ValueError unless ``manifold`` was built from a video import (the 80 FaceMesh lip points)."""
    from engine.io.video.facemesh import LIP_NAMES

    c = manifold.corpus_
    if c.n_points != len(LIP_NAMES) or c.dims != 3 or list(c.point_names or []) != list(LIP_NAMES):
        raise ValueError(f"the manifold was built from {c.n_points} {c.dims}-D points "
                         f"({', '.join((c.point_names or ['unnamed'])[:3])} ...); the live mirror needs a manifold "
                         "built from a video import (lipspace import talk.mp4 -o c.npz; lipspace build c.npz)")


@dataclass(frozen=True)
class LiveSample:
    """One projected live frame: its index in the stream, time (s), F^y (k,), state."""

    index: int
    time: float
    y: np.ndarray
    state: int


@dataclass(frozen=True)
class LiveStats:
    received: int
    processed: int
    dropped: int
    no_face: int
    fps: float
    calibrating: int
    finished: bool
    error: str = ""

    def line(self) -> str:
        """The status line the window shows."""
        if self.error:
            return f"live: {self.error}"
        if self.calibrating:
            return f"live: learning the head template ({self.calibrating} frames to go); dropped {self.dropped}"
        end = ", stream ended" if self.finished else ""
        return (f"live: {self.fps:.1f} fps processed, {self.processed} of {self.received} frames, "
                f"dropped {self.dropped}, no face {self.no_face}{end}")


class LiveProjector:
    """Tracked landmarks of live frames -> F^y and states of a built manifold.

    Parameters
    ----------
    manifold : Manifold
        Fitted on a video corpus (:func:`check_video_manifold`).
    rate : float
        Frame rate of the live stream (Hz); velocities are rescaled to the manifold's.
    interocular_mm : float, default 63
        The scale assumption (as on import).
    calibration_frames : int, default 30
        Face frames averaged into the head template before projecting.
    """

    def __init__(self, manifold, *, rate: float, interocular_mm: float = 63.0, calibration_frames: int = 30):
        check_video_manifold(manifold)
        rate = float(rate)
        if not np.isfinite(rate) or rate <= 0:
            raise ValueError(f"rate={rate!r}; expected the stream's frame rate in Hz (> 0)")
        if int(calibration_frames) < 1:
            raise ValueError(f"calibration_frames={calibration_frames!r}; expected an integer >= 1")
        self.manifold = manifold
        self.rate = rate
        from engine.recordings.headpose import check_interocular

        self.interocular_mm = check_interocular(interocular_mm)
        self.calibration_frames = int(calibration_frames)
        self._calib = []
        self._pose = None
        self._prev = None
        self._state_dims = manifold.states_.centroids_.shape[1]
        self._velocity_scale = np.float32(rate / float(manifold.corpus_.rate))

    @property
    def calibrating(self) -> int:
        """Face frames still needed before projecting (0 once the template is learnt)."""
        return 0 if self._pose is not None else self.calibration_frames - len(self._calib)

    def _fit_pose(self):
        from engine.io.video.clips import head_pose_model
        from engine.io.video.facemesh import LIP_POINTS

        ref = np.stack(self._calib)[:, len(LIP_POINTS):]
        self._pose = head_pose_model(self.interocular_mm).fit(ref)
        self._calib = []

    def push(self, landmarks, index: int = 0, t: float = 0.0) -> LiveSample | None:
        """Project one frame's :data:`engine.io.video.facemesh.TRACKED_POINTS` (P, 3); None = no face.

        Returns the :class:`LiveSample`, or None while calibrating or without a face.
        """
        from engine.io.video.facemesh import LIP_POINTS

        if landmarks is None:
            self._prev = None
            return None
        lm = np.asarray(landmarks, dtype=np.float64)
        if self._pose is None:
            self._calib.append(lm)
            if len(self._calib) >= self.calibration_frames:
                self._fit_pose()
            return None
        n_lip = len(LIP_POINTS)
        lips = self._pose.transform(lm[None, n_lip:], lm[None, :n_lip])[0]
        m = self.manifold
        Fx = m.shape_.transform(lips.reshape(1, -1).astype(np.float32))
        if self._prev is None:
            V = np.zeros_like(Fx)
        else:  # per manifold frame; a dropped frame in between spreads the step over the frames missed
            prev_index, prev_fx = self._prev
            V = (Fx - prev_fx) * (self._velocity_scale / max(int(index) - prev_index, 1))
        self._prev = (int(index), Fx)
        G = m.dynamics_.transform_pair(Fx, V)
        y = np.asarray(m.embedding_.transform(G))[0]
        state = int(m.states_.predict(y[None, :self._state_dims])[0])
        return LiveSample(int(index), float(t), y.astype(np.float32), state)

    def future(self, state: int, hops: int = FUTURE_HOPS) -> np.ndarray:
        """Hop distance (K,) from ``state`` to every state, ``inf`` beyond ``hops`` or unreachable."""
        d = np.asarray(self.manifold.states_.future(int(state)), dtype=np.float64)
        d[d > hops] = np.inf
        return d


class LatestFrame:
    """A one-frame mailbox: ``put`` replaces a frame not yet taken (counted in ``dropped``)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._item = None
        self.dropped = 0
        self.closed = False

    def put(self, item) -> None:
        with self._cond:
            if self._item is not None:
                self.dropped += 1
            self._item = item
            self._cond.notify()

    def take(self, timeout: float | None = None):
        """The newest frame, waiting up to ``timeout`` s; None when closed and empty or timed out."""
        with self._cond:
            if self._item is None and not self.closed:
                self._cond.wait(timeout)
            item, self._item = self._item, None
            return item

    def close(self) -> None:
        with self._cond:
            self.closed = True
            self._cond.notify_all()


def camera_source(spec) -> tuple[str, dict, bool]:
    """``(url, av.open options, paced)`` for ``--camera``: a camera number or a video file.

    A number N opens ``/dev/videoN`` (Video4Linux); a file is played as a stream at its
    own frame rate (paced).
    """
    s = str(spec).strip()
    if s.isdigit():
        return f"/dev/video{int(s)}", {"format": "v4l2"}, False
    p = Path(s)
    if not p.is_file():
        raise FileNotFoundError(f"--camera {s}: no camera number and no such video file")
    return str(p), {}, True


class LiveSession:
    """Read, track and project a live stream in two background threads.

    Parameters
    ----------
    manifold : Manifold
        Built from a video corpus.
    source : int or str
        Camera number or video file (see :func:`camera_source`).
    tracker_factory : callable, optional
        Returns an object with ``track(rgb) -> (P, 3) | None`` and ``close()``
        (default :class:`engine.io.video.facemesh.FaceTracker`); made in the tracking thread.
    max_samples : int
        Samples kept for :meth:`poll` between calls.
    calibration_frames : int
        See :class:`LiveProjector`.
    """

    def __init__(self, manifold, source, *, tracker_factory=None, interocular_mm: float = 63.0,
                 calibration_frames: int = 30, max_samples: int = 10000):
        check_video_manifold(manifold)
        self.url, self._opts, self.paced = camera_source(source)
        self.manifold = manifold
        self._factory = tracker_factory
        self._iod = interocular_mm
        self._calib = calibration_frames
        self._mail = LatestFrame()
        self._out = deque(maxlen=max_samples)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.received = self.processed = self.no_face = 0
        self._times = deque(maxlen=30)
        self.rate = None
        self.error = ""
        self.finished = False
        self.projector = None
        self._threads = []

    # ---------------------------------------------------------------- threads
    def start(self) -> LiveSession:
        import av

        try:
            container = av.open(self.url, mode="r", **self._opts)
        except (av.error.FFmpegError, OSError) as exc:
            raise ValueError(f"cannot open {self.url} as a video stream ({exc})") from None
        if not container.streams.video:
            container.close()
            raise ValueError(f"{self.url} holds no video stream")
        st = container.streams.video[0]
        r = st.average_rate or st.guessed_rate or st.base_rate or 30
        self.rate = float(r)
        self.projector = LiveProjector(self.manifold, rate=self.rate, interocular_mm=self._iod,
                                       calibration_frames=self._calib)
        self._threads = [threading.Thread(target=self._read, args=(container,), name="live-read", daemon=True),
                         threading.Thread(target=self._track, name="live-track", daemon=True)]
        for th in self._threads:
            th.start()
        return self

    def _read(self, container):
        import av

        t0 = time.perf_counter()
        try:
            for k, frame in enumerate(container.decode(video=0)):
                if self._stop.is_set():
                    break
                if self.paced:  # a file plays at its own rate, as a camera would deliver it
                    wait = t0 + k / self.rate - time.perf_counter()
                    if wait > 0:
                        time.sleep(wait)
                self.received += 1
                self._mail.put((k, k / self.rate, frame.to_ndarray(format="rgb24")))
        except av.error.FFmpegError as exc:
            self.error = f"the stream failed after {self.received} frames ({exc})"
        finally:
            container.close()
            self._mail.close()

    def _track(self):
        try:
            if self._factory is None:
                from engine.io.video.facemesh import FaceTracker

                tracker = FaceTracker()
            else:
                tracker = self._factory()
        except Exception as exc:  # noqa: BLE001 - shown in the window's status line, never a crash
            self.error = str(exc)
            self._stop.set()
            return
        try:
            while not self._stop.is_set():
                item = self._mail.take(timeout=0.2)
                if item is None:
                    if self._mail.closed:
                        break
                    continue
                k, t, rgb = item
                lm = tracker.track(rgb)
                if lm is None:
                    self.no_face += 1
                sample = self.projector.push(lm, k, t)
                with self._lock:
                    self.processed += 1
                    self._times.append(time.perf_counter())
                    if sample is not None:
                        self._out.append(sample)
        finally:
            tracker.close()
            self.finished = True

    # ---------------------------------------------------------------- queries
    def poll(self) -> tuple[list[LiveSample], LiveStats]:
        """Samples projected since the last call, and the counters."""
        with self._lock:
            out = list(self._out)
            self._out.clear()
            ts = list(self._times)
        fps = (len(ts) - 1) / (ts[-1] - ts[0]) if len(ts) > 1 and ts[-1] > ts[0] else 0.0
        calib = self.projector.calibrating if self.projector is not None else 0
        return out, LiveStats(self.received, self.processed, self._mail.dropped, self.no_face, fps, calib,
                              self.finished, self.error)

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._mail.close()
        for th in self._threads:
            th.join(timeout)
