"""One-glance summary of a result file (used by ``icewall summary RESULT.h5 [--json]``)."""

from __future__ import annotations

import math
import os

import numpy as np

from icewall.analysis.ductility import result_ductility
from icewall.analysis.extract import FIRST_PEAK_SOFTENING, first_maximum, stroke_mask
from icewall.analysis.mechanism import format_mechanism, mechanism_check
from icewall.deck.analysis_options import CONVERGED_TOLERANCE
from icewall.deck.load import LoadedDeck
from icewall.results.reader import open_result

_NO_FINISH = "no finish record: run still going, or killed"
LINEAR_NOTE = "linear-elastic, not a prediction"
"""What a linear-solver result is (icewall summary and report say it; no test/predicted ratio,
no ductility verdict): the initial moduli and tied interfaces, no cracking, crushing or
yielding, so its loads grow without bound."""


def solver_label(solver: str | None) -> str:
    """The solver of a result as summary and report print it."""
    if solver == "linear":
        return f"linear ({LINEAR_NOTE})"
    return solver or "unknown (not recorded in the file)"


def summarize(path: str | os.PathLike) -> dict:
    """Key numbers of one analysis as a JSON-serialisable dict (None where there are no steps)."""
    with open_result(path) as r:
        a, h = r.attrs, r.history
        stored = r.stored_deck()  # None: the stored deck no longer loads (reader's rule)
        deck_problem = r.stored_deck_problem or None
        solver = a.get("solver")
        ductility = result_ductility(r) if len(h["step"]) and solver != "linear" else None
    if solver == "linear":
        ductility = {"message": f"not assessed: {LINEAR_NOTE}"}
    status = str(a.get("status", ""))
    reason = str(a.get("stop_reason", ""))
    if status == "running" and not reason:
        reason = _NO_FINISH
    out = {
        "path": os.fspath(path), "specimen": a.get("specimen"), "solver": solver,
        "status": status,
        "stop_reason": reason, "n_steps": int(len(h["step"])),
        "max_load": None, "deflection_at_max_load": None,
        # the largest load before the curve first softens (icewall.analysis.extract)
        "first_max_load": None, "deflection_at_first_max_load": None, "final_load": None,
        "final_deflection": None, "total_iterations": 0, "iterations_per_step_median": None,
        "iterations_per_step_max": None, "run_time_s": a.get("run_time_s"),
        "load_measure": a.get("load_measure"), "load_unit": a.get("load_unit"),
        "ductility": ductility,  # CSA S474 8.4.4, icewall.analysis.ductility
        "snap_throughs": [],  # control deflections where a snap-back drop was accepted
        "jumps": [],  # control deflections reached by a step over a stall (max_jumps)
        # issue 20 §1: bottom plate at the peak vs f_y, first crushing, residual mechanism
        "mechanism": mechanism_check(path) if len(h["step"]) else None,
        "equilibrium": None,  # how far the stored steps are from equilibrium (_equilibrium)
        "energy": None,  # the energy balance at the last step (_energy_balance)
        # why the stored deck no longer loads (None: it does); what needs it is unknown
        "stored_deck_problem": deck_problem,
    }
    if out["n_steps"]:
        load, defl, its = h["load"], h["control_displacement"], h["iterations"]
        i = int(np.argmax(load))  # first step at the peak
        stroke = np.flatnonzero(stroke_mask(np.asarray(defl)))  # the recorded curve
        first = stroke[first_maximum(np.asarray(load)[stroke])]
        out.update({
            "max_load": float(load[i]), "deflection_at_max_load": float(defl[i]),
            "first_max_load": float(load[first]),
            "deflection_at_first_max_load": float(defl[first]),
            "final_load": float(load[-1]), "final_deflection": float(defl[-1]),
            "total_iterations": int(its.sum()),
            "iterations_per_step_median": float(np.median(its)),
            "iterations_per_step_max": int(its.max()),
        })
        if "snap_back" in h:
            out["snap_throughs"] = [float(d) for d in defl[np.asarray(h["snap_back"]) > 0]]
        if "jumped" in h:
            out["jumps"] = [float(d) for d in defl[np.asarray(h["jumped"]) > 0]]
        if "dynamic_time_steps" in h:
            out["dynamic_drops"] = _dynamic_drops(h, defl)
        if solver != "linear":
            out["equilibrium"] = _equilibrium(h, stored)
        if "external_work" in h and "energy_imbalance" in h:
            out["energy"] = _energy_balance(h)
    return finite_figures(out)


def _energy_balance(history) -> dict:
    """The energy account at the last step (N mm): the external work, the imbalance and, in a
    run that can take dynamic drops, the numerical dissipation of their time integration
    (solve/energy.py), each also as a fraction of the external work (None where there is
    none)."""
    external = float(history["external_work"][-1])
    imbalance = float(history["energy_imbalance"][-1])
    numerical = (float(history["numerical_dissipation"][-1])
                 if "numerical_dissipation" in history else None)

    def fraction(value):
        return None if value is None or external == 0.0 else value / external

    return {"external_work": external, "energy_imbalance": imbalance,
            "imbalance_fraction": fraction(imbalance), "numerical_dissipation": numerical,
            "numerical_fraction": fraction(numerical)}


def _dynamic_drops(history, deflection) -> dict:
    """The steps reached by a dynamic drop (solve.dynamic): their deflections, time steps and
    the largest kinetic energy of any (N mm) with the deflection of its drop."""
    steps = np.asarray(history["dynamic_time_steps"])
    kinetic = np.asarray(history["largest_kinetic_energy"])
    dynamic = np.flatnonzero(steps > 0)
    largest = int(dynamic[np.argmax(kinetic[dynamic])]) if dynamic.size else None
    return {"deflections": [float(deflection[i]) for i in dynamic],
            "time_steps": int(steps.sum()),
            "largest_kinetic_energy": None if largest is None else float(kinetic[largest]),
            "deflection_of_largest": None if largest is None else float(deflection[largest])}


def finite_figures(value):
    """`value` with every non-finite float made None: a figure derived from the file (the
    reader refuses a file holding a NaN or infinity) that is undefined, e.g. a ductility ratio
    of a curve with no initial stiffness, is no figure ("-", JSON null), never "nan"."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_figures(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite_figures(v) for v in value]
    return value


def _equilibrium(history, stored: LoadedDeck | None) -> dict:
    """The largest load and displacement norms (eqs. 4.4-4.5) over the stored steps and, where
    the stored deck (with the run's --set overrides) loads, its scheme and tolerances."""
    out = {"largest_load_norm": float(np.max(history["load_norm"])),
           "largest_displacement_norm": float(np.max(history["displacement_norm"])),
           "scheme": None, "tolerance_load": None, "tolerance_displacement": None}
    if stored is None:  # a file without a readable deck: the norms alone
        return out
    analysis = stored.deck.analysis
    tol_load, tol_disp = analysis.tolerance_load, analysis.tolerance_displacement
    load, disp = np.asarray(history["load_norm"]), np.asarray(history["displacement_norm"])
    # the schemes' own test: a load norm 100x inside its tolerance passes whatever the first
    # correction's displacement norm (solve.newton, solve.control)
    met = (load <= tol_load) & ((disp <= tol_disp) | (load <= 0.01 * tol_load))
    out.update(scheme=analysis.scheme, tolerance_load=tol_load,
               tolerance_displacement=tol_disp, steps_outside=int(np.count_nonzero(~met)))
    return out


def _dynamic_rows(drops: dict | None) -> list[tuple[str, str]]:
    """The summary's line on the dynamic drops (none for a run that cannot take them)."""
    if drops is None:
        return []
    if not drops["deflections"]:
        return [("dynamic drops", "none")]
    return [("dynamic drops", f"{len(drops['deflections'])} "
             f"({drops['time_steps']} time steps), {_deflection_list(drops['deflections'])};"
             f" largest kinetic energy {drops['largest_kinetic_energy']:.4g} N mm "
             f"(at {drops['deflection_of_largest']:.4g} mm)")]


def _num(value, unit: str = "", fmt: str = ".6g") -> str:
    if value is None:
        return "-"
    text = format(value, fmt) if isinstance(value, float) else str(value)
    return f"{text} {unit}".rstrip()


def _ductility_rows(d: dict | None, unit: str) -> list[tuple[str, str]]:
    """Lines of the CSA S474 clause 8.4.4 check (verdict, yield point, energy, why)."""
    if not d or d.get("ductility_ratio") is None:
        return [("ductility (CSA S474)", d["message"] if d else "-")]
    bound = ">= " if d["ratio_is_lower_bound"] else ""
    energy = f"{_num(d['energy'], d['energy_unit'], '.4g')}"
    if d.get("energy_Nmm") is not None:
        energy += f" = {d['energy_Nmm']:.4g} N mm (total jack load)"
    return [("ductility (CSA S474)", f"{d['verdict']}: mu = {bound}{d['ductility_ratio']:.2f}"
             f" (needs {d['required_ratio']:g} at {d['load_fraction']:.0%} of P_y)"),
            ("yield load, deflection", f"{d['yield_load']:.6g} {unit}, "
                                       f"{d['yield_deflection']:.4g} mm"),
            ("energy absorbed", energy + " to the end of the run"),
            ("ductility note", d["message"])]


LISTED_SNAP_THROUGHS = 6
"""More snap-throughs than this are given as a count, the first few and the last."""


def _deflection_list(deflections) -> str:
    """The deflections as "at 2.06 mm, at 3.1 mm"; for many (a Newton run may drop hundreds
    of times) their count, the first LISTED_SNAP_THROUGHS - 1 and the last."""
    items = [f"at {d:.4g} mm" for d in deflections]
    if len(items) <= LISTED_SNAP_THROUGHS:
        return ", ".join(items) or "none"
    return (f"{len(items)}: " + ", ".join(items[:LISTED_SNAP_THROUGHS - 1])
            + f", ..., {items[-1]}")


def _equilibrium_text(e: dict | None, jumped: bool) -> str:
    """One line: the largest norms of the stored steps against the run's tolerances."""
    if not e:
        return "-"
    norms = (f"largest load norm {e['largest_load_norm']:.3g}, displacement norm "
             f"{e['largest_displacement_norm']:.3g}")
    if e.get("tolerance_load") is None:
        return norms + " (the stored deck does not read: tolerances unknown)"
    tol_load, tol_disp = e["tolerance_load"], e["tolerance_displacement"]
    if e["steps_outside"] or jumped:
        verdict = (f"not every step is an equilibrium to its tolerances ({e['steps_outside']} "
                   "outside" + (", steps over a stall" if jumped else "") + ")")
    elif max(tol_load, tol_disp) <= CONVERGED_TOLERANCE:
        verdict = "every step a converged equilibrium"
    else:
        verdict = "every step within loose tolerances (figures move with them)"
    return (f"{verdict}: {tol_load:g} (load), {tol_disp:g} (displacement), scheme "
            f"{e['scheme']}; {norms}")


def _energy_text(e: dict) -> str:
    """One line: the external work, the imbalance and the drops' numerical dissipation."""
    def part(name, value, fraction):
        share = "-" if fraction is None else f"{100.0 * fraction:.3g} %"
        return f"{name} {share} ({value:.4g} N mm)"

    parts = [part("imbalance", e["energy_imbalance"], e["imbalance_fraction"])]
    if e.get("numerical_dissipation") is not None:
        parts.append(part("numerical dissipation of the dynamic drops",
                          e["numerical_dissipation"], e["numerical_fraction"]))
    return f"external work {e['external_work']:.4g} N mm; of it {', '.join(parts)}"


def _first_maximum_text(s: dict, unit: str) -> str:
    """The first maximum, and whether the curve climbs past it later (a second hump)."""
    first = s.get("first_max_load")
    if first is None:
        return "-"
    text = f"{_num(first, unit)} at {_num(s.get('deflection_at_first_max_load'), 'mm')}"
    if s.get("max_load") is not None and s["max_load"] > first:
        text += (f" (before the curve first softens by {100 * FIRST_PEAK_SOFTENING:g} %; it "
                 "climbs higher later)")
    return text


def format_summary(summary: dict) -> str:
    """Human-readable block of aligned ``key : value unit`` lines."""
    s = summary
    lu = s.get("load_unit") or ""
    measure = s.get("load_measure")
    load_label = f"max load ({measure})" if measure else "max load"
    iters = "-"
    if s.get("iterations_per_step_max") is not None:
        iters = (f"median {_num(s['iterations_per_step_median'], fmt='g')}, "
                 f"max {s['iterations_per_step_max']}")
    rows = [
        ("file", s.get("path") or "-"),
        ("specimen", s.get("specimen") or "-"),
        ("solver", solver_label(s.get("solver"))),
        ("status", s.get("status") or "-"),
        ("stop reason", s.get("stop_reason") or "-"),
        ("steps", _num(s.get("n_steps"))),
        (load_label, _num(s.get("max_load"), lu)),
        ("deflection at max load", _num(s.get("deflection_at_max_load"), "mm")),
        ("first maximum", _first_maximum_text(s, lu)),
        ("final load", _num(s.get("final_load"), lu)),
        ("final deflection", _num(s.get("final_deflection"), "mm")),
        ("total iterations", _num(s.get("total_iterations"))),
        ("iterations per step", iters),
        ("snap-throughs", _deflection_list(s.get("snap_throughs") or ())),
        *_dynamic_rows(s.get("dynamic_drops")),
        ("steps over a stall", ", ".join(f"to {d:.4g} mm" for d in s.get("jumps") or ())
         or "none"),
        ("equilibrium", _equilibrium_text(s.get("equilibrium"), bool(s.get("jumps")))),
        *([("energy balance", _energy_text(s["energy"]))] if s.get("energy") else []),
        ("run time", _num(s.get("run_time_s"), "s", ".1f")),
        *_ductility_rows(s.get("ductility"), lu),
        *(format_mechanism(s["mechanism"]) if s.get("mechanism") else []),
        *([("stored deck", f"does not load, so what needs it is unknown: "
            f"{s['stored_deck_problem']}")] if s.get("stored_deck_problem") else []),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}} : {_printable(v)}" for k, v in rows)


def _printable(text: str) -> str:
    """`text` with control characters shown escaped: a damaged file's stop reason or unit
    cannot move the terminal's cursor."""
    return "".join(c if c.isprintable() else ascii(c)[1:-1] for c in str(text))
