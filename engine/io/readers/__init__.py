"""Readers of corpus files: articulograph, EMA, MAT, markers, landmarks, meshes, alignments."""
