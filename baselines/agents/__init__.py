"""Agents on top of the analytic nominals: zoo-style configs, training, evaluation, sweeps.

* :mod:`~baselines.agents.config`: hyper-parameters from ``configs/agents/ALGO.yaml``
  (keyed by environment id plus ``default``; plain YAML only; shipped in the package as
  ``baselines/configs/agents``), validated;
* :mod:`~baselines.agents.train`: ``motion-bench train`` (``run(TrainConfig)``);
* :mod:`~baselines.agents.ars`: sb3-contrib's ARS for ``--algo ars``, with paired
  episode seeds for the two candidates of a direction;
* :mod:`~baselines.agents.callbacks`: its SB3 callbacks, one job each (validation, save
  the best, report an evaluation), composed as SB3's ``EvalCallback``;
* :mod:`~baselines.agents.rundir`: the run folder (SB3 zip, normalisation statistics as
  ``.npz``, resolved config, manifest with checksums) and loading it back;
* :mod:`~baselines.agents.vec`: the SB3 vector environment of a run (native where the
  environment has one, ``DummyVecEnv`` otherwise);
* :mod:`~baselines.agents.evaluate`: the criterion of a policy on a split and
  ``motion-bench agent`` (``run(AgentConfig)``);
* :mod:`~baselines.agents.scorers`: one scorer per environment family (criterion, the
  agent's results, data or seed-range splits), registered once, looked up by id;
* :mod:`~baselines.agents.reaching_score`: the papers' criterion on a data split;
* :mod:`~baselines.agents.juggling_score`: Juggling-v0's seed-range splits, catch rate and
  the hand's deviation from the demonstrations;
* :mod:`~baselines.agents.cascade_score`: Cascade-v0's catches before the first drop,
  catch rate and drops per catch, agent and juggler on the same seeds;
* :mod:`~baselines.agents.sweep`: ``motion-bench sweep`` on Ray Tune (a package: search
  space, trainable, driver, summary, plot, CLI).

Needs the ``rl`` extra (and ``sweep`` for sweeps); ``import baselines.agents`` is light.
"""
