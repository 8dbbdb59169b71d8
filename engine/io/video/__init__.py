"""Video import: face-mesh landmarks tracked in clips."""
