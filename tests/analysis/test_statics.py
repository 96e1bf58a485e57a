"""Closed-form statics of the CF layouts (issue 20 §1): the issue's numbers reproduced."""

import pytest

from icewall.analysis.statics import (
    CF_WALLS,
    Station,
    candidate_table,
    cf_layouts,
    fixed_end_moment_per_load,
    midspan_moment_per_load,
    plate_force_ratio,
)


def _layout(span, name):
    return next(lay for lay in cf_layouts(span, 300.0, 333.0) if lay.name == name)


def test_todays_layout_gives_the_issues_moment_arms():
    assert midspan_moment_per_load(1500.0, _layout(1500.0, "A").stations) == pytest.approx(808.5)
    assert midspan_moment_per_load(1250.0, _layout(1250.0, "A").stations) == pytest.approx(646.0)


def test_single_midspan_load_is_pl_over_4():
    assert midspan_moment_per_load(1000.0, (Station(0.0),)) == pytest.approx(250.0)
    # two symmetric loads at +-a: M = P (L/2 - a)
    assert midspan_moment_per_load(1000.0, (Station(200.0),)) == pytest.approx(300.0)
    # an overhang load lifts the midspan moment by P (x - L/2)
    assert midspan_moment_per_load(1000.0, (Station(600.0, 2.0),)) == pytest.approx(-200.0)


def test_fixed_end_moment_of_a_central_load_is_pl_over_8():
    assert fixed_end_moment_per_load(1000.0, (Station(0.0),)) == pytest.approx(125.0)


def test_issue_ratios_at_the_test_ultimate():
    ratio = {row["layout"]: row["ratio"] for row in candidate_table()}["A"]
    assert ratio["CF-4"] == pytest.approx(1.07, abs=0.005)
    assert ratio["CF-13"] == pytest.approx(1.35, abs=0.005)
    assert ratio["CF-8"] == pytest.approx(1.48, abs=0.005)


def test_plate_ratio_by_hand():
    g = CF_WALLS["CF-4"]
    by_hand = 808.5 * 560e3 / (250.0 - 12.6) / (371.0 * 12.6 * 381.0)
    assert plate_force_ratio(808.5, g["P_1"], h=g["h"], t_f=g["t_f"], f_y=g["f_y"],
                             b=g["b"]) == pytest.approx(by_hand)


def test_which_layouts_4_2_1_rules_out():
    verdict = {row["layout"]: row["violates_4_2_1"] for row in candidate_table()}
    assert verdict["A"] == ["CF-4", "CF-13"]
    assert verdict["C"] == ["CF-13"]
    assert verdict["D"] == []
    # CF-8 is the exception of 4.2.1: a high ratio never rules a layout out ...
    assert all("CF-8" not in v for v in verdict.values())
    # ... but a layout under which its plate cannot reach yield does
    cannot = {row["layout"]: row["cf8_cannot_yield"] for row in candidate_table()}
    assert cannot["F"] == cannot["G"] == ["CF-8"]
    assert cannot["D"] == [] and cannot["A"] == []


def test_continuity_loads_cancel_the_support_rotation_moment():
    layout = _layout(1500.0, "F")
    end = layout.stations[-1]
    span_only = tuple(s for s in layout.stations if s.x < 750.0)
    assert end.load * (end.x - 750.0) == pytest.approx(fixed_end_moment_per_load(1500.0,
                                                                                 span_only))
    assert midspan_moment_per_load(1500.0, layout.stations) == pytest.approx(975.0 - 637.5)
