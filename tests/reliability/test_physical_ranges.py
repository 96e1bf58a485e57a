"""Issue 38, item 4: a deck that passes `check` cannot give a silent wrong result under any
scheme. Every material and geometric value has a physical range (icewall.deck.physical): a
value outside it is one line naming the key, exit 2, unless analysis.allow_unphysical (then a
warning per value). Every scheme refuses a singular initial system the same way, before any
file is written, and NumPy's floating-point warnings never reach the user."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from reliability_support import CF4, DECKS, TF1, error_lines, invoke

from icewall.deck.load import load_deck
from icewall.deck.physical import RANGES, outside

ALLOW = ("--set", "analysis.allow_unphysical=true")


def _scalar_cases():
    """(key, value) just outside each end of every range of a value CF-4 has (no list)."""
    for key, rng in RANGES.items():
        if "[*]" in key or key in ("materials.concrete.k_t", "materials.concrete.k_c"):
            continue
        if rng.low is not None:
            yield key, rng.low / 10 if rng.low > 0 else -1.0
        if rng.high is not None:
            yield key, rng.high * 10


SCALARS = list(_scalar_cases())
ISSUE = [("materials.steel.E", "1.0e-300"), ("materials.steel.E", "1.0e30"),
         ("materials.steel.fy", "1.0e-6"), ("geometry.top_plate", "1.0e-9"),
         ("geometry.width", "1.0e+308"), ("geometry.span", "1.0e308"),
         ("geometry.depth", "1.0e308")]


def _one_line(result) -> str:
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and "internal error" not in result.output
    lines = error_lines(result)
    assert len(lines) == 1, result.stderr
    return lines[0]


@pytest.mark.parametrize(("key", "value"), ISSUE + [(k, repr(v)) for k, v in SCALARS])
def test_a_value_outside_its_physical_range_is_refused(key, value):
    result = invoke("check", CF4, "--set", f"{key}={value}")
    line = _one_line(result)
    if "physical" in line:
        assert f"{key}:" in line and "analysis.allow_unphysical" in line
    else:  # a hard limit or a geometric rule checked before it (a patch off the wall)
        assert key in line or "geometry." in line or "loads." in line, line


@pytest.mark.parametrize(("deck", "assignment", "key"), [
    (CF4, "geometry.supports=[{x: 750.0, bearing_plate_width: 2.0e4}]",
     "geometry.supports[0].bearing_plate_width"),
    (CF4, "geometry.supports=[{x: 750.0, bearing_plate_thickness: 0.01}]",
     "geometry.supports[0].bearing_plate_thickness"),
    (TF1, "geometry.legs=[{x: 625.0, length: 50.0, height: 0.001}]", "geometry.legs[0].height"),
    (CF4, "materials.concrete.k_t=1.0e9", "materials.concrete.k_t"),
])
def test_list_items_and_derived_overrides_have_ranges(deck, assignment, key):
    assert f"{key}:" in _one_line(invoke("check", deck, "--set", assignment))


def test_zero_where_zero_means_none_is_allowed():
    result = invoke("check", CF4, "--set", "geometry.end_plate=0",
                    "--set", "geometry.supports=[{x: 750.0, bearing_plate_width: 0}]")
    assert result.exit_code == 0, result.output


def test_allow_unphysical_runs_it_with_a_warning_per_value():
    result = invoke("check", CF4, "--set", "materials.steel.E=2.0e11",
                    "--set", "geometry.width=0.381", *ALLOW)
    assert result.exit_code == 0, result.output
    lines = [line for line in result.stderr.splitlines() if "allowed by analysis.allow_un" in line]
    assert len(lines) == 2
    assert {"materials.steel.E", "geometry.width"} == {k for k in ("materials.steel.E",
                                                                  "geometry.width")
                                                       if any(k in line for line in lines)}


def test_the_shipped_decks_and_the_stability_variants_lie_inside(monkeypatch):
    monkeypatch.syspath_prepend(str(DECKS.parent / "tests" / "stability"))
    from stability_cases import HEAVY, QUICK

    decks = sorted(DECKS.glob("*.yaml"))
    assert len(decks) >= 18
    loaded = [load_deck(deck).deck for deck in decks]
    loaded += [load_deck(DECKS / case.deck, list(case.overrides)).deck for case in QUICK + HEAVY]
    for deck in loaded:  # loaded with the ranges checked, and no value outside any of them
        assert not deck.analysis.allow_unphysical
        assert outside(deck) == []


# -- every scheme refuses a singular system the same way ---------------------------------------
SCHEMES = {"linear": "analysis.solver=linear", "secant": "analysis.scheme=secant",
           "newton": "analysis.scheme=newton"}


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_every_scheme_refuses_a_singular_system_alike(scheme, tmp_path):
    """Steel E = 1e-300 MPa: linear and secant stopped on a singular system, Newton reported
    "completed" after 128 steps at zero load (issue 38)."""
    out = tmp_path / "out.h5"
    result = invoke("run", CF4, "--set", "materials.steel.E=1.0e-300", *ALLOW, "--set",
                    SCHEMES[scheme], "--set", "loads.control.target=2", "-q", "-o", out)
    assert result.exit_code == 1, result.output
    (line,) = error_lines(result)
    assert line.startswith("error: the deck's initial elastic system (initial moduli, "
                           "interface pairs tied) has no solution: stiffness matrix is singular")
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing written, no lock left


# -- NumPy's floating-point warnings -------------------------------------------------------------
def test_floating_point_errors_are_counted_not_printed():
    from icewall.preflight import floating_point_guard

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning would fail here
        with floating_point_guard() as counts:
            big = np.array([1e308]) * 10.0
            np.array([0.0]) / np.array([0.0])
    assert np.isinf(big[0]) and counts == {"overflow": 1, "invalid value": 1}


def test_a_run_reports_them_in_one_line(monkeypatch, tmp_path):
    import icewall.pipeline as pipeline

    real = pipeline._write_linear

    def overflowing(*args, **kwargs):
        for _ in range(108):  # what steel E = 1e30 printed, one warning each
            np.array([1e308]) * 10.0
        return real(*args, **kwargs)

    monkeypatch.setattr(pipeline, "_write_linear", overflowing)
    result = invoke("run", CF4, "--set", "analysis.solver=linear", "--set",
                    "loads.control.target=1", "-q", "-o", tmp_path / "x.h5")
    assert result.exit_code == 0, result.output
    assert "RuntimeWarning" not in result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert lines == ["warning: NumPy floating-point errors during the analysis (108 overflow); "
                     "values that large or undefined mean a modulus, a size or a load far "
                     "outside its range, so check the result"]
