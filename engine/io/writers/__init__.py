"""Writers: trajectories, meshes, glTF animations, tidy tables, Praat TextGrids."""
