"""The juggling environments' episode seeds per split live in the task layer
(``motion_envs.datasets.juggling``), defined once; the baselines import them."""

from __future__ import annotations

import ast
import itertools
from pathlib import Path

import numpy as np
import pytest

from motion_envs.datasets.juggling import MAX_SPLIT_EPISODES, SPLIT_SEEDS, episode_seeds

ROOT = Path(__file__).resolve().parents[1]


def test_split_seed_ranges_are_disjoint():
    firsts = sorted(SPLIT_SEEDS.values())
    assert set(SPLIT_SEEDS) == {"train", "val", "test"}
    assert all(b - a >= MAX_SPLIT_EPISODES for a, b in itertools.pairwise(firsts))
    assert firsts[-1] + MAX_SPLIT_EPISODES - 1 < 2**32  # a valid numpy seed


def test_episode_seeds():
    np.testing.assert_array_equal(episode_seeds("val", 3), [10**9, 10**9 + 1, 10**9 + 2])
    assert episode_seeds("test", 0).size == 0 and episode_seeds("train", 2).dtype == np.int64
    with pytest.raises(ValueError, match=r"split must be one of \['test', 'train', 'val'\]"):
        episode_seeds("validation", 1)
    with pytest.raises(ValueError, match="episodes must be in"):
        episode_seeds("train", MAX_SPLIT_EPISODES + 1)


def test_split_seeds_are_defined_once_in_the_task_layer():
    """No module but ``datasets.juggling._records`` assigns ``SPLIT_SEEDS``; every other
    use imports it from ``motion_envs.datasets.juggling``."""
    homes, importers = [], []
    for folder in ("motion_envs", "baselines", "experiments", "benchmarks", "tools"):
        for path in (ROOT / folder).rglob("*.py"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                targets = (
                    [node.target] if isinstance(node, ast.AnnAssign | ast.AugAssign) else []
                ) + (node.targets if isinstance(node, ast.Assign) else [])
                if any(isinstance(t, ast.Name) and t.id == "SPLIT_SEEDS" for t in targets):
                    homes.append(path.relative_to(ROOT).as_posix())
                if isinstance(node, ast.ImportFrom) and any(
                    a.name == "SPLIT_SEEDS" for a in node.names
                ):
                    importers.append((path.relative_to(ROOT).as_posix(), node.module))
    assert homes == ["motion_envs/datasets/juggling/_records.py"]
    assert importers and all(
        module in ("motion_envs.datasets.juggling", "motion_envs.datasets.juggling._records")
        for _, module in importers
    ), importers
