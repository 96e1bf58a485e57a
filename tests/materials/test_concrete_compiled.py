"""The numba kernel of the concrete update (concrete_compiled) against the NumPy reference:
the same stresses, trial states and iteration moduli from the same (strain, state), the same
load history of a small analysis, and the rules that choose the kernel."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from dataclasses import fields, replace
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("numba")

import icewall.materials.concrete_compiled as compiled  # noqa: E402
from icewall.deck.load import load_deck  # noqa: E402
from icewall.materials.concrete import update_concrete  # noqa: E402
from icewall.materials.concrete_law import ConcreteLaw, floored_moduli  # noqa: E402
from icewall.materials.concrete_state import ConcreteState  # noqa: E402
from icewall.materials.mode_rules import equivalent_uniaxial_strengths  # noqa: E402
from icewall.materials.parameters import derive_concrete_parameters  # noqa: E402
from icewall.materials.substep import update_concrete_substepped  # noqa: E402
from icewall.materials.ultimate_surface import strength_scale  # noqa: E402
from icewall.mesh.build import build_mesh, region_materials  # noqa: E402
from icewall.model.build import build_model  # noqa: E402
from icewall.model.materials import build_groups, concrete_point_parameters  # noqa: E402
from icewall.pipeline import run_deck  # noqa: E402

DECKS = Path(__file__).resolve().parents[2] / "decks"
PARAMS = derive_concrete_parameters(53.5, 100.0)
ET, EC = PARAMS.eps_t, PARAMS.eps_c
FORMULATIONS = compiled.COMPILED_FORMULATIONS  # what the kernel covers
TRIALS = ("corotational", "incremental")
STEPS = 24


def _principal(e1: float, e2: float, angle: float, zz: float = 0.0) -> list[float]:
    """Global strain [xx, yy, zz, gamma_xy] with principal strains e1, e2 at `angle`."""
    c, s = np.cos(angle), np.sin(angle)
    return [c * c * e1 + s * s * e2, s * s * e1 + c * c * e2, zz, 2.0 * c * s * (e1 - e2)]


def _leg(points: list[list[float]]) -> np.ndarray:
    """STEPS strains piecewise linear through `points` (the first excluded)."""
    points = np.array(points, dtype=float)
    t = np.linspace(0.0, len(points) - 1.0, STEPS + 1)[1:]
    return np.stack([np.interp(t, np.arange(len(points)), points[:, j]) for j in range(4)], 1)


def _histories() -> np.ndarray:
    """(STEPS, n, 4) strain paths: past the peaks in tension and compression and back across
    zero (closing cracks, crushed directions in tension), biaxial and mixed states, hoop strains,
    and principal axes rotating through 45 degrees."""
    zero = [0.0, 0.0, 0.0, 0.0]
    paths = [
        _leg([zero, [12 * ET, 0, 0, 0], [2 * ET, 0, 0, 0], [-1.5 * EC, 0, 0, 0]]),
        _leg([zero, [-5 * EC, 2 * EC, 0, 0], [-2.5 * EC, EC, 0, 0], [20 * ET, -0.5 * EC, 0, 0]]),
        _leg([zero, [-4 * EC, EC, EC, 0], [-2 * EC, 0, 0, 0], [20 * ET, 0, 0, 0]]),
        _leg([zero, [-2 * EC, -2 * EC, -EC, 0], [-EC, -EC, 0, 0]]),
        _leg([zero, [6 * ET, 6 * ET, 3 * ET, 0], [-0.5 * EC, 8 * ET, 0, 0]]),
        _leg([zero, [8 * ET, -EC, 0, 2 * ET], [20 * ET, -1.2 * EC, 2 * ET, 0]]),
        _leg([zero, [0, 0, 0, 10 * ET], [0, 0, 0, -10 * ET]]),
        _leg([zero, [0.5 * ET, 0, -0.4 * EC, 0], [3 * ET, 0, -1.5 * EC, 0]]),
        _leg([zero, zero]),  # virgin: zero strain throughout
        np.array([_principal(6 * ET, -0.6 * EC, a, 2 * ET)
                  for a in np.linspace(0.0, 0.5 * np.pi, STEPS)]),
        np.array([_principal(-0.3 * EC + 2 * ET * t, -1.2 * EC * t, np.pi / 4 * t)
                  for t in np.linspace(0.05, 1.0, STEPS)]),
    ]
    return np.stack(paths, axis=1)


def _parameters(variant: str, n: int):
    if variant == "per-point":  # k_t, k_c of each point's crack band (model.materials)
        return concrete_point_parameters(PARAMS, np.linspace(20.0, 200.0, n), {})
    if variant == "floor":  # §3.2.5 rule (b) in the errata's signed reading
        return derive_concrete_parameters(53.5, 100.0, compression_tension_rule="floor")
    if variant == "band":  # and the mode rules blended over a band of the stresses
        return derive_concrete_parameters(53.5, 100.0, compression_tension_rule="floor",
                                          mode_rule_band=0.5)
    if variant == "peak":  # and a direction past its peak keeping its strength
        return derive_concrete_parameters(53.5, 100.0, compression_tension_rule="floor",
                                          mode_rule_band=0.5, post_peak_strength="peak")
    if variant == "scaled":  # and a fallen envelope scaled through the committed point
        return derive_concrete_parameters(53.5, 100.0, compression_tension_rule="floor",
                                          mode_rule_band=0.5, post_peak_strength="peak",
                                          fallen_strength="scaled")
    if variant == "continuous":  # and direction 1 on the major strain, G bounded by G0
        return derive_concrete_parameters(53.5, 100.0, compression_tension_rule="floor",
                                          mode_rule_band=0.5, post_peak_strength="peak",
                                          fallen_strength="scaled",
                                          rotating_axes="continuous")
    return PARAMS


def _calls(formulation: str, trial: str, variant: str, frozen_every: int = 0):
    """The (strain, committed state, params, frozen) of every step of the paths, driven by
    the NumPy update; with frozen_every, every that many steps a third of the points frozen."""
    strains = _histories()
    n = strains.shape[1]
    params = _parameters(variant, n)
    rng = np.random.default_rng(7)
    state, calls = ConcreteState.initial(n, PARAMS), []
    for k, strain in enumerate(strains):
        frozen = (rng.random(n) < 0.35 if frozen_every and k % frozen_every == 0 else None)
        calls.append((strain, state, params, frozen))
        _, _, state = update_concrete(strain, state, params, formulation, trial, frozen,
                                      with_moduli=False)
    return calls


def _assert_same_update(reference, result, exact: bool = False) -> None:
    """Flags equal; floats to 1e-12 of the largest of their row (bit for bit if `exact`)."""
    (stress_r, state_r), (stress_c, state_c) = reference, result
    pairs = [("returned stress", stress_r, stress_c)]
    pairs += [(f.name, getattr(state_r, f.name), getattr(state_c, f.name))
              for f in fields(ConcreteState)]
    for name, a, b in pairs:
        assert a.shape == b.shape and a.dtype == b.dtype, name
        if exact or a.dtype == bool:
            np.testing.assert_array_equal(b, a, err_msg=name)
            continue
        scale = np.abs(a).reshape(a.shape[0], -1).max(axis=1).reshape((-1,) + (1,) * (a.ndim - 1))
        assert np.all(np.abs(b - a) <= 1e-12 * np.maximum(scale, 1e-300)), name


def _reference(strain, state, params, formulation, trial, frozen):
    stress, _, new = update_concrete(strain, state, params, formulation, trial, frozen,
                                     with_moduli=False)
    return stress, new


@pytest.mark.parametrize("variant", ["scalar", "per-point", "floor", "band", "peak",
                                     "scaled", "continuous"])
@pytest.mark.parametrize("trial", TRIALS)
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_update_equals_numpy_along_the_paths(formulation, trial, variant):
    calls = _calls(formulation, trial, variant, frozen_every=3)
    reached = dict.fromkeys(("cracked", "crushed", "closing", "crushed in tension", "held",
                             "past 45 degrees"), 0)
    for strain, state, params, frozen in calls:
        reference = _reference(strain, state, params, formulation, trial, frozen)
        _assert_same_update(reference, compiled.compiled_update(strain, state, params,
                                                                formulation, trial, frozen))
        # and from the same state a little off the path
        off = strain + 0.3 * ET * np.sin(np.arange(strain.size)).reshape(strain.shape)
        _assert_same_update(_reference(off, state, params, formulation, trial, None),
                            compiled.compiled_update(off, state, params, formulation, trial))
        new, eps_u = reference[1], reference[1].equivalent_uniaxial_strain
        reached["cracked"] += int(new.cracked.sum())
        reached["crushed"] += int(new.crushed.sum())
        reached["closing"] += int(np.sum(state.cracked & (eps_u < 0.0)))
        reached["crushed in tension"] += int(np.sum(state.crushed & (eps_u > 0.0)))
        if frozen is not None:
            would_load = np.abs(eps_u) > state.max_equivalent_uniaxial_strain
            reached["held"] += int(np.sum(frozen[:, None] & would_load))
        reached["past 45 degrees"] += int(np.sum(np.abs(new.angle) > 0.25 * np.pi))
    assert all(reached.values()), reached  # the paths reach the branches they are meant to


@pytest.mark.parametrize("coaxial", [False, True])
@pytest.mark.parametrize("floor", [0.0, 0.02, 0.5])
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_floored_moduli_equal_numpy(formulation, floor, coaxial):
    for strain, state, params, frozen in _calls(formulation, "corotational", "per-point", 4):
        _, trial = _reference(strain, state, params, formulation, "corotational", frozen)
        reference = floored_moduli(trial, params, formulation, floor, coaxial)
        result = compiled.compiled_floored_moduli(trial, params, formulation, floor, coaxial)
        scale = np.abs(reference).max(axis=(1, 2), keepdims=True)
        assert np.all(np.abs(result - reference) <= 1e-12 * scale)


# OpenBLAS kernels whose FMA chains the compiled kernel copies (checked bit for bit here);
# with others (Sandybridge, Prescott: no FMA) NumPy's matmul sums differently, and the two
# kernels agree to round-off only (checked to 1e-12 of each row, as the other tests do).
BIT_EXACT_BLAS = ("Haswell", "SkylakeX", "Zen", "Cooperlake", "SapphireRapids")


def _blas_architecture() -> str:
    """The running OpenBLAS kernel (threadpoolctl; '' where it cannot tell)."""
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return ""
    return next((str(i.get("architecture")) for i in threadpool_info()
                 if i.get("internal_api") == "openblas"), "")


@pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"),
                    reason="bit equality assumes x86's einsum lanes and BLAS FMA chains")
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_bit_for_bit_on_x86(formulation):
    """Same arithmetic in the same order, NumPy's own exp and arctan2: not one bit differs
    with the FMA kernels of OpenBLAS (BIT_EXACT_BLAS), round-off with the others."""
    exact = _blas_architecture() in BIT_EXACT_BLAS
    for strain, state, params, frozen in _calls(formulation, "corotational", "per-point", 2):
        reference = _reference(strain, state, params, formulation, "corotational", frozen)
        _assert_same_update(reference, compiled.compiled_update(
            strain, state, params, formulation, "corotational", frozen), exact=exact)
        moduli = compiled.compiled_floored_moduli(reference[1], params, formulation, 0.02, True)
        expected = floored_moduli(reference[1], params, formulation, 0.02, True)
        if exact:
            np.testing.assert_array_equal(moduli, expected)
        else:
            scale = np.abs(expected).max(axis=(1, 2), keepdims=True)
            assert np.all(np.abs(moduli - expected) <= 1e-12 * scale)


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_substepped_update_equals_numpy(formulation):
    """Increments of up to 12 cracking strains, in sub-steps of half of one (substep.py)."""
    calls = _calls(formulation, "incremental", "per-point")
    for (_, state, params, frozen), (strain, *_) in zip(calls[::4], calls[3::4], strict=False):
        assert np.abs(strain - state.strain)[:, [0, 1, 3]].max() > 2 * ET  # sub-stepped
        mask = np.arange(strain.shape[0]) % 3 == 0
        for frozen in (None, mask):
            stress, _, new = update_concrete_substepped(strain, state, params, formulation,
                                                        0.5 * ET, frozen=frozen,
                                                        with_moduli=False)
            _assert_same_update((stress, new), compiled.compiled_substepped(
                strain, state, params, formulation, 0.5 * ET, frozen=frozen))


strains = st.lists(st.floats(-4e-3, 1e-3), min_size=4, max_size=4)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.lists(strains, min_size=3, max_size=3), min_size=3, max_size=3),
       st.sampled_from(FORMULATIONS), st.sampled_from(TRIALS), st.booleans())
def test_property_random_paths_equal_numpy(path, formulation, trial, freeze):
    """Three points, three steps of random strains (the last step of each frozen or not)."""
    path = np.array(path)  # (steps, points, 4)
    state = ConcreteState.initial(3, PARAMS)
    for k, strain in enumerate(path):
        frozen = np.array([True, False, freeze]) if k == len(path) - 1 else None
        reference = _reference(strain, state, PARAMS, formulation, trial, frozen)
        _assert_same_update(reference, compiled.compiled_update(strain, state, PARAMS,
                                                                formulation, trial, frozen))
        state = reference[1]


@pytest.mark.parametrize(("rule", "band"), [("equal", 0.0), ("floor", 0.0), ("equal", 0.4),
                                            ("floor", 0.4)])
def test_strength_surface_and_mode_rules_equal_numpy(rule, band):
    """sigma_ic on the ray of a trial stress, the kernel's passes against
    equivalent_uniaxial_strengths: rays that miss the surface below the cap (hydrostatic
    compression), a zero state, zero components (the strain-sign fallback), rules (a)-(c),
    sharp and blended over a band (states with a component inside it included)."""
    params = derive_concrete_parameters(53.5, 100.0, compression_tension_rule=rule,
                                        mode_rule_band=band)
    rng = np.random.default_rng(3)
    trial = np.vstack([[[0.0, 0.0, 0.0], [-30.0, -30.0, -30.0], [-30.0, -30.0, -29.0],
                        [2.0, 2.0, 2.0], [3.0, 0.0, 0.0], [-40.0, 0.0, 1e-9], [0.0, -40.0, 0.0],
                        [-50.0, -60.0, 0.0], [2.0, -50.0, -10.0], [1.0, 2.0, -70.0],
                        [-1e-13, 0.0, 0.0], [-4.4, 2e-4, -9.1], [-4.4, 0.3, -9.1],
                        [2.0, -0.2, 1.0], [2.0, -0.05, -0.01]],
                       rng.uniform(-80.0, 4.0, (40, 3)), rng.uniform(-1.0, 1.0, (20, 3))])
    sign = np.where(rng.random(trial.shape) < 0.5, -1.0, 1.0)
    expected = equivalent_uniaxial_strengths(trial, params, strain_sign=sign)
    _, capped = strength_scale(trial, params.fc, params.surface, return_capped=True)
    assert capped.any() and not capped.all()
    kernels, prm = compiled._kernels(), compiled.parameter_tuple(params)
    work = np.zeros((len(trial), kernels.N_WORK, 3))
    work[:, kernels.W_TRIAL], work[:, kernels.W_EPS_U] = trial, sign
    rays = np.array([kernels.unit_ray(*row, params.fc) for row in trial])
    theta = np.where(rays[:, 5] != 0, np.clip(np.arctan2(rays[:, 4], rays[:, 3]), 0.0,
                                              np.pi / 3.0), 0.0)
    scale = kernels.strength_scales(rays[:, 0].copy(), rays[:, 1].copy(), np.cos(theta),
                                    rays[:, 2].copy(), prm)
    for i, value in enumerate(scale):
        kernels.uniaxial_strengths(work, i, value, prm)
    np.testing.assert_array_equal(work[:, kernels.W_STRENGTH], expected)


def _history(tmp_path: Path, kernel: str, monkeypatch) -> dict[str, np.ndarray]:
    monkeypatch.setenv(compiled.KERNEL_VARIABLE, kernel)
    loaded = load_deck(DECKS / "cf4.yaml", ["loads.control.target=3", "outputs.fields=[]",
                                            "loads.control.increment=0.25",
                                            "analysis.element_size=100"])
    path = tmp_path / f"{kernel}.h5"
    assert run_deck(loaded, path).status == "completed"
    with h5py.File(path, "r") as f:
        return {k: f["history"][k][()] for k in ("load", "cracked_in_plane", "iterations")}


def test_analysis_load_history_is_the_same_with_both_kernels(tmp_path, monkeypatch):
    """CF-4, 12 steps of 0.25 mm on 100 mm elements: cracking from the second step on."""
    calls, update = [], compiled.compiled_update

    def counted(*args, **kwargs):
        calls.append(len(args[0]))
        return update(*args, **kwargs)

    monkeypatch.setattr(compiled, "compiled_update", counted)
    numpy_run = _history(tmp_path, "numpy", monkeypatch)
    assert calls == []
    numba_run = _history(tmp_path, "numba", monkeypatch)
    assert len(calls) >= numba_run["iterations"].sum()  # every evaluation went through it
    uncracked = numpy_run["cracked_in_plane"] == 0
    assert uncracked.any() and not uncracked.all() and numpy_run["load"].size == 12
    # bit-identical kernels give identical histories; where the BLAS kernel makes them differ
    # at round-off (BIT_EXACT_BLAS), the secant iteration, stopped at the first iterate within
    # 5 %, amplifies that to about 1e-8 (Sandybridge): a kernel error would show at 1e-3
    rtol = 1e-12 if _blas_architecture() in BIT_EXACT_BLAS else 1e-6
    np.testing.assert_allclose(numba_run["load"][uncracked], numpy_run["load"][uncracked],
                               rtol=rtol)
    assert numba_run["load"].max() == pytest.approx(numpy_run["load"].max(), rel=1e-6)
    np.testing.assert_array_equal(numba_run["cracked_in_plane"], numpy_run["cracked_in_plane"])


def _concrete_kernel(monkeypatch, kernel: str | None, *overrides: str) -> str:
    if kernel is None:
        monkeypatch.delenv(compiled.KERNEL_VARIABLE, raising=False)
    else:
        monkeypatch.setenv(compiled.KERNEL_VARIABLE, kernel)
    deck = load_deck(DECKS / "cf4.yaml", ["analysis.element_size=150", *overrides]).deck
    model = build_model(deck, build_mesh(deck), region_materials(deck))
    groups = build_groups(model.description, model.cell_material, model.gauss_spacing,
                          model.kinematics.dV.shape[1])
    return next(g for g in groups if isinstance(g.law, ConcreteLaw)).law.kernel


def test_kernel_selection(monkeypatch):
    assert compiled.available() and compiled.available("axisymmetric", "incremental")
    assert not compiled.available("plane_stress") and not compiled.available(trial_stress="total")
    assert _concrete_kernel(monkeypatch, None) == "numba"  # auto by default
    assert _concrete_kernel(monkeypatch, "auto", "analysis.formulation=plane_stress") == "numpy"
    assert _concrete_kernel(monkeypatch, " NumPy ") == "numpy"
    # the tangent and the pure secant without floor keep their NumPy moduli
    assert _concrete_kernel(monkeypatch, "numba", "analysis.concrete_stiffness=tangent") == "numpy"
    assert _concrete_kernel(monkeypatch, "numba", "analysis.concrete_stiffness=secant",
                            "analysis.iteration_stiffness_floor=0") == "numpy"
    with pytest.warns(RuntimeWarning, match="not plane_stress with corotational"):
        assert compiled.choose_kernel("plane_stress", "corotational", "numba") == "numpy"
    monkeypatch.setattr(compiled, "numba_installed", lambda: False)
    with pytest.warns(RuntimeWarning, match="numba is not installed"):
        assert _concrete_kernel(monkeypatch, "numba") == "numpy"
    assert _concrete_kernel(monkeypatch, "auto") == "numpy"
    with pytest.raises(ValueError, match="unknown concrete kernel"):
        compiled.choose_kernel("plane_strain", "corotational", "fortran")
    with pytest.raises(ValueError, match="does not cover plane_stress"):
        compiled.compiled_update(np.zeros((1, 4)), ConcreteState.initial(1, PARAMS), PARAMS,
                                 "plane_stress")


def test_numba_not_imported_when_the_numpy_kernel_is_chosen(tmp_path):
    """`icewall run` with ICEWALL_CONCRETE_KERNEL=numpy never imports numba."""
    script = f"""
import sys
from icewall.cli import main
try:
    main(["run", {str(DECKS / "cf4.yaml")!r}, "-q", "-o", {str(tmp_path / "r.h5")!r},
          "--set", "analysis.element_size=150", "--set", "loads.control.target=1"])
except SystemExit as exc:
    assert not exc.code, exc.code
print(sorted(m for m in sys.modules if m.split(".")[0] == "numba"))
"""
    env = {**os.environ, compiled.KERNEL_VARIABLE: "numpy"}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert f["history/load"].size == 1


def test_compiled_update_leaves_its_inputs_alone():
    strain, state, params, frozen = _calls("plane_strain", "corotational", "per-point", 1)[12]
    before = replace(state, **{f.name: getattr(state, f.name).copy() for f in fields(state)})
    strain_before = strain.copy()
    compiled.compiled_update(strain, state, params, "plane_strain", "corotational", frozen)
    assert np.array_equal(strain, strain_before)
    for f in fields(ConcreteState):
        assert np.array_equal(getattr(state, f.name), getattr(before, f.name)), f.name
