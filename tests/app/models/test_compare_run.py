"""The Compare panel's Qt-free work: requests checked before running, table cells and sorting, a row's selection."""
from __future__ import annotations

import math

import numpy as np
import pytest

from app.models.compare_run import ComparisonRequest, apply_row, cell_text, check_request, columns, sort_key
from app.models.state import AppState
from engine.comparison.fields import FieldError


def test_bad_requests_are_refused_before_any_work(field_manifold):
    with pytest.raises(FieldError, match="no field 'emotion'"):
        check_request(field_manifold, ComparisonRequest(field="emotion", levels=()))
    with pytest.raises(FieldError, match="has 3 levels: a \\(20\\), b \\(20\\), c \\(20\\); choose two"):
        check_request(field_manifold, ComparisonRequest(field="condition", levels=()))
    with pytest.raises(FieldError, match="speaker"):  # one speaker: nothing to compare
        check_request(field_manifold, ComparisonRequest(field="speaker", levels=()))
    with pytest.raises(FieldError, match="cannot also be the pairing field"):
        check_request(field_manifold, ComparisonRequest(field="condition", levels=("a", "b"), paired_by="condition"))
    values, pairs, contrasts, designs = check_request(
        field_manifold, ComparisonRequest(field="condition", levels=("a", "b", "c"), paired_by="text"))
    assert contrasts == [("a", "b"), ("a", "c")] and len(designs) == 2 and len(values) == 60 and pairs is not None


def test_the_table_is_the_commands_rows(condition_comparison):
    r = condition_comparison.result
    assert columns()[:3] == ("field", "level_a", "level_b")
    assert {row["family"] for row in r.rows_} == {"cluster", "dynamics", "state"}
    assert all(set(columns()) <= set(row) for row in r.rows_)
    assert cell_text("p", 0.000123) == "0.00012" and cell_text("estimate", 1.23456) == "1.23"
    assert cell_text("q", float("nan")) == "-" and cell_text("n_utterances", np.int64(40)) == "40"
    values = [0.3, float("nan"), "x", 0.1, -2.0]
    assert sorted(values, key=sort_key)[:3] == [-2.0, 0.1, 0.3]
    assert math.isnan(sorted(values, key=sort_key)[3]) and sorted(values, key=sort_key)[4] == "x"


def test_a_row_selects_what_it_describes(field_manifold, condition_comparison):
    s = AppState(field_manifold)
    rows = condition_comparison.result.rows_
    state_row = next(r for r in rows if r["family"] == "state" and (r["level_a"], r["level_b"]) == ("a", "c"))
    sel = apply_row(s, condition_comparison, state_row)
    assert sel.kind == "state" and s.state == int(state_row["target"]) and s.color_mode == "difference"
    assert s.comparison.levels == ("a", "c")  # the difference view shows the row's contrast
    assert s.color_field == "condition" and s.field_filter == {("condition", "a"), ("condition", "c")}
    cluster_row = next(r for r in rows if r["family"] == "cluster" and r["target"] in s.phone_names)
    apply_row(s, condition_comparison, cluster_row)
    assert s.visible_phones == {cluster_row["target"]} and s.phone_filter == {cluster_row["target"]}
    assert s.color_mode == "phone"
    dyn = next(r for r in rows if r["family"] == "dynamics")
    apply_row(s, condition_comparison, dyn)
    assert s.color_mode == "class"
    with pytest.raises(IndexError, match="contrast 5 out of range 0..1"):
        condition_comparison.with_contrast(5)
