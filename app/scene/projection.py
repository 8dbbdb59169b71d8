"""World -> screen for a pyvista view: :mod:`app.models.projection` (numpy only), under its older name."""
from app.models.projection import STANDARD_VIEWS, nearest_on_screen, project, standard_camera, view_transform

__all__ = ["view_transform", "project", "nearest_on_screen", "standard_camera", "STANDARD_VIEWS"]
