"""A virtual (simulated) cohort reproducing the design of Faraway & Choe's experiment.

**This is simulated data, never real recordings.** The paper's motion capture is not
public; this seeded generative model has the paper's design and, once calibrated
(``motion-bench calibrate-cohort``), Table 1 statistics close to the published ones.
Every parameter lives in a YAML file (``configs/cohorts/*.yaml``, see
:mod:`motion_envs.datasets.cohort_config`); the same file and seed give the same cohort
bit for bit.

Design (``design`` section): ``n_subjects`` subjects (sex alternates female/male by
index, so 20 subjects are 10 + 10; age uniform in ``age_range``; height normal by sex);
tasks ``POD-BLOCK-GRIP`` from 3 pods x 5 blocks x 4 thumb grips, of which the
``requested_tasks`` (35) are performed, each with the ``replicates`` (push, pull); each
trajectory is lost independently with probability ``dropout``; sampling at
``sampling_hz`` (25 Hz).

Trajectory ``l`` of subject ``i``, task ``j``, sampled at ``t_k = k / hz``,
``k = 0 .. n_l - 1`` with normalised time ``tau_k = k / (n_l - 1)``::

    q_l(tau) = slerp(q_s, q_e,l, alpha_l(tau)) * expmap(r_l(tau)) * expmap(eps_lk)

* ``q_s = expmap(start_rotvec)``: fixed start (palm down on the thigh).
* ``q_e,l = q_s * R_pod * R_block * R_grip * expmap(jitter_l)``: the end set by the task
  (``R_pod`` pitch about y, ``R_block = expmap((0, pitch, yaw))``, ``R_grip`` roll about
  x; degrees in the file) with a small per-trial jitter (sd ``endpoint_jitter_deg`` per
  axis).
* ``alpha_l(tau) = I_tau(a_l, b_l)``: Beta speed profile,
  ``log a_l = log a + spread (sqrt(s) z_i + sqrt(1 - s) z_l)`` (same for ``b``), ``s``
  the ``subject_share``.
* Duration ``D_l = max(min_s, (base_s + per_radian_s theta_j) exp(u_i + u_j + u_l))``
  with normal ``u`` of sd ``subject_sd``, ``task_sd``, ``trial_sd``; ``theta_j`` the
  start-to-end angle; ``n_l = round(D_l hz) + 1`` (at least 5).
* Residual ``r_l = c + T_j + S_i + U_ij + E_l``: sine series
  ``f(tau) = sum_{k=1..K} f_k sin(k pi tau)`` with ``f_k`` in R^3, all zero at
  ``tau = 0, 1`` and (for ``K >= 2``) not Bézier curves of low degree:

  - ``c``: common component, the fixed coefficients ``common.coefficients`` times
    ``common.scale`` (the paper's downward tilt: a rotation about +y);
  - ``T_j``: task component, ``task.scale`` times the sum of independent random series
    for the task's pod, block, grip and the task itself, with variance shares
    ``task.weights``;
  - ``S_i``: subject component; ``U_ij``: subject-by-task interaction; ``E_l``: trial
    component; scales ``subject.scale``, ``subject_task.scale``, ``trial.scale``.

  Random series draw ``f_k ~ N(0, scale^2 w_k I_3)`` with ``w_k = k^-decay / sum_m m^-decay``
  (``decay`` = ``residual.decay``; larger is smoother).
* ``eps_lk ~ N(0, noise_rad^2 I_3)``: white measurement noise on every sample.

Random streams: ``numpy.random.SeedSequence(seed, spawn_key=...)`` gives independent
child streams: ``(1,)`` for the task-level draws, ``(2, i)`` for everything about
subject ``i`` and its trials, ``(3, i)`` for subject ``i``'s measurement noise. So a
cohort generated in chunks of subjects (:func:`iter_cohort`, bounded memory) is
identical to the one generated at once, and changing ``n_subjects`` keeps the first
subjects unchanged. Draws are standard normals scaled afterwards, so the criteria are
smooth functions of the scales (what the calibration relies on).

Predictors (numeric, per trajectory): ``sex`` (0 = female, 1 = male), ``age`` (years),
``height_cm``. As in the paper's finding, they have no effect on the motion.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.cohort_config import (
    DEFAULT_COHORT,
    CohortConfig,
    load_cohort_config,
)
from motion_envs.datasets.orientation import OrientationDataset
from motion_envs.geometry import quaternion as quat
from motion_envs.models.slerp_residual import MIN_SAMPLES
from motion_envs.models.speed_profile import beta_alpha

__all__ = [
    "DEFAULT_COHORT",
    "CohortGenerator",
    "cohort_size",
    "generate_cohort",
    "iter_cohort",
    "load_cohort",
    "sine_basis",
]

FloatArray = NDArray[np.float64]

_TASK_KEY = 1
_SUBJECT_KEY = 2
_NOISE_KEY = 3
_COMPONENTS = ("common", "task", "subject", "subject_task", "trial")


def sine_basis(tau: FloatArray, harmonics: int) -> FloatArray:
    """``sin(k pi tau)`` for ``k = 1 .. harmonics``: ``(n,)`` -> ``(n, harmonics)``."""
    tau = np.asarray(tau, dtype=np.float64)
    k = np.arange(1, harmonics + 1, dtype=np.float64)
    return np.sin(np.pi * tau[..., None] * k)


def _rot(axis: int, deg: float) -> FloatArray:
    v = np.zeros(3)
    v[axis] = np.radians(deg)
    return quat.expmap(v)


@dataclass(frozen=True)
class _SubjectDraws:
    """Everything drawn for one subject (all tasks of the design, all replicates)."""

    age: float
    height: float
    curve: FloatArray  # (K, 3) unit draws
    task_curves: FloatArray  # (n_all_tasks, K, 3)
    duration_u: float
    speed_z: FloatArray  # (2,)
    trial_curves: FloatArray  # (n_all_tasks, R, K, 3)
    trial_speed_z: FloatArray  # (n_all_tasks, R, 2)
    trial_duration_u: FloatArray  # (n_all_tasks, R)
    keep_u: FloatArray  # (n_all_tasks, R)
    jitter: FloatArray  # (n_all_tasks, R, 3)


class CohortGenerator:
    """Generator of one configured cohort; see the module docstring for the model.

    Parameters
    ----------
    config:
        A :class:`CohortConfig`, a cohort name (``"faraway2008"``) or a YAML path.
    components:
        Residual components to include (default all of ``common``, ``task``,
        ``subject``, ``subject_task``, ``trial``); the others are switched off. Used
        to check the generator against its own ground truth.
    noise:
        Include the measurement noise (default True).
    """

    def __init__(
        self,
        config: CohortConfig | str | os.PathLike[str] = DEFAULT_COHORT,
        components: tuple[str, ...] | None = None,
        noise: bool = True,
    ) -> None:
        self.config = config if isinstance(config, CohortConfig) else load_cohort_config(config)
        comps = _COMPONENTS if components is None else tuple(components)
        unknown = sorted(set(comps) - set(_COMPONENTS))
        if unknown:
            raise ValueError(f"components must be a subset of {list(_COMPONENTS)}; got {unknown}")
        self.components = comps
        self.noise = bool(noise)
        c = self.config.data
        des = c["design"]
        self.harmonics = int(c["residual"]["harmonics"])
        self.hz = float(des["sampling_hz"])
        self.all_tasks = self.config.all_tasks()
        self.replicate_names = [str(r) for r in des["replicates"]]
        self.requested = [self.all_tasks.index(t) for t in des["requested_tasks"]]
        n_sub = int(des["n_subjects"])
        self.subject_names = [f"S{i + 1:0{max(2, len(str(n_sub)))}d}" for i in range(n_sub)]

    # ----------------------------------------------------------------- task level
    @cached_property
    def start(self) -> FloatArray:
        """``(4,)`` the fixed start orientation ``q_s``."""
        return quat.expmap(np.radians(self.config.get("design.start_rotvec_deg")))

    @cached_property
    def task_ends(self) -> FloatArray:
        """``(n_all_tasks, 4)`` nominal end orientation of every task of the design."""
        des = self.config.data["design"]
        ends = []
        for p in des["pods"].values():
            for pitch, yaw in des["blocks"].values():
                for roll in des["grips"].values():
                    block = quat.expmap(np.radians([0.0, pitch, yaw]))
                    q = quat.multiply(self.start, _rot(1, p))
                    q = quat.multiply(quat.multiply(q, block), _rot(0, roll))
                    ends.append(q)
        return np.stack(ends)

    def task_angles(self) -> FloatArray:
        """``(n_all_tasks,)`` start-to-end rotation angle of each task, radians."""
        return quat.angle(np.broadcast_to(self.start, self.task_ends.shape), self.task_ends)

    def spectral_weights(self) -> FloatArray:
        """``(K,)`` variance share ``w_k = k^-decay / sum_m m^-decay`` of harmonic ``k``."""
        k = np.arange(1, self.harmonics + 1, dtype=np.float64)
        w = k ** -float(self.config.get("residual.decay"))
        return w / w.sum()

    @cached_property
    def _task_draws(self) -> tuple[dict[str, FloatArray], FloatArray]:
        des = self.config.data["design"]
        rng = np.random.default_rng(
            np.random.SeedSequence(self.config.seed, spawn_key=(_TASK_KEY,))
        )
        K = self.harmonics
        draws = {
            "pod": rng.standard_normal((len(des["pods"]), K, 3)),
            "block": rng.standard_normal((len(des["blocks"]), K, 3)),
            "grip": rng.standard_normal((len(des["grips"]), K, 3)),
            "interaction": rng.standard_normal((len(self.all_tasks), K, 3)),
        }
        duration_u = rng.standard_normal(len(self.all_tasks))
        return draws, duration_u

    def common_coefficients(self) -> FloatArray:
        """``(K, 3)`` sine coefficients of the common component (zero if switched off)."""
        out = np.zeros((self.harmonics, 3))
        if "common" in self.components:
            coef = np.asarray(self.config.get("residual.common.coefficients"), dtype=np.float64)
            out[: len(coef)] = coef * float(self.config.get("residual.common.scale"))
        return out

    def task_coefficients(self) -> FloatArray:
        """``(n_all_tasks, K, 3)`` sine coefficients of every task component."""
        des = self.config.data["design"]
        draws, _ = self._task_draws
        if "task" not in self.components:
            return np.zeros((len(self.all_tasks), self.harmonics, 3))
        weights = self.config.get("residual.task.weights")
        total = float(sum(weights.values()))
        n_b, n_g = len(des["blocks"]), len(des["grips"])
        j = np.arange(len(self.all_tasks))
        pod, block, grip = j // (n_b * n_g), (j // n_g) % n_b, j % n_g
        unit = (
            np.sqrt(weights["pod"] / total) * draws["pod"][pod]
            + np.sqrt(weights["block"] / total) * draws["block"][block]
            + np.sqrt(weights["grip"] / total) * draws["grip"][grip]
            + np.sqrt(weights["interaction"] / total) * draws["interaction"]
        )
        scale = float(self.config.get("residual.task.scale"))
        return scale * np.sqrt(self.spectral_weights())[None, :, None] * unit

    # -------------------------------------------------------------- subject level
    def _subject_draws(self, i: int) -> _SubjectDraws:
        rng = np.random.default_rng(
            np.random.SeedSequence(self.config.seed, spawn_key=(_SUBJECT_KEY, i))
        )
        des = self.config.data["design"]
        K, J, R = self.harmonics, len(self.all_tasks), len(self.replicate_names)
        lo, hi = des["age_range"]
        mean, sd = des["height_cm"]["male" if i % 2 else "female"]
        return _SubjectDraws(
            age=float(rng.uniform(lo, hi)),
            height=float(mean + sd * rng.standard_normal()),
            curve=rng.standard_normal((K, 3)),
            task_curves=rng.standard_normal((J, K, 3)),
            duration_u=float(rng.standard_normal()),
            speed_z=rng.standard_normal(2),
            trial_curves=rng.standard_normal((J, R, K, 3)),
            trial_speed_z=rng.standard_normal((J, R, 2)),
            trial_duration_u=rng.standard_normal((J, R)),
            keep_u=rng.uniform(size=(J, R)),
            jitter=rng.standard_normal((J, R, 3)),
        )

    def _scale(self, component: str) -> float:
        if component not in self.components:
            return 0.0
        return float(self.config.get(f"residual.{component}.scale"))

    def generate(self, subjects: range | None = None) -> OrientationDataset:
        """Generate the trajectories of the given subject indices (default: all).

        The result for ``range(a, b)`` equals the matching slice of the full cohort bit
        for bit (independent random streams per subject).
        """
        c = self.config.data
        n_sub = int(c["design"]["n_subjects"])
        subjects = range(n_sub) if subjects is None else subjects
        if subjects.step != 1 or subjects.start < 0 or subjects.stop > n_sub:
            raise ValueError(
                f"subjects must be a contiguous range within range({n_sub}); got {subjects}"
            )
        dur, sp, des = c["durations"], c["speed_profile"], c["design"]
        sw = np.sqrt(self.spectral_weights())[:, None]  # (K, 1)
        common = self.common_coefficients()
        task_coef = self.task_coefficients()
        _, task_u = self._task_draws
        angles = self.task_angles()
        s_subj, s_st, s_trial = (self._scale(k) for k in ("subject", "subject_task", "trial"))
        share = float(sp["subject_share"])
        spread = float(sp["spread"])
        jitter_sd = np.radians(float(des["endpoint_jitter_deg"]))
        dropout = float(des["dropout"])
        req = np.asarray(self.requested, dtype=np.int64)
        R = len(self.replicate_names)

        coefs, ends, log_a, log_b, durations = [], [], [], [], []
        subj_idx, task_idx, rep_idx, preds = [], [], [], []
        for i in subjects:
            d = self._subject_draws(i)
            keep = d.keep_u[req] >= dropout  # (J_req, R)
            jj, rr = np.nonzero(keep)
            tj = req[jj]
            coef = (
                common[None]
                + task_coef[tj]
                + s_subj * sw * d.curve[None]
                + s_st * sw * d.task_curves[tj]
                + s_trial * sw * d.trial_curves[tj, rr]
            )
            coefs.append(coef)
            jit = quat.expmap(jitter_sd * d.jitter[tj, rr])
            ends.append(quat.multiply(self.task_ends[tj], jit))
            z = np.sqrt(share) * d.speed_z[None, :] + np.sqrt(1 - share) * d.trial_speed_z[tj, rr]
            log_a.append(np.log(sp["a"]) + spread * z[:, 0])
            log_b.append(np.log(sp["b"]) + spread * z[:, 1])
            u = (
                dur["subject_sd"] * d.duration_u
                + dur["task_sd"] * task_u[tj]
                + dur["trial_sd"] * d.trial_duration_u[tj, rr]
            )
            base = dur["base_s"] + dur["per_radian_s"] * angles[tj]
            durations.append(np.maximum(dur["min_s"], base * np.exp(u)))
            subj_idx.append(np.full(tj.size, i))
            task_idx.append(tj)
            rep_idx.append(rr)
            preds.append(np.tile([i % 2, d.age, d.height], (tj.size, 1)))

        coef = np.concatenate(coefs) if coefs else np.zeros((0, self.harmonics, 3))
        L = coef.shape[0]
        if L == 0:
            raise ValueError(f"no trajectories generated for subjects {subjects}")
        q_end = np.concatenate(ends)
        a = np.exp(np.concatenate(log_a))
        b = np.exp(np.concatenate(log_b))
        D = np.concatenate(durations)
        n = np.maximum(MIN_SAMPLES, np.rint(D * self.hz).astype(np.int64) + 1)
        offsets = np.concatenate([[0], np.cumsum(n)])
        idx = np.repeat(np.arange(L), n)
        k = np.arange(offsets[-1]) - offsets[idx]
        t = k / self.hz
        tau = k / (n[idx] - 1.0)
        alpha = beta_alpha(tau, a[idx], b[idx])
        slerp = quat.slerp(self.start, q_end[idx], alpha, validate=False)
        basis = sine_basis(tau, self.harmonics)  # (N, K)
        r = np.einsum("nk,nkc->nc", basis, coef[idx])
        q = quat.multiply(slerp, quat.expmap(r))
        noise_sd = float(c["residual"]["noise_rad"]) if self.noise else 0.0
        if noise_sd > 0:
            # trajectories are subject-major, so each subject's samples are contiguous
            per_subject = np.array([c.shape[0] for c in coefs])
            traj_bounds = np.concatenate([[0], np.cumsum(per_subject)])
            sample_bounds = offsets[traj_bounds]
            eps = np.concatenate(
                [
                    np.random.default_rng(
                        np.random.SeedSequence(self.config.seed, spawn_key=(_NOISE_KEY, i))
                    ).standard_normal((int(hi - lo), 3))
                    for i, lo, hi in zip(
                        subjects, sample_bounds[:-1], sample_bounds[1:], strict=True
                    )
                ]
            )
            q = quat.multiply(q, quat.expmap(noise_sd * eps))
        q = quat.normalize(q)

        subj = np.concatenate(subj_idx)
        tj = np.concatenate(task_idx)
        rr = np.concatenate(rep_idx)
        P = np.concatenate(preds)
        names = np.asarray(self.subject_names)[subj]
        tasks = np.asarray(self.all_tasks)[tj]
        reps = np.asarray(self.replicate_names)[rr]
        ids = np.char.add(np.char.add(np.char.add(np.char.add(names, "-"), tasks), "-"), reps)
        bounds = offsets[1:-1]
        return OrientationDataset(
            name=f"cohort:{self.config.name}",
            quaternions=tuple(np.split(q, bounds)),
            times=tuple(np.split(t, bounds)),
            trajectory_ids=ids.astype(str),
            subjects=names.astype(str),
            tasks=tasks.astype(str),
            replicates=rr.astype(np.int64) if R > 1 else np.zeros(L, dtype=np.int64),
            predictors={"sex": P[:, 0], "age": P[:, 1], "height_cm": P[:, 2]},
            simulated=True,
        )

    def iter_chunks(self, chunk_subjects: int = 64) -> Iterator[OrientationDataset]:
        """Yield the cohort in chunks of ``chunk_subjects`` subjects (bounded memory)."""
        if chunk_subjects < 1:
            raise ValueError(f"chunk_subjects must be >= 1; got {chunk_subjects}")
        n_sub = int(self.config.get("design.n_subjects"))
        for start in range(0, n_sub, chunk_subjects):
            yield self.generate(range(start, min(n_sub, start + chunk_subjects)))


def cohort_size(config: CohortConfig) -> int:
    """Expected number of trajectories: subjects x requested tasks x replicates x (1 - dropout)."""
    des = config.data["design"]
    return round(
        des["n_subjects"]
        * len(des["requested_tasks"])
        * len(des["replicates"])
        * (1.0 - des["dropout"])
    )


def generate_cohort(
    config: CohortConfig | str | os.PathLike[str] = DEFAULT_COHORT,
    n_subjects: int | None = None,
    seed: int | None = None,
) -> OrientationDataset:
    """Generate a whole cohort (simulated data; see the module docstring).

    ``n_subjects`` and ``seed`` override the configuration's values.
    """
    cfg = config if isinstance(config, CohortConfig) else load_cohort_config(config)
    overrides: dict[str, object] = {}
    if n_subjects is not None:
        overrides["design.n_subjects"] = int(n_subjects)
    if seed is not None:
        overrides["seed"] = int(seed)
    if overrides:
        cfg = cfg.with_values(**overrides)
    return CohortGenerator(cfg).generate()


def iter_cohort(
    config: CohortConfig | str | os.PathLike[str] = DEFAULT_COHORT,
    chunk_subjects: int = 64,
    n_subjects: int | None = None,
) -> Iterator[OrientationDataset]:
    """Generate a cohort chunk by chunk (e.g. 100,000 trajectories in bounded memory)."""
    cfg = config if isinstance(config, CohortConfig) else load_cohort_config(config)
    if n_subjects is not None:
        cfg = cfg.with_values(**{"design.n_subjects": int(n_subjects)})
    return CohortGenerator(cfg).iter_chunks(chunk_subjects)


def load_cohort(
    config: CohortConfig | str | os.PathLike[str] = DEFAULT_COHORT, min_deg: float = 0.0
) -> OrientationDataset:
    """The configured cohort as an :class:`OrientationDataset` (``simulated=True``).

    Trajectories rotating less than ``min_deg`` degrees are dropped (``n_dropped``).
    """
    return generate_cohort(config).drop_small_rotations(min_deg)
