"""Qt views of the explorer; each observes one :class:`app.models.state.AppState` and never calls another view."""
from app.views.clusters_panel import ClustersPanel
from app.views.lip_view import LipView
from app.views.manifold_view import ManifoldView
from app.views.phone_timeline import PhoneTimeline
from app.views.scree_panel import ScreePanel
from app.views.trajectory_editor import TrajectoryEditor

__all__ = ["ManifoldView", "LipView", "TrajectoryEditor", "PhoneTimeline", "ClustersPanel", "ScreePanel"]
