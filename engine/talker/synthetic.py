"""The embedded default corpus, a deterministic synthetic talker: its public names in one place.

The talker lives in three modules, one concept each: :mod:`engine.talker.synthetic_talker` (the
estimator :class:`SyntheticTalker`, its presets and articulator dynamics),
:mod:`engine.talker.gestures` (the phones' articulatory gestures and the ground-truth gesture
phases) and :mod:`engine.talker.talker_cache` (the cache of generated corpora and
:func:`load_synthetic`). This module gathers their public names, so scripts importing them from
here keep working.
"""
from __future__ import annotations

from engine.talker.gestures import PHONE_GESTURES, Gesture, gesture_phases, phone_gestures
from engine.talker.synthetic_talker import (
    GENERATOR_VERSION,
    HELD_OUT_TALKER,
    LIP_MODEL_AXES,
    PRESETS,
    T63,
    SyntheticTalker,
    lip_roles,
    speaker_anatomy,
)
from engine.talker.talker_cache import (
    audio_folder,
    cache_folder,
    cache_path,
    cache_token,
    generator_fingerprint,
    load_synthetic,
    talker_key,
)

__all__ = ["GENERATOR_VERSION", "PRESETS", "HELD_OUT_TALKER", "LIP_MODEL_AXES", "T63", "SyntheticTalker",
           "load_synthetic", "cache_folder", "cache_token", "talker_key", "cache_path", "audio_folder",
           "generator_fingerprint", "Gesture", "PHONE_GESTURES", "phone_gestures", "gesture_phases", "lip_roles",
           "speaker_anatomy"]
