"""Deprecated location of :mod:`baselines.learned.rows` (the path-frame, predicted-timing
and learned rows of ``motion-bench orientation``), kept so that existing imports work:
every name is looked up in :mod:`baselines.learned.rows` (which also re-exports
:mod:`baselines.learned.reading`'s ``bootstrap_ratio``, ``format_comparison`` and
``plot_ratios``). Import from there instead."""

from __future__ import annotations

from typing import Any

from baselines.learned import rows

__all__ = list(rows.__all__)


def __getattr__(name: str) -> Any:
    return getattr(rows, name)
