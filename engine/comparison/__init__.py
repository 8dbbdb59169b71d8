"""Comparing conditions on one manifold: speakers, emotions or groups, and where they move differently."""
