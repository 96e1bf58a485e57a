"""`icewall params` and `icewall point`: derived parameters and the material-point driver."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from icewall.cli import main

DECKS = Path(__file__).resolve().parents[2] / "decks"


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def test_params_lists_each_core_with_table_4_4_quantities():
    result = invoke("params", str(DECKS / "cf4.yaml"), "--json")
    assert result.exit_code == 0, result.output
    rows = json.loads(result.output)
    assert [r["region"] for r in rows] == ["core_1", "core_2", "core_3"]
    for row in rows:
        # Table 4.4, CF-4: E = 32200, f't = 2.41; k_t = f't h_c / G_f (eq. 3.29)
        assert row["E0"] == pytest.approx(32200, rel=0.01)
        assert row["ft"] == pytest.approx(2.41, rel=0.01)
        assert row["k_t"] == pytest.approx(row["ft"] * row["h_c"] / 0.10, rel=1e-9)
        assert row["warnings"] == []


def test_params_warns_when_the_crack_band_snaps_back():
    # h_c > E G_f / f't^2 = 32183 * 0.1 / 2.414^2 = 552 mm needs elements of ~1.7 m at 3x3;
    # use a large G_f-free override instead: k_t large enough that k_t f't > E.
    result = CliRunner().invoke(
        main, ["params", str(DECKS / "cf4.yaml"), "--set", "materials.concrete.k_t=20000"])
    assert result.exit_code == 0
    assert "tensile softening branch snaps back" in result.stderr


def test_point_uniaxial_compression_peaks_at_fc(tmp_path):
    out = tmp_path / "path.csv"
    result = invoke("point", "--fc", "53.5", "--path", "uniaxial-compression", "--csv",
                    str(out), "--json", "--max-strain", "0.004", "--steps", "200")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["peak_stress_xx"] == pytest.approx(-53.5, rel=1e-3)
    assert summary["strain_at_peak_xx"] == pytest.approx(-0.0025, rel=0.02)
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    assert len(rows) == 201


def test_point_trial_stress_forms_agree_without_rotation_and_differ_on_the_rotating_path():
    def peak(path, trial):
        result = invoke("point", "--fc", "53.5", "--path", path, "--json", "--steps", "120",
                        "--max-strain", "0.004", "--trial-stress", trial)
        assert result.exit_code == 0, result.output
        return json.loads(result.output)["peak_stress_xx"]

    assert peak("uniaxial-compression", "incremental") == peak("uniaxial-compression",
                                                               "corotational")
    assert peak("rotating", "incremental") != peak("rotating", "corotational")
    assert invoke("point", "--fc", "53.5", "--trial-stress", "secant").exit_code == 2


def test_point_rejects_a_bad_path():
    result = invoke("point", "--fc", "53.5", "--path", "zigzag")
    assert result.exit_code == 2
    assert "Traceback" not in result.output
