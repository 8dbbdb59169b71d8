"""The comparison table's schema: the columns of a result row and the families its rows belong to.

Kept apart from :mod:`engine.comparison.compare` (which imports scikit-learn) so that a table can
be laid out, as the explorer's Compare panel is when its window opens, before any comparison runs.
"""
from __future__ import annotations

__all__ = ["COLUMNS", "FAMILIES"]

#: columns of a result row, in the order of the CSV table
COLUMNS = ("field", "level_a", "level_b", "family", "measure", "target", "space", "estimate", "unit", "ci_low",
           "ci_high", "p", "q", "value_a", "value_b", "n_utterances", "n_utterances_a", "n_utterances_b",
           "n_speakers", "design")
#: the families, each corrected for its own number of comparisons
FAMILIES = ("cluster", "dynamics", "state")
