"""Published figures of the source papers, for side-by-side reporting.

Faraway & Choe (2008), Table 1: median over trajectories of the maximum over time of
the tangent-space error, in radians, on 1,088 reaches of 20 subjects (motion capture,
not public). The between-subject value is 0.242 in the paper's text and 0.265 in its
table; both are kept.
"""

from __future__ import annotations

__all__ = ["FARAWAY_CHOE_TABLE1", "FARAWAY_CHOE_TABLE1_NOTES"]

FARAWAY_CHOE_TABLE1: dict[str, float] = {
    "within_subject": 0.125,
    "between_subject": 0.265,
    "slerp_empirical": 0.397,
    "slerp_average": 0.448,
    "approximation_d2": 0.126,
    "approximation_d3": 0.083,
    "approximation_d4": 0.049,
    "null_d2": 0.296,
    "null_d3": 0.371,
    "null_d4": 0.294,
    "null_average": 0.288,
    "subject_predictor_d2": 0.281,
    "subject_predictor_d3": 0.375,
    "subject_predictor_d4": 0.298,
    "task_predictor_d2": 0.251,
    "task_predictor_d3": 0.377,
    "task_predictor_d4": 0.278,
}

FARAWAY_CHOE_TABLE1_NOTES: dict[str, str] = {
    "between_subject": "0.242 in the text, 0.265 in the table",
    "null_d3": "cannot follow from the stated procedure (see docs/models.md)",
}
