"""The state graph over the manifold: states, directed geodesics (hop paths), hemispheres, bridges."""
