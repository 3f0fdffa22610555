"""The SB3 callbacks of ``motion-bench train``, one job each, composed as SB3's
``EvalCallback(callback_on_new_best=..., callback_after_eval=...)`` and rl-zoo do.

* :class:`ValidationCallback`: scores the deterministic policy with a validation
  criterion at the start, every ``eval_freq`` steps and at the end; keeps the best
  criterion and the list of evaluations; triggers ``callback_on_new_best`` on a new best
  and ``callback_after_eval`` after every evaluation (both see it as ``self.parent``);
* :class:`KeepAtCallback`: the same schedule without a validation split (a refit):
  triggers ``callback_on_new_best`` once, at the first evaluation point at or after
  ``keep_timesteps``, and then stops the training;
* :class:`SaveBestCallback`: saves the model (and its ``VecNormalize`` statistics) of a
  new best into the run folder;
* :class:`EvaluationHookCallback`: hands each evaluation to a plain function (the Ray
  Tune trial's report).

:func:`baselines.agents.train.run` combines them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.callbacks import BaseCallback, EventCallback

from baselines.agents.rundir import ObsNormalizer, save_model

__all__ = ["EvaluationHookCallback", "KeepAtCallback", "SaveBestCallback", "ValidationCallback"]

#: A validation criterion of a policy (lower is better).
Criterion = Callable[[Callable[[NDArray[np.float32]], NDArray[np.floating]]], float]


class ValidationCallback(EventCallback):
    """Scores the policy on the validation split; keeps the best criterion.

    ``criterion`` maps a deterministic policy (raw observations to actions, through the
    model's ``VecNormalize`` statistics of the moment) to the validation criterion.
    ``last_evaluation`` is the latest ``{"timesteps", "val_criterion",
    "best_val_criterion", "is_best"}``.
    """

    def __init__(
        self,
        criterion: Criterion,
        eval_freq: int,
        callback_on_new_best: BaseCallback | None = None,
        callback_after_eval: BaseCallback | None = None,
    ) -> None:
        super().__init__(callback_after_eval)
        self.criterion = criterion
        self.eval_freq = int(eval_freq)
        self.callback_on_new_best = callback_on_new_best
        if callback_on_new_best is not None:
            callback_on_new_best.parent = self
        self.best = math.inf
        self.best_timesteps = 0
        self.evaluations: list[dict[str, float]] = []
        self.last_evaluation: dict[str, Any] = {}
        self._next = 0

    def _init_callback(self) -> None:
        if self.callback_on_new_best is not None:
            self.callback_on_new_best.init_callback(self.model)

    def _evaluate(self) -> None:
        normalizer = ObsNormalizer.from_vec_normalize(self.model.get_vec_normalize_env())
        model = self.model

        def policy(obs: NDArray[np.float32]) -> NDArray[np.floating]:
            action: NDArray[np.floating] = model.predict(normalizer(obs), deterministic=True)[0]
            return action

        crit = self.criterion(policy)
        is_best = crit < self.best
        if is_best:
            self.best, self.best_timesteps = crit, self.num_timesteps
            if self.callback_on_new_best is not None:
                self.callback_on_new_best.on_step()
        self.evaluations.append({"timesteps": self.num_timesteps, "val_criterion": crit})
        self.logger.record("eval/val_criterion", crit)
        self.logger.record("eval/best_val_criterion", self.best)
        self.last_evaluation = {
            "timesteps": self.num_timesteps,
            "val_criterion": crit,
            "best_val_criterion": self.best,
            "is_best": is_best,
        }
        self._on_event()

    def _on_training_start(self) -> None:
        super()._on_training_start()
        self._evaluate()  # the nominal itself when the action head starts at zero
        self._next = self.num_timesteps + self.eval_freq

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self._evaluate()
            self._next = self.num_timesteps + self.eval_freq
        return True

    def _on_training_end(self) -> None:
        if self.evaluations[-1]["timesteps"] != self.num_timesteps:
            self._evaluate()


class KeepAtCallback(ValidationCallback):
    """:class:`ValidationCallback`'s schedule (start, every ``eval_freq`` steps, end)
    without a criterion: the policy at the first evaluation point at or after
    ``keep_timesteps`` is kept (``callback_on_new_best``, ``best_timesteps``) and the
    training stops there (what follows could not change the kept policy). Evaluations
    are listed with a NaN criterion."""

    def __init__(
        self, keep_timesteps: int, eval_freq: int, callback_on_new_best: BaseCallback
    ) -> None:
        super().__init__(lambda policy: math.nan, eval_freq, callback_on_new_best)
        self.keep_timesteps = int(keep_timesteps)
        self.kept = False

    def _evaluate(self) -> None:
        if not self.kept and self.num_timesteps >= self.keep_timesteps:
            self.kept, self.best_timesteps = True, self.num_timesteps
            assert self.callback_on_new_best is not None
            self.callback_on_new_best.on_step()
        self.evaluations.append({"timesteps": self.num_timesteps, "val_criterion": math.nan})

    def _on_step(self) -> bool:
        return super()._on_step() and not self.kept


class SaveBestCallback(BaseCallback):
    """``agent.zip`` (and ``normalization.npz`` under ``VecNormalize``) in ``run_dir``,
    written each time it is triggered (``callback_on_new_best``)."""

    def __init__(self, run_dir: str | Path) -> None:
        super().__init__()
        self.run_dir = Path(run_dir)

    def _on_step(self) -> bool:
        save_model(self.model, self.run_dir / "agent.zip")
        vn = self.model.get_vec_normalize_env()
        if vn is not None:
            ObsNormalizer.save_vec_normalize(vn, self.run_dir / "normalization.npz")
        return True


class EvaluationHookCallback(BaseCallback):
    """Calls ``hook`` with the parent's ``last_evaluation`` and ``run_dir``
    (``callback_after_eval`` of :class:`ValidationCallback`)."""

    def __init__(self, hook: Callable[[dict[str, Any]], None], run_dir: str | Path) -> None:
        super().__init__()
        self.hook = hook
        self.run_dir = str(run_dir)

    def _on_step(self) -> bool:
        assert isinstance(self.parent, ValidationCallback)
        self.hook({**self.parent.last_evaluation, "run_dir": self.run_dir})
        return True
