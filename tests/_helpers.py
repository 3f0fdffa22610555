"""Plain helper functions shared by test modules (not a test module: pytest collects nothing here).

Why a module and not conftest fixtures: these take arguments and return values, so an explicit
``from _helpers import ...`` shows the reader where they come from; fixtures (``conftest.py``)
are kept for set-up that a test requests by name (e.g. skipping without an OpenGL backend).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def run_juggler_alone(
    task: Any, noise: Any, seed: int, cycle: int, n_steps: int, world: Any, continuous: bool
) -> tuple[np.ndarray, list[tuple[bool, bool, bool]]]:
    """The analytic juggler alone in ``world``: its hand path and per-step events.

    As ``motion-bench juggling`` runs cycle ``cycle`` of ``seed`` (to the first catch), or,
    with ``continuous``, juggling on and redrawing the noise at each toss as Juggling-v0
    does, for at most ``n_steps`` control periods (stopping at a drop). ``events`` holds
    ``(released, caught, dropped)`` per period.
    """
    from motion_envs.models.juggling import cycle_rngs, load_juggler

    juggler = load_juggler(None, task)
    world_rng, juggler_rng = cycle_rngs(seed, cycle + 1)[cycle]
    home = getattr(juggler, "home_", task.home)
    state = world.reset(home, noise=noise, rng=world_rng)
    juggler.reset(state, juggler_rng)
    hands, events, phase = [], [], juggler.phase
    for _ in range(n_steps):
        target, armed = juggler.command(state)
        if continuous and juggler.phase != phase and juggler.phase == "toss":
            world.redraw_noise(world_rng)
        phase = juggler.phase
        state = world.step(target, armed)
        hands.append(state.hand_pos)
        events.append((state.released, state.caught, state.dropped))
        if state.dropped or (state.caught and not continuous):
            break
    return np.array(hands), events


def train_tiny_run(out: Any) -> Any:
    """A tiny PPO run of OrientationReach-v1 with observation normalisation, trained into
    the folder ``out`` (the run folder that the tampering and fuzz tests change)."""
    import dataclasses
    import warnings

    from baselines.agents.train import run as train_run
    from tests.test_agent_train import tiny_config

    cfg = tiny_config("ppo", "MotionEnvs/OrientationReach-v1", out)
    overrides = {**cfg.overrides, "normalize": {"obs": True, "reward": False}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        train_run(dataclasses.replace(cfg, overrides=overrides))
    return out


def reset_poisoned(env: Any, clean: np.ndarray, subjects: np.ndarray, l: int) -> Any:
    """Reset a calibrated reaching env (unwrapped) on trajectory ``l`` with the features of
    that trajectory and of every other person's NaN (only the person's other reaches
    clean): the reset's ``(obs, info)``."""
    poisoned = clean.copy()
    poisoned[l] = np.nan
    poisoned[subjects != subjects[l]] = np.nan
    env._calibration.features = poisoned
    return env.reset(options={"trajectory": l})


def rollout_digest(env: Any, seed: int) -> str:
    """A SHA-256 of a zero-action Cascade-v1 episode reset with ``seed`` (the residuals
    and any timing entry 0): every observation, reward and the balls' states in
    ``info``, step by step."""
    import hashlib

    h = hashlib.sha256()
    obs, _ = env.reset(seed=seed)
    h.update(obs.tobytes())
    done = False
    while not done:
        obs, reward, te, tr, info = env.step(np.zeros(env.action_space.shape, np.float32))
        done = te or tr
        h.update(obs.tobytes() + np.float64(reward).tobytes() + info["balls"].tobytes())
    return h.hexdigest()


def load_experiment(name: str) -> Any:
    """``experiments/NAME.py`` as a module, registered in ``sys.modules`` under ``name`` (so
    its dataclasses resolve their module); a script that needs ``benchmarks/``'s
    ``_timing`` puts it on ``sys.path`` itself."""
    import importlib.util
    import sys
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "experiments" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


#: A noiseless flight for the release-anchored estimators' hand-worked tests: released at
#: ``T_R`` (s) from ``P0`` at ``V0`` (m, m/s) under gravity ``G``.
P0, V0, T_R, G = (0.1, 1.0), (-0.8, 3.5), 1.0, 9.81


def release_flight(t: float) -> np.ndarray:
    """The ball of that flight at time ``t``, ``(x, z)``."""
    s = t - T_R
    return np.array([P0[0] + V0[0] * s, P0[1] + V0[1] * s - 0.5 * G * s * s])


def release_frames(delay: float, n: int) -> list[Any]:
    """``n`` noiseless camera frames of that flight, captured every 10 ms from 10 ms
    after the release, arriving ``delay`` s later (put ``delay`` on the estimators' 5 ms
    grid)."""
    from motion_envs.models.juggling import CameraFrame

    out = []
    for j in range(1, n + 1):
        c = T_R + 0.01 * j
        x, z = release_flight(c)
        out.append(CameraFrame(c, c + delay, float(x), float(z)))
    return out


def check_env_contract(env: Any) -> None:
    """Gymnasium's and SB3's checkers pass on ``env`` (unwrapped) and ``reset(seed)`` is
    deterministic under a random action (at most 300 steps)."""
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check

    check_env(env.unwrapped, skip_render_check=True)
    sb3_check(env.unwrapped, warn=True)

    def play(seed: int) -> np.ndarray:
        rng = np.random.default_rng(0)
        obs, _ = env.reset(seed=seed)
        path = [obs]
        for _ in range(300):
            obs, _, term, trunc, _ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            path.append(obs)
            if term or trunc:
                break
        return np.stack(path)

    np.testing.assert_array_equal(play(1003), play(1003))


def check_timing_entry(env: Any, plain: Any) -> None:
    """``env`` (a wrapped env with a timing entry) has one action entry more than
    ``plain`` (the same without it), and passes :func:`check_env_contract`."""
    assert env.action_space.shape == (plain.action_space.shape[0] + 1,)
    check_env_contract(env)


def ranked_v2_play(
    spy: Any, calls: list[tuple[str, dict[str, Any], bool]], controller: str, wins: Any
) -> Any:
    """A Juggling-v2 bench ``play`` over ``spy`` (``tests/test_juggling_v2_bench.Spy``)
    that records ``(split, kwargs, choosing)`` in ``calls`` and ranks synthetically: the
    release-anchored ``juggler_delay_estimator`` catches nothing, a play of ``controller``
    catches every toss where ``wins(kwargs, split)`` and none elsewhere, any other play
    as the spy's."""
    from dataclasses import replace

    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        calls.append((split, kwargs, spy.choosing))
        eps = spy.play(policy, env_id, kwargs, split, n)
        if kwargs["controller"] == "juggler_delay_estimator":
            return replace(eps, catches=np.zeros(n, dtype=np.int64), dropped=np.ones(n, bool))
        if kwargs["controller"] != controller:
            return eps
        catches = np.full(n, 3 if wins(kwargs, split) else 0)
        return replace(eps, catches=catches, dropped=catches < 3)

    return play


def assert_validation_first_in_grid_order(
    calls: list[tuple[str, dict[str, Any], bool]], key: Any, grid: Any
) -> None:
    """A bench's choice on a grid read validation seeds only: the plays made while
    choosing (``calls``: split, env keywords, whether choosing) are ``grid``'s candidates
    in order (``key(kwargs)`` of each), all on validation seeds, and every validation play
    comes before the first test play."""
    chosen = [(s, kw) for s, kw, choosing in calls if choosing]
    assert [s for s, _ in chosen] == ["val"] * len(grid)
    assert [key(kw) for _, kw in chosen] == list(grid)
    splits = [s for s, _, _ in calls]
    assert "test" in splits and "val" not in splits[splits.index("test") :]


def rank_cascade_catches(
    spy: Any, calls: list[tuple[str, dict[str, Any], bool]], score: Any
) -> None:
    """Make a Cascade-v1 bench spy (``tests/test_cascade_v1.Spy``) record ``(split,
    kwargs, choosing)`` in ``calls`` and catch ``score(kwargs, split)`` in each play, or,
    where that is None, what the spy's own ``catches`` gives."""
    catches = spy.catches

    def ranked(policy: Any, kwargs: dict[str, Any], split: str) -> int:
        calls.append((split, kwargs, spy.choosing))
        got = score(kwargs, split)
        return catches(policy, kwargs, split) if got is None else int(got)

    spy.catches = ranked


def run_ranked_v2(
    controller: str, wins: Any, **choosers: Any
) -> tuple[dict[str, Any], list[tuple[str, dict[str, Any], bool]]]:
    """Juggling-v2's bench on one small medium level (5 test and 4 validation episodes,
    no ILC) over a spy ranked by :func:`ranked_v2_play` (``controller`` catches every toss
    where ``wins(kwargs, split)``), each chooser keyword's function spied: the bench's
    document and the plays ``(split, kwargs, choosing)``."""
    from baselines.juggling_bench.v2 import V2Config, run_v2
    from tests.test_juggling_v2_bench import Spy

    spy = Spy()
    calls: list[tuple[str, dict[str, Any], bool]] = []
    play = ranked_v2_play(spy, calls, controller, wins)
    config = V2Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    doc = run_v2(config, play, **{k: spy.chooser(f) for k, f in choosers.items()})
    return doc, calls


def run_ranked_cascade_v1(
    score: Any, **choosers: Any
) -> tuple[dict[str, Any], list[tuple[str, dict[str, Any], bool]]]:
    """Cascade-v1's bench likewise (:func:`rank_cascade_catches` with ``score``): the
    bench's document and the plays."""
    from baselines.juggling_bench.cascade_v1 import CascadeV1Config, run_cascade_v1
    from tests.test_cascade_v1 import Spy

    spy = Spy()
    calls: list[tuple[str, dict[str, Any], bool]] = []
    rank_cascade_catches(spy, calls, score)
    config = CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    doc = run_cascade_v1(config, spy.play, **{k: spy.chooser(f) for k, f in choosers.items()})
    return doc, calls


#: The juggling benches' rows whose parameter a grid chooses (Juggling-v2's and
#: Cascade-v1's alike): when the pick is made on the grids' episodes their plays score them.
GRID_ROWS = frozenset(
    {
        "juggler",
        "best_constant",
        "juggler_mean_delay",
        "late_meeting",
        "delay_tracker",
        "delay_estimator_catch",
        "estimator_offset_catch",
        "estimator_tracker_catch",
        "pooled_estimator_catch",
    }
)


def recording_ilc(calls: list[tuple[str, int, bool, str]], spy: Any, episodes: Any) -> Any:
    """A stand-in for a bench's task-error ILC class recording its training and plays in
    ``calls`` as ``(split, n, spy.choosing, "ilc")`` (training: split ``"train"``, n 0);
    its ``evaluate(split, n)`` returns ``episodes(split, n)``."""

    class RecordingILC:
        c, d, history = np.zeros(2), 0.1, []

        def __init__(self, *args: Any) -> None:
            pass

        def train(self) -> None:
            calls.append(("train", 0, spy.choosing, "ilc"))

        def evaluate(self, split: str, n: int) -> Any:
            calls.append((split, n, spy.choosing, "ilc"))
            return episodes(split, n)

    return RecordingILC


def assert_picked_on(
    doc: dict[str, Any],
    calls: list[tuple[str, int, bool, str]],
    counts: tuple[int, int],
    rows: Any,
) -> None:
    """A juggling bench's pick of the best row read ``counts = (val_episodes,
    pick_episodes)`` validation episodes as it should: ``calls`` (its plays ``(split, n,
    choosing, controller)``, the ILC's training as split ``"train"``) show the grids on
    ``val_episodes``, the pick on ``pick_episodes`` of each row of ``rows`` (the
    non-reference rows) once, or with equal counts of those off a grid only (the grids'
    plays reused), the training and every validation play before the first test play;
    the document's ``seeds`` say both counts."""
    from motion_envs.datasets.juggling import SPLIT_SEEDS

    val_episodes, pick_episodes = counts
    first = SPLIT_SEEDS["val"]
    assert doc["seeds"]["choice"] == {"split": "val", "first": first, "count": val_episodes}
    assert doc["seeds"]["pick"] == {"split": "val", "first": first, "count": pick_episodes}
    assert {(s, n) for s, n, choosing, _ in calls if choosing} == {("val", val_episodes)}
    pick = [n for s, n, choosing, _ in calls if s == "val" and not choosing]
    assert set(pick) == {pick_episodes}
    played = set(rows) if pick_episodes > val_episodes else set(rows) - GRID_ROWS
    assert len(pick) == len(played)
    splits = [s for s, _, _, _ in calls]
    assert "test" in splits and "val" not in splits[splits.index("test") :]
    assert splits.index("train") < splits.index("test")


def pick_ranking_catches(
    kwargs: dict[str, Any], split: str, n: int, first: int, late: int
) -> np.ndarray:
    """The catches of ``n`` episodes of a juggling bench's play that tell a pick of the
    best row on 4 validation episodes from one on more: on validation
    ``juggler_mean_delay_catch`` catches ``first`` in each of the first 4 episodes and
    none after, ``juggler_mean_delay`` at +40 ms (late meeting's grid candidate) ``late``
    in every episode; every other play, and every test play, none."""
    catches = np.zeros(n, dtype=np.int64)
    ctl = kwargs["controller"]
    if split == "val" and ctl == "juggler_mean_delay_catch":
        catches[:4] = first
    elif split == "val" and ctl == "juggler_mean_delay" and kwargs.get("delay_offset") == 0.04:
        catches[:] = late
    return catches
