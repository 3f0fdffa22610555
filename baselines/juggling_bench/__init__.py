"""``motion-bench juggling``: the analytic juggler of Lippi et al. (section III-A).

Demonstrations are SIMULATED by default (:mod:`motion_envs.datasets.juggling`: a
seeded model of a person; the paper's recordings are not public) or read from the users'
CSV (``--data PATH.csv``, :func:`motion_envs.datasets.juggling.read_juggling_csv`). They
are split by demonstration (cycle): the juggler is fitted on the training cycles only
(``N`` per phase by cross-validation inside the training cycles) and scored on the
held-out ones, as :func:`motion_envs.models.juggling.fit_juggler` does for every user.

Reported:

* catch rate of ``--cycles`` seeded cycles in the pure-model world, unperturbed and with
  release-velocity noise (``--noise``, relative std) plus hand tracking noise
  (``--tracking``, m), each with and without the eq. 10 correction (the same seeded
  cycles in every condition);
* per phase, on the held-out demonstrations (all resampled to the same normalised-time
  grid): the median over demonstrations of the max over time of the position error
  (the papers' criterion) and of the RMSE, for Lippi's regression, a minimum-jerk movement
  and a DMP (``movement_primitives``) with the same end points and duration, next to the
  within-person variability (a training demonstration of the same person re-targeted to
  the held-out end points, median over the training demonstrations);
* per phase, the paper's validation of the linear hypothesis on the training cycles
  (Lilliefors, F-test, 95 % intervals, jackknife spread over the estimates);
* a Figure-6-style plot and an animation (GIF) of the juggler.

With ``--levels``: Juggling-v1's levels and reference controllers (and a trained agent
with ``--agent DIR``), :mod:`~baselines.juggling_bench.levels`. With ``--pattern 3``: the
three-ball cascade (``MotionEnvs/Cascade-v0``) at the same levels,
:mod:`~baselines.juggling_bench.cascade` (another siteswap is refused with the reasons it
does not fit the cascade juggler, :func:`pattern_check`).

With ``--analyse FILE``: the ball flights and pattern timing of a recording,
:mod:`~baselines.juggling_bench.analyse`.

:func:`run` computes (a pure function of a frozen :class:`JugglingConfig`: no argparse,
no printing, no files), :func:`report` is the printed text, :func:`write` writes
``results.json``, ``results.csv``, ``juggling_fig6.png`` and ``juggling.gif`` (every file
through :mod:`motion_envs._io`, atomically); :func:`register` adds the sub-command.

The package splits by concern: :mod:`~baselines.juggling_bench.config` (the frozen config
and its checks), :mod:`~baselines.juggling_bench.scoring` (per-phase errors, validation,
catch rates), :mod:`~baselines.juggling_bench.runner` (:func:`run`),
:mod:`~baselines.juggling_bench.text` (report, CSV), :mod:`~baselines.juggling_bench.media`
(:func:`write`: files, figure, GIFs) and :mod:`~baselines.juggling_bench.cli`
(argparse).
"""

from __future__ import annotations

from baselines.juggling_bench.cascade import (
    CascadeConfig,
    CascadeEpisodes,
    cascade_episode,
    cascade_episodes,
    check_cascade_config,
    pattern_check,
    report_cascade,
    run_cascade,
    write_cascade,
)
from baselines.juggling_bench.cli import (
    gravity_task,
    juggling_data,
    level_names,
    main,
    noise_levels,
    register,
    siteswap_pattern,
)
from baselines.juggling_bench.config import (
    MIN_CYCLES,
    TARGET_NOISE5_CORRECTED,
    TARGET_UNPERTURBED,
    TARGET_VARIABILITY_RATIO,
    JugglingConfig,
    check_config,
)
from baselines.juggling_bench.levels import (
    LevelsConfig,
    check_levels_config,
    report_levels,
    run_levels,
    write_levels,
)
from baselines.juggling_bench.media import (
    PHASE_COLORS,
    VIDEO_CAPTION,
    plot_figure6,
    write,
    write_animation,
    write_mujoco_video,
)
from baselines.juggling_bench.runner import load_demos, run
from baselines.juggling_bench.scoring import catch_rates, phase_errors, validation
from baselines.juggling_bench.text import report, results_csv

__all__ = [
    "MIN_CYCLES",
    "PHASE_COLORS",
    "TARGET_NOISE5_CORRECTED",
    "TARGET_UNPERTURBED",
    "TARGET_VARIABILITY_RATIO",
    "VIDEO_CAPTION",
    "CascadeConfig",
    "CascadeEpisodes",
    "JugglingConfig",
    "LevelsConfig",
    "cascade_episode",
    "cascade_episodes",
    "catch_rates",
    "check_cascade_config",
    "check_config",
    "check_levels_config",
    "gravity_task",
    "juggling_data",
    "level_names",
    "load_demos",
    "main",
    "noise_levels",
    "pattern_check",
    "phase_errors",
    "plot_figure6",
    "register",
    "report",
    "report_cascade",
    "report_levels",
    "results_csv",
    "run",
    "run_cascade",
    "run_levels",
    "siteswap_pattern",
    "validation",
    "write",
    "write_animation",
    "write_cascade",
    "write_levels",
    "write_mujoco_video",
]
