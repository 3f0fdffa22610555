"""The pure :func:`run` of ``motion-bench position`` (load the data, run the benchmark,
read the learned columns).

(Named ``runner`` so that the package attribute ``run`` stays the function.)"""

from __future__ import annotations

from typing import Any

from baselines import options
from baselines.learned import LEARNED_MODES
from baselines.position_bench.config import PositionConfig
from baselines.position_bench.scoring import run_benchmark
from motion_envs.datasets import load_position_dataset


def run(config: PositionConfig) -> dict[str, Any]:
    """The benchmark of ``config``: the ``results.json`` document (plus the predictions
    under ``_predictions``/``_truth`` for :func:`plot_grid`) with the learned columns'
    comparisons under ``learned.comparisons``; no files, no printing except the progress
    bar on stderr when ``config.progress``."""
    from baselines.learned.position_reading import position_comparisons

    if config.learned not in LEARNED_MODES:
        raise options.ConfigError(
            "learned", f"expected one of {list(LEARNED_MODES)}; got {config.learned!r}"
        )
    dataset = load_position_dataset(config.data, config.shapes)
    doc = run_benchmark(
        dataset,
        n_points=config.n_points,
        kinds=list(config.conditions),
        n_sines=config.n_sines,
        use_peers=config.use_peers,
        n_weights=config.n_weights,
        progress=config.progress,
        split=config.split,
        test_fraction=config.test_fraction,
        split_seed=config.split_seed,
        learned=config.learned,
    )
    doc["learned"]["comparisons"] = position_comparisons(doc)
    from baselines.verdicts import position_verdicts, verdicts_document

    doc.update(verdicts_document(position_verdicts(doc)))
    return doc
