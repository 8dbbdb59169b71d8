"""Recordings: the corpus, blocked corpora, registration, kinematics, sensor layouts, speakers, orientation,
head pose."""
