"""espeak-ng's library speaking given phones, with the time at which each phone starts.

The espeak-ng program tells nothing about where its phones fall in the sound (without
MBROLA voices); its library (``libespeak-ng.so.1``, installed with espeak-ng) does: with
phoneme events switched on, every phone it speaks comes with its mnemonic and its first
sample. This module speaks phone strings in espeak-ng's own phoneme notation
(``[[h'Vt]]``) and returns the samples and those phone starts.

:data:`ESPEAK_PHONE` maps each phone of the talker's set (:data:`engine.phonetics.phones.PHONES`)
to one espeak-ng phoneme of its British English voice (``en``): the diphthongs (``ay``
``aI``, ``ea`` ``e@`` ...) and the affricates (``ch`` ``tS``, ``jh`` ``dZ``) are single
phonemes there too, so one talker phone is one espeak-ng phone event.

The library is not thread-safe and keeps global state, so it is never loaded into the
calling process: :class:`EspeakWorker` runs ``python -m engine.phonetics.espeak_phones`` and talks
to it through pipes (one request at a time; one worker per thread).
"""
from __future__ import annotations

import ctypes
import ctypes.util
import json
import os
import struct
import subprocess
import sys
import tempfile
import threading

__all__ = ["ESPEAK_PHONE", "PAUSE_MNEMONIC", "LIBRARY_NAME", "espeak_library", "EspeakWorker", "EspeakLibraryError"]

#: The file name of espeak-ng's shared library (Debian/Ubuntu package libespeak-ng1).
LIBRARY_NAME = "libespeak-ng.so.1"

#: Talker phone -> espeak-ng phoneme mnemonic (voice ``en``, Received Pronunciation).
ESPEAK_PHONE = {
    # consonants
    "p": "p", "b": "b", "m": "m", "ch": "tS", "jh": "dZ", "s": "s", "z": "z", "sh": "S", "zh": "Z",
    "f": "f", "v": "v", "th": "T", "dh": "D", "k": "k", "g": "g", "t": "t", "d": "d", "r": "r",
    "w": "w", "n": "n", "ng": "N", "hh": "h", "l": "l", "y": "j",
    # vowels of the paper's British set
    "aa": "A:", "ae": "a", "ah": "V", "ao": "O:", "aw": "aU", "ay": "aI", "ax": "@", "ea": "e@",
    "eh": "E", "ey": "eI", "ia": "i@", "ih": "I", "iy": "i:", "oh": "0", "ow": "oU", "oy": "OI",
    "ua": "U@", "uh": "U",
    # the two the CMU dictionary adds
    "uw": "u:", "er": "3:",
    # a pause inside a sentence
    "sil": "_",
}
#: The mnemonic espeak-ng reports for a short pause.
PAUSE_MNEMONIC = "_"

_PHONEME_EVENT = 7
_LIST_TERMINATED = 0
_AUDIO_OUTPUT_SYNCHRONOUS = 2
_INITIALIZE_PHONEME_EVENTS = 0x0001
_CHARS_UTF8, _PHONEMES = 0x1, 0x100
_HEADER = struct.Struct("<II")


class EspeakLibraryError(OSError):
    """The espeak-ng library could not be loaded or failed to speak."""


def espeak_library() -> str | None:
    """The espeak-ng library to load (a name ``ctypes`` finds), or None when it is not installed.

    Looked up without loading it (``ctypes.util.find_library``: the linker's cache).
    """
    return ctypes.util.find_library("espeak-ng") or None


# ------------------------------------------------------------------ worker process side
class _EventId(ctypes.Union):
    _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p), ("string", ctypes.c_char * 8)]


class _Event(ctypes.Structure):
    """``espeak_EVENT`` of speak_lib.h (API revision 12, espeak-ng 1.49-1.52)."""

    _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint), ("text_position", ctypes.c_int),
                ("length", ctypes.c_int), ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                ("user_data", ctypes.c_void_p), ("id", _EventId)]


_Callback = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(_Event))


def _serve(library: str, voice: str, stdin, stdout) -> None:
    """Answer requests (one JSON string of phonemes per line) until stdin closes."""
    lib = ctypes.CDLL(library)
    lib.espeak_Initialize.restype = ctypes.c_int
    rate = lib.espeak_Initialize(_AUDIO_OUTPUT_SYNCHRONOUS, 0, None, _INITIALIZE_PHONEME_EVENTS)
    if rate <= 0:
        raise EspeakLibraryError(f"{library}: espeak_Initialize failed ({rate})")
    if lib.espeak_SetVoiceByName(voice.encode()) != 0:
        raise EspeakLibraryError(f"{library}: no voice {voice!r}")
    chunks: list[bytes] = []
    events: list[tuple[str, int]] = []
    n = [0]

    def on_audio(wav, count, ev):
        if wav and count > 0:
            chunks.append(ctypes.string_at(wav, 2 * count))
            n[0] += count
        i = 0
        while ev[i].type != _LIST_TERMINATED:
            if ev[i].type == _PHONEME_EVENT:
                events.append((ev[i].id.string.decode("utf-8", "replace"), int(ev[i].sample)))
            i += 1
        return 0

    callback = _Callback(on_audio)  # kept referenced for as long as the library may call it
    lib.espeak_SetSynthCallback(callback)
    for line in stdin:
        text = json.loads(line).encode()
        chunks.clear()
        events.clear()
        n[0] = 0
        err = lib.espeak_Synth(ctypes.c_char_p(text), len(text) + 1, 0, 1, 0, _CHARS_UTF8 | _PHONEMES, None, None)
        head = json.dumps({"rate": rate, "error": int(err), "events": events}).encode()
        stdout.write(_HEADER.pack(len(head), n[0]))
        stdout.write(head)
        stdout.write(b"".join(chunks))
        stdout.flush()


# ------------------------------------------------------------------ caller side
class EspeakWorker:
    """One espeak-ng library process; :meth:`speak` one phoneme string at a time.

    Parameters
    ----------
    voice : str, default="en"
        espeak-ng voice (``en`` is British English, the talker's accent).
    library : str or None
        The library to load; None finds it (:func:`espeak_library`).

    Raises
    ------
    EspeakLibraryError
        When the library is not installed.
    """

    #: Seconds one :meth:`speak` may take before the process is ended as hung (a sentence
    #: takes well under one second; the word method's program call has the same limit).
    timeout_s = 60.0

    def __init__(self, *, voice: str = "en", library: str | None = None):
        library = library or espeak_library()
        if library is None:
            raise EspeakLibraryError(f"{LIBRARY_NAME} is not installed (Debian/Ubuntu: apt-get install espeak-ng)")
        env = dict(os.environ)
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        # stderr goes to a file, not a pipe: a pipe nobody reads fills and stalls the process
        self._stderr = tempfile.TemporaryFile()
        self._hung = False
        self._proc = subprocess.Popen([sys.executable, "-m", "engine.phonetics.espeak_phones", library, voice],
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr,
                                      env=env)

    def speak(self, phonemes: str):
        """Speak ``phonemes`` (espeak-ng notation, e.g. ``"[[h'Vt D@]]"``).

        Returns
        -------
        samples : bytes
            16-bit little-endian mono samples.
        rate : int
            Their sample rate (Hz).
        events : list of (str, int)
            Each phone spoken, in order: its mnemonic and its first sample.
        """
        p = self._proc
        assert p.stdin is not None and p.stdout is not None  # opened with PIPE
        watchdog = threading.Timer(self.timeout_s, self._end_hung)  # a hung library: its reads end short
        watchdog.daemon = True
        watchdog.start()
        try:
            p.stdin.write((json.dumps(phonemes) + "\n").encode())
            p.stdin.flush()
            head = p.stdout.read(_HEADER.size)
            if len(head) < _HEADER.size:
                raise EspeakLibraryError(self._failure())
            n_head, n_samples = _HEADER.unpack(head)
            info = json.loads(p.stdout.read(n_head))
            samples = p.stdout.read(2 * n_samples)
        except (OSError, ValueError) as exc:
            raise EspeakLibraryError(f"espeak-ng library process failed: {exc}; {self._failure()}") from exc
        finally:
            watchdog.cancel()
        if info["error"] != 0 or len(samples) != 2 * n_samples:
            raise EspeakLibraryError(f"espeak-ng could not speak {phonemes!r} (error {info['error']})")
        return samples, int(info["rate"]), [(m, int(s)) for m, s in info["events"]]

    @property
    def running(self) -> bool:
        """Whether the library process is still there to answer (False once it failed or was ended)."""
        return self._proc.poll() is None

    def _end_hung(self) -> None:
        self._hung = True
        self._proc.kill()

    def _failure(self) -> str:
        if self._hung:
            self._proc.wait()
            return f"espeak-ng library process gave no answer within {self.timeout_s:g} s and was ended"
        self._proc.kill()
        self._proc.wait()
        self._stderr.seek(0)
        err = self._stderr.read().decode(errors="replace").strip().splitlines()
        return f"espeak-ng library process ended: {err[-1] if err else 'no message'}"

    def close(self) -> None:
        """End the process."""
        running = self._proc.poll() is None
        assert self._proc.stdin is not None and self._proc.stdout is not None  # opened with PIPE
        try:
            self._proc.stdin.close()
        except OSError:  # a killed process's pipe may fail to flush
            pass
        if running:
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._proc.stdout.close()
        self._stderr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


if __name__ == "__main__":
    _serve(sys.argv[1], sys.argv[2], sys.stdin.buffer, sys.stdout.buffer)
