"""The explorer's one shared application state, free of Qt and VTK.

:class:`AppState` (:mod:`app.models.state.app_state`) holds indices and modes; its fields
are declared once in :mod:`app.models.state.fields`, sent by the events of
:mod:`app.models.state.events`; what the views derive from a manifold is
:mod:`app.models.state.derived`; trajectories and clicked-state targets are
:mod:`app.models.state.trajectory` and :mod:`app.models.state.targets`.
"""
from app.models.state.app_state import AppState
from app.models.state.derived import cluster_table, frame_phone_codes, frame_phones, knn_density, prepare_derived
from app.models.state.events import Event
from app.models.state.fields import COLOR_MODES, DEFAULT_HORIZON_MS, FIELDS, HEMISPHERES, HORIZON_MAX_MS, StateField
from app.models.state.targets import TARGET_SPACING, insert_state_target, state_path
from app.models.state.trajectory import TrajectoryData, original_trajectory

__all__ = ["Event", "AppState", "StateField", "FIELDS", "TrajectoryData", "HEMISPHERES", "COLOR_MODES",
           "DEFAULT_HORIZON_MS", "HORIZON_MAX_MS", "knn_density", "frame_phones", "frame_phone_codes", "state_path",
           "cluster_table", "original_trajectory", "prepare_derived", "insert_state_target", "TARGET_SPACING"]
