"""Ridge in coefficient space on OrientationCoefficients-v0, with and without the person
calibration summary, leave one person out (the envs' ``fold``), vr-kitchen.

For each fold (held-out person): the training people's episodes give the targets (the
least-squares action of each episode, :meth:`CoefficientEnv.target_actions`) and the
inputs (the env's observation: the context, and with ``calibration=K`` the summary of K
other reaches of the same person, ``n_draws`` draws per episode); the ridge penalty is
chosen by group folds over the training people only; the held-out person's episodes are
scored by the env (each episode's max error averaged over ``n_draws`` calibration draws).
The criterion is the median over all people's episodes (the papers'), comparable to the
``*_predicted_timing`` rows of ``motion-bench orientation`` (the env's base slerp uses
the training people's mean speed profile).

    python experiments/coefficient_calibration.py --k 5
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import motion_envs  # noqa: F401  (registers the ids)

ENV_ID = "MotionEnvs/OrientationCoefficients-v0"


def _observations(env, n_draws: int, seed: int) -> np.ndarray:
    """``(n_draws, L, obs_dim)`` observations of every episode (fresh calibration draws)."""
    L = env.task.n_trajectories
    env.reset(seed=seed)
    return np.stack(
        [
            np.stack([env.reset(options={"trajectory": l})[0] for l in range(L)])
            for _ in range(n_draws)
        ]
    )


def _ridge(X, Y, groups):
    from sklearn.linear_model import Ridge
    from sklearn.model_selection import GridSearchCV, GroupKFold
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    search = GridSearchCV(
        make_pipeline(StandardScaler(), Ridge()),
        {"ridge__alpha": [0.1, 1.0, 10.0, 100.0, 1000.0, 1e4]},
        cv=GroupKFold(n_splits=min(4, len(set(groups)))),
        scoring="neg_mean_squared_error",
    )
    search.fit(X, Y, groups=groups)
    return search


def run(k: int, nominal: str, n_draws: int, seed: int) -> dict:
    errors = {"nominal": [], "ridge": [], f"ridge_person_k{k}": []}
    people = []
    for fold in range(8):
        kw = {"nominal": nominal, "fold": fold}
        for name, cal in (("ridge", 0), (f"ridge_person_k{k}", k)):
            train = gym.make(ENV_ID, split="train", calibration=cal, **kw).unwrapped
            test = gym.make(ENV_ID, split="test", calibration=cal, **kw).unwrapped
            draws = n_draws if cal else 1
            X = _observations(train, draws, seed).reshape(-1, train.observation_space.shape[0])
            Y = np.tile(train.target_actions(), (draws, 1))
            groups = np.tile(np.asarray(train.task.subjects).astype(str), draws)
            model = _ridge(X, Y, groups)
            Xt = _observations(test, draws, seed + 1)
            L = test.task.n_trajectories
            per_draw = [test.score(np.arange(L), model.predict(Xt[r])) for r in range(draws)]
            errors[name].append(np.mean(per_draw, axis=0))
        errors["nominal"].append(
            test.score(np.arange(L), np.zeros((L, test.action_space.shape[0])))
        )
        people.append(np.asarray(test.task.subjects).astype(str))
    out = {name: np.concatenate(v) for name, v in errors.items()}
    groups = np.concatenate(people)
    crit = {name: float(np.median(v)) for name, v in out.items()}
    from baselines.stats import compare_errors

    cmp = compare_errors(
        out[f"ridge_person_k{k}"], out["ridge"], groups, f"ridge_person_k{k}", "ridge"
    )
    return {"criteria": crit, "comparison": cmp.__dict__ if hasattr(cmp, "__dict__") else str(cmp)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--k", type=int, default=5)
    p.add_argument("--nominal", default="slerp")
    p.add_argument("--draws", type=int, default=5)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args()
    t0 = time.perf_counter()
    res = run(a.k, a.nominal, a.draws, a.seed)
    res["seconds"] = time.perf_counter() - t0
    print(json.dumps(res, indent=1, default=str))


if __name__ == "__main__":
    main()
