"""The configuration of ``motion-bench position``: :class:`PositionConfig`, the methods
and the criteria's printed names."""

from __future__ import annotations

from dataclasses import dataclass

METHODS: tuple[str, ...] = ("line", "null", "lippi", "dmp", "promp", "ridge", "mlp")


PEER_METHODS = ("dmp", "promp")


CRITERION_TEXT = {
    "max_error": "median over demos of max_t |error|",
    "rmse": "median over demos of RMSE",
    "dtw": "median over demos of DTW (sum of Euclidean costs)",
    "swept_area": "median over demos of swept error area",
}


@dataclass(frozen=True)
class PositionConfig:
    """What ``motion-bench position`` computes (the defaults are the CLI's).

    ``data`` is ``"lasa"`` or a position CSV path, ``shapes`` the tasks kept (None: all);
    the other fields are :func:`run_benchmark`'s arguments (``n_sines=None``: chosen by
    cross-validation; ``use_peers``: the DMP and ProMP columns when installed;
    ``learned``: the budget of the ridge and mlp columns, one of :data:`LEARNED_MODES`).
    """

    data: str = "lasa"
    shapes: tuple[str, ...] | None = None
    n_points: int = 200
    conditions: tuple[str, ...] = ("start", "end")
    n_sines: int | None = None
    n_weights: int = 10
    split: str = "loo"
    test_fraction: float = 0.25
    split_seed: int = 0
    use_peers: bool = True
    progress: bool = True
    learned: str = "full"
