"""Evaluation under equal information: protocols, their methods, paired tests and reports."""
