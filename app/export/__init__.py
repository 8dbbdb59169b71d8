"""Exports of a lip trajectory that other programs play: glTF morph animation, MP4 video.

``app.export.animation`` writes the ``.glb`` (through :mod:`engine.io.writers.gltf`) with the
audio as a ``.wav`` beside it; ``app.export.video`` renders the lip view off-screen
frame by frame with pyvista and muxes it with the audio through PyAV.
"""
