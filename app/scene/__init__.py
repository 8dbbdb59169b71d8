"""Scene-building functions: each takes any pyvista plotter and returns a handle.

Handles keep the dataset and actor so views update them in place (colours,
positions, visibility) instead of re-adding actors on every click. Tests pass
``pyvista.Plotter(off_screen=True)``; the explorer passes its ``QtInteractor``.
"""
from app.scene.handles import Handle
from app.scene.lips import LipsHandle, add_lips, lip_mesh
from app.scene.manifold import (
                                ORIGINAL_COLOUR,
                                PATH_COLOUR,
                                S_COLOUR,
                                SYNTHETIC_COLOUR,
                                V_COLOUR,
                                PointsHandle,
                                add_cluster_ellipsoids,
                                add_global_axes,
                                add_local_frame,
                                add_manifold_points,
                                add_marker,
                                add_point_markers,
                                add_state_path,
                                add_trajectory,
                                add_zero_velocity_plane,
                                label_zoom,
                                move_to_overlay,
                                overlay_renderer,
                                scene_scale,
                                to_rgb8,
)
from app.scene.pick import ClickPicker, enable_click_picking, pick_display_point
from app.scene.pyvista_import import import_plotting
from app.scene.sensors import SensorsHandle, add_sensors

import_plotting()  # the scene modules read pyvista's plotting package only when they draw

__all__ = ["Handle", "PointsHandle", "LipsHandle", "SensorsHandle", "add_sensors", "ClickPicker",
           "add_manifold_points", "add_zero_velocity_plane",
           "add_global_axes", "label_zoom", "add_local_frame", "add_trajectory", "add_cluster_ellipsoids",
           "add_state_path",
           "add_marker", "add_point_markers", "add_lips", "lip_mesh", "enable_click_picking", "pick_display_point",
           "scene_scale", "overlay_renderer", "move_to_overlay",
           "to_rgb8", "ORIGINAL_COLOUR", "SYNTHETIC_COLOUR", "PATH_COLOUR", "S_COLOUR", "V_COLOUR"]
