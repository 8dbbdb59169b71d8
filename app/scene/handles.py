"""A drawn thing: its dataset and actor, updated in place."""
from __future__ import annotations

__all__ = ["Handle"]


class Handle:
    """Dataset + actor of one scene element.

    Attributes
    ----------
    plotter : pyvista plotter the actor lives in
    mesh : pyvista.DataSet drawn by ``actor``
    actor : vtk actor
    """

    def __init__(self, plotter, mesh, actor):
        self.plotter = plotter
        self.mesh = mesh
        self.actor = actor

    @property
    def visible(self) -> bool:
        return bool(self.actor.GetVisibility())

    def set_visible(self, visible: bool) -> None:
        self.actor.SetVisibility(bool(visible))

    def replace_geometry(self, new) -> None:
        """Swap the dataset's geometry for ``new`` (same actor, no re-add)."""
        self.mesh.copy_from(new, deep=True)
        self.mesh.Modified()

    def remove(self) -> None:
        self.plotter.remove_actor(self.actor, render=False)
