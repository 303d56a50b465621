"""``summary.md``'s section on the hybrid multi-phase findings (see
:mod:`softlanding.report.phased`)."""

from __future__ import annotations

from typing import Any

from softlanding.report.summary import _f, _table


def _two_phase(h: dict) -> list[str]:
    rows = h["two_phase"]
    worst = max(abs(r["difference"]) for r in rows)
    spread = max(r["arrest_force_spread"] for r in rows)
    return [
        "### 1. The body-arrest phase optimised (fig_hybrid_findings, fig_two_phase_landing)",
        "", "Two phases: yielding until the foot stops, then static stance until the body "
        "stops; the phase-2 force free within |u| <= u_max with the support force within "
        "[0, crater depth].", "",
        _table(["v0", "two-phase depth", "paper's depth", "difference", "phase-2 force",
                "crater depth - foot weight", "arcs", "replay diff."],
               [[_f(r["v0"], 3), _f(r["depth"], 9), _f(r["paper_depth"], 9),
                 f"{r['difference']:.1e}", _f(r["arrest_force"], 6),
                 _f(r["crater_capacity_minus_foot_weight"], 6),
                 " / ".join(" ".join(a) for a in r["arcs"]),
                 f"{r['replay_difference']:.1e}"] for r in rows[::max(1, len(rows) // 8)]]),
        "", f"Largest |two-phase - paper| over {len(rows)} velocities: {worst:.1e}. The optimal "
        f"phase-2 force is constant (largest spread {spread:.1e}) and equals the crater's "
        "capacity minus the foot's weight: the paper's constant arrest u_b, with its "
        "condition active, is optimal (confirms the paper's assumption).", ""]


def _two_step(h: dict) -> list[str]:
    rows = h["two_step"]
    return [
        "Second yielding step (yielding, static, yielding, static) from several starts:", "",
        _table(["v0", "one-step depth", "two-step depth", "gain", "middle phases collapse"],
               [[_f(r["v0"], 2), _f(r["one_step_depth"], 9), _f(r["two_step_depth"], 9),
                 f"{r['gain']:.1e}", _f(r["collapsed"])] for r in rows]),
        "", "A gain <= 0 (to the four-phase transcription's grid error) means a second step "
        "never lowers the depth.", ""]


def _legs(h: dict) -> list[str]:
    rows = h["leg_extension"]
    out = ["### 2. Pre-impact leg extension (fig_leg_extension)", "",
           "Changes the paper's initial condition: the leg length at impact is a decision in "
           "[0, s] (both masses at v0).", "",
           _table(["v0", "depth", "paper (leg s/2)", "gain", "optimal leg length", "verified"],
                  [[_f(r["v0"], 3), _f(r["depth"], 6), _f(r["paper_depth"], 6),
                    _f(r["gain"], 4), _f(r["extension"], 4), _f(not r["unverified_reasons"])]
                   for r in rows[::max(1, len(rows) // 8)]]), ""]
    drop = h.get("leg_extension_drop") or []
    if drop:
        out += ["From a drop (a flight phase, the actuator free in flight):", "",
                _table(["v0", "depth", "gain", "leg length", "rate", "CoM velocity",
                        "verified"],
                       [[_f(r["v0"], 3), _f(r["depth"], 6), _f(r["gain"], 4),
                         _f(r["extension"], 4), _f(r["rate"], 4), _f(r["com_velocity"], 4),
                         _f(not r["unverified_reasons"])] for r in drop[::max(1, len(drop) // 8)]]),
                ""]
    return out


def _hops(h: dict) -> list[str]:
    rows = h["hopping"]

    def cell(c: Any, key: str, nd: int = 4) -> str:
        return "n/a" if c is None else _f(c[key], nd)

    return [f"### 3. Minimum-energy hopping, eta = {h['hop_eta']:g} (fig_hybrid_findings, "
            "fig_hop_cycle)", "",
            _table(["v0", "apex", "optimum: energy", "crater", "CoT", "impedance: energy",
                    "(k_p, k_d, u_t)", "rigid: energy", "crater"],
                   [[_f(r["free"]["v0"], 2), _f(r["free"]["apex_height"], 3),
                     cell(r["free"], "energy"), cell(r["free"], "depth"),
                     cell(r["free"], "cot", 3), cell(r["impedance"], "energy"),
                     "n/a" if r["impedance"] is None else
                     "({k_p:.3g}, {k_d:.3g}, {u_t:.3g})".format(**r["impedance"]["gains"]),
                     cell(r["rigid"], "energy"), cell(r["rigid"], "depth")] for r in rows]),
            "", "Energies per cycle in m_t g x_s, evaluated on the exact replay of each control.",
            ""]


def hybrid_markdown(h: dict) -> list[str]:
    """The section's Markdown lines.

    Parameters
    ----------
    h : dict
        ``summary["hybrid"]``.
    """
    return (["## Beyond the paper: the landing as a hybrid multi-phase problem", ""]
            + _two_phase(h) + _two_step(h) + _legs(h) + _hops(h))


__all__ = ["hybrid_markdown"]
