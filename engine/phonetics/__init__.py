"""Phones: phone sets, pronunciation, targets from text/phones/states, speech audio and spectrograms."""
