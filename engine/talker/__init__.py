"""The synthetic talker: the lip model, its corpora (one or many speakers), virtual sensors and video."""
