"""``motion-bench sweep``: many configurations x seeds of ``motion-bench train`` on Ray Tune.

A sweep file (``configs/sweeps/NAME.yaml``, plain YAML) names a search over algorithms,
environment ids, hyper-parameters and environment kwargs, and the seeds every
configuration is trained with::

    search: grid              # grid (every combination), random or optuna (num_samples)
    num_samples: 4            # random, optuna: configurations to try
    random_seed: 0            # random: numpy.random.default_rng(random_seed); optuna: TPE seed
    seeds: [0, 1, 2, 3, 4]
    timesteps: 100000         # optional overrides of the agent config
    n_envs: 8
    test_split: test
    inner_folds: 3            # optional: checkpoints by inner folds over people, then a refit
    space:
      algo: [ppo]
      env_id: [MotionEnvs/OrientationReach-v0, MotionEnvs/OrientationReach-v1]
      hyperparams: {learning_rate: [3.0e-4, 1.0e-3]}
      env_kwargs: {nominal: [bezier-null]}

Grid values are lists; a random search also takes ``{uniform: [lo, hi]}``,
``{loguniform: [lo, hi]}`` and ``{randint: [lo, hi]}`` (inclusive) and draws
``num_samples`` configurations up front, so every seed of a configuration trains the same
hyper-parameters. ``search: optuna`` takes the same space and lets Optuna's TPE sampler
(Ray Tune's ``OptunaSearch``) propose ``num_samples`` configurations one after another,
each trial training its configuration on every seed in turn and minimising the median
validation criterion over seeds. Otherwise each (configuration, seed) is one Ray Tune
trial that calls
:func:`baselines.agents.train.run`, the code path of ``motion-bench train`` (runs in
``OUT/runs/``), reports the validation criterion after every evaluation with the run
folder as its checkpoint, and at the end scores the best-on-validation policy on the test
split (:func:`baselines.agents.evaluate.run`). The summary table has one row per
configuration: median and spread over seeds of the test criterion and of its ratio to the
zero-action nominal (``n/a`` where the nominal's criterion is 0: the analytic juggler of
``Juggling-v0`` drops nothing at 5 % noise; juggling rows add the catch rates and the
hand's deviation ratio, and the plot then shows the criterion itself); the configuration
marked ``best`` has the lowest median *validation* criterion (the test split plays no
part in the choice).

With ``inner_folds: K`` (leave-one-person-out sweeps, ``env_kwargs.fold``) each trial
is nested (:mod:`~baselines.agents.sweep.nested`): ``K`` inner agents validated on
groups of the fold's training people choose the kept step, then one agent is refitted on
all of them; per fold, the configuration with the best inner score is reported
(:mod:`~baselines.agents.sweep.lopo`).

Ray: by default a local instance with ``--num-cpus`` (default: the machine's cores), one
CPU per trial; ``--address ADDR`` (e.g. ``auto``) joins an existing cluster started with
``ray start`` (so does Ray's ``RAY_ADDRESS`` environment variable when ``--address`` is
not given). On a cluster ``--out`` must be on storage every node sees (NFS, a shared
mount). ``--resume`` continues an interrupted sweep (Ctrl-C, which ends the command with
that advice, or a crash) in the same ``--out``: Ray Tune keeps its finished trials as they
are and starts the unfinished ones over (a trial whose run folder was finished is only
scored again: ``resumed`` in trials.csv); on an ``--out`` with no sweep it starts one.
Without ``--resume`` an ``--out`` that holds a sweep is refused, and ``--resume`` refuses a
sweep file whose settings differ from the ones recorded in ``OUT/sweep.json``.

Files: every file motion-envs writes (each trial's run folder, sweep.json, results.json,
trials.csv, table.csv, table.md, sweep.png) goes through :mod:`motion_envs._io` (atomic
replace).
Ray Tune's own experiment state, trial results and checkpoint copies under ``--out`` are
written by Ray itself (its storage layer); their consistency on interruption is Ray's
business, which is what ``--resume`` (``Tuner.restore``) relies on.

The package splits by concern, after Ray Tune's driver-apart-from-trainable pattern:
:mod:`~baselines.agents.sweep.space` (the sweep file, the search space),
:mod:`~baselines.agents.sweep.trainable` (one trial; knows nothing of the driver),
:mod:`~baselines.agents.sweep.driver` (Ray, ``Tuner``, ``Tuner.restore``: :func:`run`),
:mod:`~baselines.agents.sweep.summary` (rows, table, result files),
:mod:`~baselines.agents.sweep.plot` and :mod:`~baselines.agents.sweep.cli`.
"""

from __future__ import annotations

from baselines.agents.sweep.cli import register
from baselines.agents.sweep.driver import SweepInterrupted, run, trial_settings
from baselines.agents.sweep.plot import plot_sweep
from baselines.agents.sweep.space import (
    SEARCHES,
    SweepConfig,
    configuration,
    expand_configurations,
    load_sweep,
)
from baselines.agents.sweep.summary import format_table, summarize, write_results
from baselines.agents.sweep.trainable import TrialSettings, train_and_score

__all__ = [
    "SEARCHES",
    "SweepConfig",
    "SweepInterrupted",
    "TrialSettings",
    "configuration",
    "expand_configurations",
    "format_table",
    "load_sweep",
    "plot_sweep",
    "register",
    "run",
    "summarize",
    "train_and_score",
    "trial_settings",
    "write_results",
]
