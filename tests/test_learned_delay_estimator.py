"""The learned delay rule (baselines.learned.delay_estimator): training reads only the
training seeds, it recovers known delays of noiseless flights between the grid's delays
(where the default rule is off by up to half a step), exact save/load, corrupt and
wrong-shape files refused in one line naming the file, None without flights, and a
tiny-budget run of experiments/learned_delay_estimator.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _helpers import P0, T_R, G, load_experiment, release_frames

from baselines.learned.delay_estimator import (
    N_FEATURES,
    FlightSamples,
    LearnedDelayRule,
    flight_features,
    train_delay_rule,
)
from baselines.learned.model_file import LearnedModelFileError, write_model_file
from motion_envs.datasets.juggling import SPLIT_SEEDS, episode_seeds
from motion_envs.models.juggling import mean_flight_delay


def _anchored(delay: float, n: int = 8) -> tuple[np.ndarray, np.ndarray]:
    frames = release_frames(delay, n)
    s0 = np.array([f.arrival - T_R for f in frames])
    q = np.array([[f.x - P0[0], f.z - P0[1]] for f in frames])
    return s0, q


def _synthetic(n_episodes: int = 40, seed: int = 0) -> FlightSamples:
    """Episodes of 1-3 noiseless flights at a delay drawn in 100-200 ms (0.1 ms steps,
    mostly between the 5 ms grid's delays)."""
    rng = np.random.default_rng(seed)
    s = FlightSamples(G)
    for e in range(n_episodes):
        d = round(float(rng.uniform(0.1, 0.2)), 4)
        for k in (1, 2, 3):
            s.episode.append(e)
            s.flights.append((_anchored(d),) * k)
            s.delay.append(d)
    return s


@pytest.fixture(scope="module")
def fitted() -> LearnedDelayRule:
    return LearnedDelayRule.fit(_synthetic(), seed=0)


@pytest.mark.parametrize("delay", [0.1125, 0.1333, 0.1475, 0.1712])
def test_it_recovers_known_delays_of_noiseless_flights(
    fitted: LearnedDelayRule, delay: float
) -> None:
    # the default rule snaps to the 5 ms grid: 112.5 -> 110, 133.3 -> 135, 147.5 -> 145,
    # 171.2 -> 170 ms; the learned rule reads the residual curve's shape between them
    default = mean_flight_delay([_anchored(delay)], G)
    assert default is not None and abs(default - delay) >= 1.1e-3
    for k in (1, 3):
        got = fitted([_anchored(delay)] * k, G)
        assert got is not None and abs(got - delay) < 0.5e-3


def test_no_flight_tells_no_delay(fitted: LearnedDelayRule) -> None:
    assert fitted([], G) is None
    s0, q = _anchored(0.15)
    assert fitted([(s0 - 1.0, q)], G) is None  # every frame before its release
    assert flight_features([], G) is None


def test_save_load_is_exact(fitted: LearnedDelayRule, tmp_path: Path) -> None:
    path = fitted.save(tmp_path / "rule.safetensors")
    back = LearnedDelayRule.load(path)
    assert back.kind == fitted.kind and back.info == json.loads(json.dumps(fitted.info))
    assert set(back.tensors) == set(fitted.tensors)
    for name, t in fitted.tensors.items():
        assert back.tensors[name].tobytes() == t.tobytes()
    X = np.random.default_rng(1).normal(size=(20, N_FEATURES))
    assert back.correction(X).tobytes() == fitted.correction(X).tobytes()
    flights = [_anchored(0.1333), _anchored(0.141)]
    assert back(flights, G) == fitted(flights, G)


def _one_line_naming(exc: pytest.ExceptionInfo[Any], path: Path) -> None:
    msg = str(exc.value)
    assert str(path) in msg and "\n" not in msg


def test_a_corrupt_file_is_refused(fitted: LearnedDelayRule, tmp_path: Path) -> None:
    path = fitted.save(tmp_path / "rule.safetensors")
    data = path.read_bytes()
    cut = tmp_path / "cut.safetensors"
    cut.write_bytes(data[: len(data) - 16])
    with pytest.raises(LearnedModelFileError) as exc:
        LearnedDelayRule.load(cut)
    _one_line_naming(exc, cut)
    flipped = tmp_path / "flipped.safetensors"
    flipped.write_bytes(data[:-1] + bytes([data[-1] ^ 0xFF]))
    with pytest.raises(LearnedModelFileError, match="weights_sha256") as exc:
        LearnedDelayRule.load(flipped)
    _one_line_naming(exc, flipped)


def test_a_wrong_shape_file_is_refused(fitted: LearnedDelayRule, tmp_path: Path) -> None:
    good = LearnedDelayRule.load(fitted.save(tmp_path / "rule.safetensors"))
    tensors = {**good.tensors, "x_mean": np.zeros(N_FEATURES + 1)}
    header = {"architecture": {"kind": good.kind, "n_inputs": N_FEATURES,
                               "hidden": int(good.tensors.get("W1", np.zeros((1, 0))).shape[1])},
              "features": json.loads(json.dumps(_features(tmp_path, good)))}  # fmt: skip
    bad = tmp_path / "bad.safetensors"
    write_model_file(bad, tensors, header)
    with pytest.raises(LearnedModelFileError, match="x_mean") as exc:
        LearnedDelayRule.load(bad)
    _one_line_naming(exc, bad)


def _features(tmp_path: Path, rule: LearnedDelayRule) -> dict[str, Any]:
    from baselines.learned.model_file import read_model_file

    _, header = read_model_file(rule.save(tmp_path / "again.safetensors"))
    return header["features"]


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("MotionEnvs/Cascade-v1", {"level": "medium", "pattern": "3", "max_catches": 3}),
        ("MotionEnvs/Juggling-v2", {"level": "medium", "max_catches": 1}),
    ],
)
def test_training_reads_only_training_seeds(
    env_id: str, kwargs: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    import gymnasium as gym

    import motion_envs  # noqa: F401

    cls = type(gym.make(env_id, **kwargs).unwrapped)
    seen: list[int] = []
    reset = cls.reset

    def spy(self: Any, *, seed: int | None = None, options: Any = None) -> Any:
        seen.append(-1 if seed is None else int(seed))
        return reset(self, seed=seed, options=options)

    monkeypatch.setattr(cls, "reset", spy)
    rule, samples = train_delay_rule(env_id, kwargs, episodes=3, seed=0, first=2, progress=False)
    assert seen == episode_seeds("train", 5)[2:].tolist()
    assert all(SPLIT_SEEDS["train"] <= s < SPLIT_SEEDS["val"] for s in seen)
    assert set(samples.episode) <= set(seen) and len(samples.delay) > 0
    # the recorded delay is the env's true one: in the level's range
    assert all(0.1 <= d <= 0.2 for d in samples.delay)
    assert rule.info["training_episodes"] == len(set(samples.episode))


def test_the_experiment_runs_on_a_tiny_budget(tmp_path: Path) -> None:
    """A bench folder of 3 test episodes of two rows (played now as the bench plays
    them), then 4 training episodes, 3 validation episodes, one seed."""
    from baselines.juggling_bench.cascade_v1 import (
        CascadeV1Config,
        _kwargs,
        cascade_v1_episodes,
        row_summary,
    )

    mod = load_experiment("learned_delay_estimator")
    config = CascadeV1Config(levels=("medium",), episodes=3, val_episodes=2, max_catches=4,
                             ilc=False)  # fmt: skip
    kept, rows = {}, {}
    for name, ctl in (("delay_estimator_catch", "juggler_delay_estimator_catch"),
                      ("oracle_catch", "juggler_oracle_catch")):  # fmt: skip
        eps = cascade_v1_episodes(None, _kwargs("medium", config, ctl), "test", 3)
        kept[name] = {"seeds": eps.seeds.tolist(), "catches": eps.catches.tolist(),
                      "tosses": eps.tosses.tolist(), "dropped": eps.dropped.tolist(),
                      "time": eps.time.tolist()}  # fmt: skip
        rows[name] = row_summary(eps)
    doc = {"config": {**config.__dict__, "levels": ["medium"]},
           "levels": [{"level": "medium", "best_non_oracle": "delay_estimator_catch",
                       "rows": rows}]}  # fmt: skip
    bench = tmp_path / "bench"
    bench.mkdir()
    (bench / "results.json").write_text(json.dumps(doc))
    (bench / "episodes.json").write_text(json.dumps({"medium": kept}))
    got = mod.run("cascade3_medium", bench, tmp_path / "out", 4, 3, (0,), progress=False)
    assert (tmp_path / "out" / "model_seed0.safetensors").is_file()
    assert json.loads((tmp_path / "out" / "results.json").read_text())["cell"] == "cascade3_medium"
    (s,) = got["seeds"]
    assert set(s["minus"]) == {"delay_estimator_catch", "oracle_catch"}
    assert s["val_errors"]["all"]["n"] == got["val_errors_default_rule"]["all"]["n"] > 0
    assert got["median_seed"] == 0 and got["test_episodes"] == 3
    paired = mod.pair_pooled("cascade3_medium", bench, tmp_path / "out", 8)
    assert paired["seeds"][0]["replay_equals_run"] is True  # the saved rule plays the same
    assert (tmp_path / "out" / "pooled_pairing.json").is_file()
    told = mod.true_delay_reference("cascade3_medium", bench)
    assert told["row"]["catches_mean"] >= 0 and set(told) >= {"minus_oracle_catch"}
    with pytest.raises(ValueError, match="Cascade-v1"):
        mod.true_delay_reference("v2_hard", bench)
