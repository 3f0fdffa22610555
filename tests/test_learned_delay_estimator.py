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


def _tiny_bench(tmp_path: Path) -> Path:
    """A Cascade-v1 three-ball medium bench folder of 3 test episodes of two rows, played
    now as the bench plays them."""
    from baselines.juggling_bench.cascade_v1 import (
        CascadeV1Config,
        _kwargs,
        cascade_v1_episodes,
        row_summary,
    )

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
    return bench


def test_the_experiment_runs_on_a_tiny_budget(tmp_path: Path) -> None:
    """A bench folder of 3 test episodes of two rows (:func:`_tiny_bench`), then 4
    training episodes, 3 validation episodes, one seed."""
    mod = load_experiment("learned_delay_estimator")
    bench = _tiny_bench(tmp_path)
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


@pytest.mark.parametrize("start", [False, True])
def test_the_start_flights_are_recorded_when_the_start_is_anchored(start: bool) -> None:
    """A flight's first anchor frame arrives its delay plus under 0.1 s after its release
    when the ball is released in the episode (measured on these seeds: 0.05-0.09 s), and
    more than 0.12 s after it for a ball thrown before ``t = 0`` whose first frame is seen
    only after the start (0.14-0.18 s): with the start anchored, each episode's first
    sample is such a start flight; without, no flight is."""
    from baselines.learned.delay_estimator import collect_flights

    kwargs = {"level": "medium", "pattern": "3", "max_catches": 30, "anchor_frames": 20,
              "anchor_start": start}  # fmt: skip
    s = collect_flights("MotionEnvs/Cascade-v1", kwargs, "train", 3, progress=False)
    lag = [[float(s0[0]) - d for s0, _ in fl] for fl, d in zip(s.flights, s.delay, strict=True)]
    first = {e: i for i, e in reversed(list(enumerate(s.episode)))}
    assert len(first) == 3 and all(len(s.flights[i]) == 1 for i in first.values())
    if start:
        assert all(lag[i][0] > 0.12 for i in first.values())
    else:
        assert max(x for row in lag for x in row) < 0.1


def test_anchor_start_run_chooses_on_validation_trains_on_training_then_plays_test(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``run(anchor_start=True)``: every reset has the start anchored; the anchor frames
    are chosen first on validation seeds only (one pass of the choice's episodes per
    declared candidate), the rule is trained on training seeds only, and every test seed
    comes after every training and validation seed; the chosen frames are the candidates'
    best validation mean (ties: the first); the pooled row with the start anchored is
    paired and ``--pair-pooled --anchor-start`` replays the row exactly."""
    from baselines.juggling_bench.v2 import POOLED_ANCHOR_FRAMES
    from motion_envs.envs.juggling import CascadeV1Env

    mod = load_experiment("learned_delay_estimator")
    bench = _tiny_bench(tmp_path)
    seen: list[tuple[int, bool]] = []
    reset = CascadeV1Env.reset

    def spy(self: Any, *, seed: int | None = None, options: Any = None) -> Any:
        seen.append((-1 if seed is None else int(seed), bool(self.anchor_start)))
        return reset(self, seed=seed, options=options)

    monkeypatch.setattr(CascadeV1Env, "reset", spy)
    out = tmp_path / "out"
    got = mod.run("cascade3_medium", bench, out, 3, 2, (0,), progress=False,
                  anchor_start=True, choice_episodes=2)  # fmt: skip
    seeds = [s for s, _ in seen if s >= 0]
    assert all(st for s, st in seen if s >= 0)  # the start anchored in every episode played
    val, train, test = (episode_seeds(split, 3).tolist() for split in ("val", "train", "test"))
    n_choice = 2 * len(POOLED_ANCHOR_FRAMES)
    assert seeds[:n_choice] == val[:2] * len(POOLED_ANCHOR_FRAMES)  # the choice first
    assert seeds[n_choice : n_choice + 2] == val[:2]  # the validation flights
    assert seeds[n_choice + 2 : n_choice + 5] == train  # the training flights
    assert all(s >= SPLIT_SEEDS["test"] for s in seeds[n_choice + 5 :])
    assert set(seeds[n_choice + 5 :]) == set(test)
    c = got["anchor_frames_choice"]
    means = c["val_mean_catches"]
    assert list(means) == [f"{f} frames, start anchored" for f in POOLED_ANCHOR_FRAMES]
    best = max(means.values())
    assert c["anchor_frames"] == POOLED_ANCHOR_FRAMES[list(means.values()).index(best)]
    assert got["env_kwargs"]["anchor_start"] is True
    assert got["env_kwargs"]["anchor_frames"] == c["anchor_frames"]
    assert "delay_rule" not in got["env_kwargs"]
    (s,) = got["seeds"]
    assert set(s["minus"]) == {"delay_estimator_catch", "oracle_catch", mod.POOLED_START}
    assert got["median_seed_against"] == mod.POOLED_START
    assert set(got["oracle_catch_minus_pooled_start"]) == {"catches", "catch_rate"}
    assert got["val_errors_pooled_rule"]["all"]["n"] == got["val_errors_default_rule"]["all"]["n"]
    paired = mod.pair_pooled("cascade3_medium", bench, out, c["anchor_frames"], start=True)
    assert paired["pooled_anchor_start"] is True
    assert paired["seeds"][0]["replay_equals_run"] is True
    # the pooled row paired here is the one the run played on the same seeds
    assert paired["pooled_estimator_catch"] == got["rows"][mod.POOLED_START]
    with pytest.raises(ValueError, match="Cascade-v1"):
        mod.run("v2_medium", bench, out, 3, 2, (0,), anchor_start=True)
