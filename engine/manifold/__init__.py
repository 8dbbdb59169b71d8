"""The visual speech manifold: shape space, dynamic features, embedding, tangent frames, inverse maps, clusters."""
