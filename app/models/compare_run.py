"""The Compare panel's work, free of Qt: what to compare, checked before any work; the run; its table; a row's
selection in the views.

* :class:`ComparisonRequest` is what the user chose: a per-utterance field, its levels (a
  reference then the levels compared with it), an optional pairing field and the numbers of
  permutations and bootstrap draws. :func:`check_request` resolves the contrasts and their
  designs at once (a field absent, one level, levels that never share a block when paired are
  refused with the engine's message, naming the field and its levels), before anything runs.
* :func:`run_comparison` fits :class:`engine.comparison.compare.ConditionComparison` on the
  state's manifold (in a worker: ``progress`` reports its stages and raises Cancelled when the
  user cancels) and returns a :class:`ComparisonShown`, what the difference view draws.
* :func:`cell_text` is how the table shows a value (the rows are those of ``lipspace compare
  --csv``: :data:`engine.comparison.compare.COLUMNS`); :func:`sort_key` how a column sorts.
* :func:`apply_row` makes the views show what a row describes, as one action of the state: the
  compared field's two levels (the small multiples), and the cluster's phone filter and ellipsoid,
  the state, or the tangent-class colouring (:func:`app.models.comparison.row_selection`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from app.models.comparison import row_selection

__all__ = ["ComparisonRequest", "ComparisonShown", "check_request", "run_comparison", "cell_text", "sort_key",
           "apply_row", "columns", "DEFAULT_PERMUTATIONS", "DEFAULT_BOOTSTRAP"]

#: the CLI's defaults (``lipspace compare``), so the window's table is the command's
DEFAULT_PERMUTATIONS = 4999
DEFAULT_BOOTSTRAP = 1000


def columns() -> tuple:
    """The table's columns: those of ``lipspace compare --csv`` (:data:`engine.comparison.table.COLUMNS`)."""
    from engine.comparison.table import COLUMNS

    return COLUMNS


@dataclass(frozen=True)
class ComparisonRequest:
    """What the Compare panel asks for.

    Attributes
    ----------
    field : str
    levels : tuple of str
        A reference level, then the levels compared with it (each against the reference).
    paired_by : str
        A pairing field ("" unpaired), e.g. ``text``: the same sentence said in each level.
    n_permutations, n_bootstrap : int
    alpha : float
    horizon_ms : float
        The future hemisphere's horizon for the dynamics (the view's, or 100 ms).
    seed : int
    """

    field: str
    levels: tuple
    paired_by: str = ""
    n_permutations: int = DEFAULT_PERMUTATIONS
    n_bootstrap: int = DEFAULT_BOOTSTRAP
    alpha: float = 0.05
    horizon_ms: float = 100.0
    seed: int = 0


@dataclass
class ComparisonShown:
    """A fitted comparison and which of its contrasts the views show.

    Attributes
    ----------
    result : engine.comparison.compare.ConditionComparison (fitted)
    request : ComparisonRequest
    values : ndarray of str (n_utterances,)
        The compared field's level of each utterance.
    contrast : int
        The contrast the difference view shows (index into ``result.contrasts_``).
    """

    result: object
    request: ComparisonRequest
    values: np.ndarray
    contrast: int = 0
    notes: list = field(default_factory=list)

    @property
    def field(self) -> str:
        return self.request.field

    @property
    def levels(self) -> tuple:
        """``(level_a, level_b)`` of the contrast shown."""
        a, b = self.result.contrasts_[self.contrast]
        return str(a), str(b)

    def with_contrast(self, i: int) -> ComparisonShown:
        """The same comparison showing contrast ``i``."""
        if not 0 <= int(i) < len(self.result.contrasts_):
            raise IndexError(f"contrast {i} out of range 0..{len(self.result.contrasts_) - 1}")
        return ComparisonShown(self.result, self.request, self.values, int(i), self.notes)


def check_request(manifold, request: ComparisonRequest, fields=None):
    """The contrasts and designs of ``request`` on ``manifold``'s corpus, resolved without any fitting.

    Returns ``(values, pairs, contrasts, designs)``; raises
    :class:`engine.comparison.fields.FieldError` (a field absent; one level; a level given twice;
    paired levels that never share a block) with the engine's message.
    """
    from engine.comparison.compare import default_contrasts
    from engine.comparison.design import ComparisonError, resolve_design
    from engine.comparison.fields import field_values, utterance_fields

    fields = utterance_fields(manifold.corpus_) if fields is None else fields
    name = manifold.corpus_.name
    values = field_values(fields, request.field, source=name)
    pairs = field_values(fields, request.paired_by, source=name) if request.paired_by else None
    if request.paired_by and request.paired_by == request.field:
        raise ComparisonError(f"pairing field {request.paired_by!r}: the field compared cannot also be the pairing "
                              "field")
    contrasts = default_contrasts(values, request.field, list(request.levels) if request.levels else None)
    designs = [resolve_design(values, a, b, by=request.field, speakers=fields["speaker"], pairs=pairs,
                              paired_by=request.paired_by, alpha=request.alpha) for a, b in contrasts]
    return values, pairs, contrasts, designs


def run_comparison(manifold, request: ComparisonRequest, progress=None) -> ComparisonShown:
    """Fit the comparison ``request`` asks for (any thread); ``progress(stage, done, total)`` may raise
    :class:`engine.progress.Cancelled`."""
    from engine.comparison.compare import ConditionComparison
    from engine.comparison.fields import utterance_fields

    fields = utterance_fields(manifold.corpus_)
    values, pairs, contrasts, _designs = check_request(manifold, request, fields)
    result = ConditionComparison(n_permutations=int(request.n_permutations), n_bootstrap=int(request.n_bootstrap),
                                 alpha=float(request.alpha), horizon_s=float(request.horizon_ms) / 1000.0,
                                 random_state=int(request.seed)).fit(
        manifold, values, by=request.field, contrasts=contrasts, speakers=fields["speaker"], pairs=pairs,
        paired_by=request.paired_by, progress=progress)
    return ComparisonShown(result, request, values, 0, list(dict.fromkeys(result.notes_)))


def _number(v) -> bool:
    return isinstance(v, (float, np.floating, int, np.integer)) and not isinstance(v, bool)


def cell_text(column: str, value) -> str:
    """How the table shows ``value`` of ``column``: p and q to two significant digits, other numbers to three,
    a missing number as "-" (as ``lipspace compare`` prints them)."""
    if _number(value):
        v = float(value)
        if math.isnan(v):
            return "-"
        if isinstance(value, (int, np.integer)):
            return str(int(value))
        digits = 2 if column in ("p", "q") else 3
        return f"{v:.2g}" if 0 < abs(v) < 10 ** -digits else f"{v:.{digits}g}"
    return str(value)


def sort_key(value):
    """A value's key when its column is sorted: numbers by value (missing last), text by its natural order."""
    if _number(value):
        v = float(value)
        return (0, math.inf if math.isnan(v) else v, "")
    return (1, 0.0, str(value))


def apply_row(state, shown: ComparisonShown, row):
    """Show what ``row`` (a row of ``shown.result.rows_``) describes, as one action; returns its
    :class:`app.models.comparison.RowSelection`.

    Every row shows the two levels it compares (the field filter on them: the small multiples, and the
    other levels dimmed). A cluster row ticks the cluster's ellipsoid and, for a phone, filters the phone
    colouring to it; a state row selects the state and keeps the difference view; a dynamics row colours by
    tangent class.
    """
    sel = row_selection(row)
    a, b = sel.levels
    contrast = shown.result.contrasts_.index((a, b)) if (a, b) in shown.result.contrasts_ else shown.contrast
    with state.batch():
        if state.comparison is not shown or contrast != shown.contrast:
            state.set_comparison(shown.with_contrast(contrast) if contrast != shown.contrast else shown)
        state.set_color_field(shown.field)
        state.set_field_levels(shown.field, sel.levels)
        if sel.kind == "cluster":
            state.set_visible_phones(sel.phones)
            if sel.phones <= set(state.phone_names):  # phones (a landmark cluster has no phone to filter)
                state.set_phone_filter(sel.phones)
                state.set_color_mode("phone")
        elif sel.kind == "state":
            state.select_state(sel.state)
            state.set_color_mode("difference")  # the state shown where it sits in the difference view
        else:  # a dynamics measure: how the frames move, by tangent class
            state.set_color_mode("class")
    return sel
