"""The learned catch-timing policy and its CEM learner (baselines/agents/catch_timing.py)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from baselines.agents import catch_timing as ct
from motion_envs.datasets.juggling import SPLIT_SEEDS

CASCADE_KW = {
    "level": "easy",
    "controller": "juggler_delay_tracker",
    "timing_scale": 0.1,
    "observe_task_error": True,
    "max_catches": 2,
}
V2_KW = {
    "level": "easy",
    "controller": "juggler_delay_tracker",
    "timing_scale": 0.1,
    "observe_task_error": True,
    "max_catches": 2,
}


def test_features_hand_worked() -> None:
    """offset 5 cm -> 1, timing -25 ms -> -0.5, timed 1, caught 3 -> 1, then the bias;
    a hand with no catch yet: zeros and the bias."""
    obs = np.array([[9.0, 9.0, 0.05, -0.025, 1.0, 3.0], [9.0, 9.0, 0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(
        ct.timing_features(obs, 1), [[1.0, -0.5, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0, 1.0]]
    )
    two = np.array([[7.0, 0.0, 0.05, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(ct.timing_features(two, 2)[0], [0, 1, 1, 1, 0, 0, 0, 0, 1])


def test_policy_rows_clip_and_zero() -> None:
    obs = np.array([[0.0, 0.05, 0.0, 1.0, 1.0]] * 2)  # one hand: features (1, 0, 1, 1, 1)
    assert not ct.TimingPolicy(np.zeros(5), 1, 3)(obs).any()
    per_row = ct.TimingPolicy(np.array([[0.2, 0, 0, 0, 0.1], [5.0, 0, 0, 0, 0]]), 1, 3)(obs)
    np.testing.assert_allclose(per_row, [[0, 0, 0.3], [0, 0, 1.0]], atol=1e-7)


def test_zero_policy_is_the_tracker() -> None:
    """``w = 0`` plays the base controller's episodes (the zero action)."""
    seeds = np.array([11, 12], dtype=np.int64)
    zero = ct.play_scores(
        "MotionEnvs/Juggling-v2", V2_KW, ct.TimingPolicy(np.zeros(5), 1, 3), seeds
    )
    import gymnasium as gym

    import motion_envs  # noqa: F401

    env = gym.make("MotionEnvs/Juggling-v2", **V2_KW).unwrapped
    nominal = [env.nominal_episode(int(s)) for s in seeds]
    assert zero[0].tolist() == [p["catches"] for p in nominal]
    assert zero[1].tolist() == [p["tosses"] for p in nominal]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"elite": 11}, "elite must be"), ({"batch": 0}, "batch must be"), ({"sigma": 0.0}, "sigma")],
)
def test_settings_errors(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ct.CEMSettings(**kwargs)


def test_cem_climbs_and_keeps_on_validation(monkeypatch: pytest.MonkeyPatch) -> None:
    """With a known score (catch rate 1 - |w - w*|^2 / 10 per episode), CEM moves its
    mean towards ``w*``; training plays only TRAINING seeds (new ones each generation,
    the same for every candidate), validation only VALIDATION seeds, never a test seed;
    the kept generation is the best on validation."""
    target = np.array([0.5, -0.3, 0.0, 0.2, 0.4])
    played: list[tuple[str, np.ndarray]] = []

    def fake(env_id: str, kwargs: Any, policy: ct.TimingPolicy, seeds: np.ndarray) -> Any:
        w = np.atleast_2d(policy.weights)
        w = np.broadcast_to(w, (len(seeds), w.shape[1]))
        split = "val" if seeds.min() >= SPLIT_SEEDS["val"] else "train"
        assert seeds.max() < SPLIT_SEEDS["test"]
        played.append((split, seeds.copy()))
        loss = ((w - target) ** 2).sum(axis=1)
        return np.round(1000 * (1 - loss / 10)).astype(np.int64), np.full(len(seeds), 1000)

    monkeypatch.setattr(ct, "play_scores", fake)
    settings = ct.CEMSettings(generations=15, population=12, elite=3, batch=2, val_episodes=3)
    out = ct.train_timing_cem("MotionEnvs/Juggling-v2", V2_KW, settings, seed=4)
    assert np.abs(out.weights - target).max() < 0.15
    assert out.kept == int(np.argmax(out.val_scores))
    train = [s for split, s in played if split == "train"]
    assert all((s < SPLIT_SEEDS["val"]).all() for s in train)
    assert len({tuple(np.unique(s)) for s in train}) == settings.generations  # new each time
    assert all(len(np.unique(s)) == settings.batch for s in train)  # shared by candidates
    again = ct.train_timing_cem("MotionEnvs/Juggling-v2", V2_KW, settings, seed=4)
    np.testing.assert_array_equal(again.weights, out.weights)


def _quadratic_scorer(target: np.ndarray, played: list[str]) -> Any:
    """A fake ``play_scores``: catches fall with the squared distance of ``w`` from
    ``target``; records each call's split."""

    def fake(env_id: str, kwargs: Any, policy: ct.TimingPolicy, seeds: np.ndarray) -> Any:
        w = np.broadcast_to(np.atleast_2d(policy.weights), (len(seeds), len(target)))
        played.append("val" if seeds.min() >= SPLIT_SEEDS["val"] else "train")
        loss = ((w - target) ** 2).sum(axis=1)  # resolved to 1e-6: no ties near the base
        return np.round(10**6 * (1 - loss / 10)).astype(np.int64), np.full(len(seeds), 10**6)

    return fake


def test_keep_base_keeps_w0_when_no_generation_beats_it_on_validation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The best policy IS the base (target 0): every generation's mean lies off it, so
    validation scores each below the base, and ``keep_base`` keeps the base (zeros);
    without it the argmax keeps a generation below the base. With the target far from 0
    the learner's generation beats the base and is kept either way."""
    played: list[str] = []
    settings = ct.CEMSettings(generations=3, population=6, elite=2, batch=2, val_episodes=3)
    monkeypatch.setattr(ct, "play_scores", _quadratic_scorer(np.zeros(5), played))
    plain = ct.train_timing_cem("MotionEnvs/Juggling-v2", V2_KW, settings, seed=1)
    assert plain.kept >= 0 and np.isnan(plain.base_score)
    assert played.count("val") == settings.generations  # no base played
    played.clear()
    kb = replace(settings, keep_base=True)
    kept = ct.train_timing_cem("MotionEnvs/Juggling-v2", V2_KW, kb, seed=1)
    assert played.count("val") == settings.generations + 1 and played[0] == "val"  # base first
    assert kept.base_score == 1.0 > max(kept.val_scores)  # the base: zero loss
    assert kept.kept == -1
    np.testing.assert_array_equal(kept.weights, np.zeros(5))
    assert kept.val_scores == plain.val_scores  # the base changes nothing else
    far = np.array([2.0, -1.5, 0.0, 1.0, 1.2])
    monkeypatch.setattr(ct, "play_scores", _quadratic_scorer(far, []))
    learned = ct.train_timing_cem("MotionEnvs/Juggling-v2", V2_KW, kb, seed=1)
    assert learned.kept == int(np.argmax(learned.val_scores)) >= 0
    assert max(learned.val_scores) > learned.base_score


def test_cem_refuses_an_env_without_the_timing_entry() -> None:
    with pytest.raises(ValueError, match="timing_scale > 0"):
        ct.train_timing_cem(
            "MotionEnvs/Juggling-v2", {"level": "easy"}, ct.CEMSettings(generations=1), 0
        )


def test_felt_errors_hand_worked() -> None:
    """One hand, two rows: a timed catch of -20 ms, the held entries repeated, an untimed
    catch, a timed +40 ms (S = +20 ms, n = 2, mean +10 ms), then a new episode (the count
    falls): cleared. Features (S / 50 ms, mean / 50 ms)."""
    felt = ct.FeltErrors()

    def obs(*rows: tuple[float, float, float]) -> np.ndarray:
        return np.array([[7.0, 0.01, timing, timed, count] for timing, timed, count in rows])

    got = [
        felt.update(obs((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), 1),
        felt.update(obs((-0.02, 1.0, 1.0), (0.0, 0.0, 0.0)), 1),
        felt.update(obs((-0.02, 1.0, 1.0), (0.03, 1.0, 1.0)), 1),
        felt.update(obs((0.0, 0.0, 2.0), (0.03, 1.0, 1.0)), 1),
        felt.update(obs((0.04, 1.0, 3.0), (0.03, 1.0, 1.0)), 1),
        felt.update(obs((0.0, 0.0, 0.0), (0.03, 1.0, 1.0)), 1),
    ]
    want = [
        [[0, 0], [0, 0]],
        [[-0.4, -0.4], [0, 0]],
        [[-0.4, -0.4], [0.6, 0.6]],
        [[-0.4, -0.4], [0.6, 0.6]],
        [[0.4, 0.2], [0.6, 0.6]],
        [[0, 0], [0.6, 0.6]],
    ]
    for g, w in zip(got, want, strict=True):
        np.testing.assert_allclose(g, w, atol=1e-12)
    # a batch of another size starts afresh
    np.testing.assert_allclose(felt.update(obs((0.01, 1.0, 1.0)), 1), [[0.2, 0.2]], atol=1e-12)


def test_memory_policy_features_and_zero_weights() -> None:
    assert ct.n_features(1) == 5 and ct.n_features(1, memory=True) == 7
    assert ct.n_features(2, memory=True) == 13
    policy = ct.TimingPolicy(np.array([0, 0, 0, 0, 0.5, 0, 0.1]), 1, 3, memory=True)
    first = policy(np.array([[9.0, 0.0, 0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(first, [[0, 0, 0.1]], atol=1e-7)  # nothing felt: the bias
    after = policy(np.array([[9.0, 0.0, -0.02, 1.0, 1.0]]))  # S = -20 ms -> -0.4
    np.testing.assert_allclose(after, [[0, 0, 0.5 * -0.4 + 0.1]], atol=1e-7)


def test_the_memory_sums_the_felt_timings_of_a_real_episode() -> None:
    """Called on every step of real Juggling-v2 episodes, the memory's sum is the sum of
    ``info["task_error"]``'s timings over the catches that had one (the env's own record,
    an independent count)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401

    kw = {**V2_KW, "level": "medium", "max_catches": 4}
    policy = ct.TimingPolicy(np.zeros(ct.n_features(1, True)), 1, 3, memory=True)
    env = gym.make("MotionEnvs/Juggling-v2", **kw)
    checked = 0
    for seed in (3, 4, 5):
        obs, _ = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs[None])[0])
            done = terminated or truncated
            if "task_error" in info and np.isfinite(info["task_error"][1]):
                total += float(info["task_error"][1])
                checked += 1
        policy(obs[None])  # the last observation: its catch is counted too
        assert policy.felt.total[0, 0] == pytest.approx(total, abs=1e-6)
    assert checked >= 3


def test_paired_gain_of_catches_is_the_paired_t_tests() -> None:
    """Cascades: the mean paired difference and its standard error, as scipy's paired t
    test has them (t = mean / se)."""
    from scipy import stats

    rng = np.random.default_rng(4)
    a, b = rng.poisson(4, 40), rng.poisson(3, 40)
    gain, se = ct.paired_gain((a, np.ones(40, np.int64)), (b, np.ones(40, np.int64)), True)
    assert gain == pytest.approx(float(np.mean(a - b)))
    assert gain / se == pytest.approx(float(stats.ttest_rel(a, b).statistic))


def test_paired_gain_of_a_pooled_rate_hand_worked() -> None:
    """One ball, two episodes: played 3/4 and 1/2 (R = 4/6), base 2/4 and 1/2 (R' = 3/6);
    influences (c - R t) / mean t: (1/3, -1/3) / 3 and (0, 0) / 3; gain 1/6; the paired
    differences (1/9, -1/9) have sd sqrt(2)/9, so se = 1/9."""
    gain, se = ct.paired_gain((np.array([3, 1]), np.array([4, 2])),
                              (np.array([2, 1]), np.array([4, 2])), False)  # fmt: skip
    assert gain == pytest.approx(1 / 6) and se == pytest.approx(1 / 9)
    with pytest.raises(ValueError, match="paired"):
        ct.paired_gain((np.array([1]), np.array([1])), (np.array([1, 2]), np.array([1, 2])), True)


def test_keep_margin_keeps_the_base_within_the_noise(monkeypatch: pytest.MonkeyPatch) -> None:
    """A best generation above the base on validation by less than the margin's standard
    errors loses to the base; with margin 0 the same run keeps the generation."""

    def fake(env_id: str, kwargs: Any, policy: ct.TimingPolicy, seeds: np.ndarray) -> Any:
        ones = np.ones(len(seeds), np.int64)
        if seeds.min() < SPLIT_SEEDS["val"]:  # training: every candidate alike
            return 10 * ones, ones
        noise = np.random.default_rng(seeds).integers(-3, 4, len(seeds))  # +-3 catches
        lift = 1 if np.abs(policy.weights).sum() > 0 else 0  # a learned w: +1 on every other
        return 10 + noise + lift * (np.arange(len(seeds)) % 2), ones

    monkeypatch.setattr(ct, "play_scores", fake)
    base = ct.CEMSettings(generations=2, population=4, elite=2, batch=2, val_episodes=20,
                          keep_base=True)  # fmt: skip
    any_gain = ct.train_timing_cem("MotionEnvs/Cascade-v1", CASCADE_KW, base, seed=0)
    assert any_gain.kept >= 0 and any_gain.gain[0] == pytest.approx(0.5)
    margin = ct.train_timing_cem(
        "MotionEnvs/Cascade-v1", CASCADE_KW, replace(base, keep_margin=50.0), seed=0
    )
    assert margin.kept == -1 and margin.gain == any_gain.gain
    with pytest.raises(ValueError, match="keep_base"):
        ct.CEMSettings(keep_margin=1.0)
    with pytest.raises(ValueError, match="keep_margin"):
        ct.CEMSettings(keep_base=True, keep_margin=-1.0)
