"""Files: atomic writing, the manifold's persistence, input validation, user folders, assets, staged outputs."""
