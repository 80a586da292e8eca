"""The leaderboard's columns (:func:`~adaptive_dd.arena.leaderboard.leaderboard`): each one's unit and
meaning, as its CSV and JSON and the docs' table give them; and which rows rank
(:func:`contenders`)."""

from __future__ import annotations

__all__ = ["COLUMNS", "contenders", "references", "told_the_model"]

COLUMNS: dict[str, tuple[str, str]] = {
    "scenario": ("-", "the scenario's name (a drawn arm: TEMPLATE_armSEED; pooled: population(N arms))"),
    "kind": ("-", "scenario (shipped or given), arm (one drawn arm), population (pooled over the arms)"),
    "controller": ("-", "the controller ranked"),
    "law": ("-", "the built-in or import path it runs: its own name, or a variant's law"),
    "floor": ("-", "the controller it is divided by, seed by seed (the same law with the true robot)"),
    "floor_note": (
        "-",
        "empty, or why the row has no ratio or why its floor is no floor "
        "(a plant friction law outside the controllers' model; the law's bandwidth or damping not "
        "its floor's)",
    ),
    "segment": ("-", "payload segment, 0-based"),
    "payload_kg": ("kg", "the payload carried in the segment (population: the mean over the arms)"),
    "seeds": ("-", "seeds whose trial did not fail before the segment's end"),
    "ratio_mean": ("-", "mean over seeds of RMS error / the floor's RMS error (same seed, same segment)"),
    "ratio_ci95_low": (
        "-",
        "percentile-bootstrap 95 % interval of ratio_mean, low end (too narrow below ~10 seeds)",
    ),
    "ratio_ci95_high": (
        "-",
        "percentile-bootstrap 95 % interval of ratio_mean, high end (too narrow below ~10 seeds)",
    ),
    "ratio_p90": ("-", "90th percentile of the per-seed ratio (linear interpolation)"),
    "ratio_cvar10": ("-", "CVaR of the worst 10 %: mean of the ceil(0.1 n) largest per-seed ratios"),
    "ratio_max": ("-", "largest per-seed ratio"),
    "failures": ("-", "trials that failed (diverged, ran away or raised) before the segment's end"),
    "saturated_seeds": ("-", "seeds whose command saturated on more than 1 % of the segment's samples"),
    "lost_seeds": (
        "-",
        "seeds whose tracking error |q_d - q| exceeded 0.2 rad in the segment",
    ),
    "rms_error_mrad": ("mrad", "mean over seeds of the joint-space RMS tracking error |q_d - q|"),
    "floor_rms_error_mrad": ("mrad", "the same of the floor"),
    "rms_rank": (
        "-",
        "rank of rms_error_mrad in the scenario's segment among the laws not told the true model (1: "
        "lowest; a law with a failed trial after those without; empty: an oracle, or a law told the true "
        "model; a law whose floor could not run is ranked too: the rank compares errors, not ratios)",
    ),
    "rms_torque_Nm": ("N m", "mean over seeds of the RMS applied torque (norm over joints)"),
    "saturation_pct": ("%", "mean over seeds of the samples with a joint's command beyond its limit"),
    "floor_saturation_pct": ("%", "the same of the floor (a saturated floor makes the ratio optimistic)"),
    "false_alarm_seeds": (
        "-",
        "seeds whose change detector alarmed in the segment with no swap in the 0.3 s before "
        "(empty: a law without a detector)",
    ),
    "missed_swaps": (
        "-",
        "seeds whose change detector did not alarm within 0.3 s after the swap that starts the "
        "segment (0 in the first segment; empty: a law without a detector)",
    ),
    "recovery_median_s": ("s", "median over seeds of the recovery time (a never counts as the latest)"),
    "recovery_p90_s": ("s", "90th percentile of the recovery time (inf: reaches a never)"),
    "recovery_never": ("-", "seeds still above 1.2x the floor's moving RMS error at the segment's end"),
    "ee_position_rms_mm": ("mm", "mean over seeds of the tool frame's RMS position error |p_d - p|"),
    "ee_position_peak_mm": ("mm", "mean over seeds of the tool frame's peak position error"),
    "ee_position_peak_max_mm": ("mm", "largest over seeds of the tool frame's peak position error"),
    "ee_orientation_rms_deg": ("deg", "mean over seeds of the tool frame's RMS orientation error"),
}
"""Every column of the table: ``name -> (unit, meaning)``."""


def contenders(df):
    """Boolean mask of the rows whose laws are ranked against each other: those with a floor, less
    the laws told the true model (``ct_oracle_late``: a measuring stick with a floor, not a law that
    learns the robot)."""
    return (df["floor"] != "") & ~told_the_model(df)


def told_the_model(df):
    """Boolean mask of the rows of laws told the true model (``ct_oracle_late`` and its variants, by
    the ``law`` column): shown beside the contenders, with their floor, and ranked with none."""
    from adaptive_dd.controllers.builtins import CONTROLLERS

    law = df["controller"]  # a variant's law where the table says it (an older table: the name)
    if "law" in df:
        law = df["law"].where(df["law"].notna() & (df["law"].astype(str) != ""), df["controller"])
    told = law.map(lambda c: c in CONTROLLERS and CONTROLLERS[c].knows.startswith("true model"))
    return told.astype(bool)


def references(df):
    """Boolean mask of the rows of laws told the true model that have a floor (``ct_oracle_late``):
    the tables and the figure show them beside the :func:`contenders`, marked, ranked with none."""
    return told_the_model(df) & (df["floor"] != "")
