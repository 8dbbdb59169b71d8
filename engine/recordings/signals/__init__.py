"""Signals derived from a corpus's sensors: quality, low-pass filtering, tracks and gestural landmarks."""
