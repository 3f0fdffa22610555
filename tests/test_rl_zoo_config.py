"""configs/rl_zoo/ppo.yml has an entry for every registered id (rl-zoo fails without one)."""

from __future__ import annotations

from pathlib import Path

import yaml

import motion_envs

ZOO = Path(__file__).resolve().parents[1] / "configs" / "rl_zoo" / "ppo.yml"


def test_every_registered_id_has_rl_zoo_hyperparameters():
    keys = set(yaml.safe_load(ZOO.read_text(encoding="utf-8")))
    assert set(motion_envs.ENV_IDS) <= keys, sorted(set(motion_envs.ENV_IDS) - keys)
    assert keys <= set(motion_envs.ENV_IDS), sorted(keys - set(motion_envs.ENV_IDS))
