"""The parts of the manifold view (:class:`app.views.manifold_view.ManifoldView`): its controls, its scene layers."""
