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

Use: :func:`generate_cohort` (an :class:`OrientationDataset` with ``simulated=True``,
also ``load_orientation_dataset("cohort[:CONFIG]")``), :func:`iter_cohort` (chunks),
:func:`motion_envs.models.criteria.score_cohort` (Table 1's in-sample rows streamed in
bounded memory),
:func:`draw_trajectory` / :func:`split_labels` (one trajectory with its subject, task,
predictors and train/test split by subject, for any orientation dataset), and
:meth:`CohortGenerator.parameters` / :meth:`CohortGenerator.true_residuals` (the ground
truth behind each trajectory).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.cohort_config import (
    DEFAULT_COHORT,
    CohortConfig,
    load_cohort_config,
)
from motion_envs.datasets.orientation import OrientationDataset
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, MIN_SAMPLES, normalised_grid
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.beta_profile import beta_alpha

__all__ = [
    "DEFAULT_COHORT",
    "CohortGenerator",
    "CohortParameters",
    "TrajectorySample",
    "cohort_size",
    "draw_trajectory",
    "generate_cohort",
    "iter_cohort",
    "load_cohort",
    "sine_basis",
    "split_labels",
]

_TASK_KEY = 1
_SUBJECT_KEY = 2
_NOISE_KEY = 3
_COMPONENTS = ("common", "task", "subject", "subject_task", "trial")


def sine_basis(tau: FloatArray, harmonics: int) -> FloatArray:
    """``sin(k pi tau)`` for ``k = 1 .. harmonics``: ``(n,)`` -> ``(n, harmonics)``."""
    tau = np.asarray(tau, dtype=np.float64)
    k = np.arange(1, harmonics + 1, dtype=np.float64)
    return np.sin(np.pi * tau[..., None] * k)


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


@dataclass(frozen=True)
class CohortParameters:
    """Ground truth of generated trajectories (one row per trajectory, cohort order).

    Attributes
    ----------
    subject_index, task_index, replicate_index:
        ``(L,)`` indices into the subjects, the design's tasks (``all_tasks``, 60) and
        the replicate names.
    predictors:
        ``(L, 3)`` sex (0 female, 1 male), age (years), height (cm).
    coefficients:
        ``(L, K, 3)`` sine coefficients of the residual: ``r_l(tau) = sum_k
        coefficients[l, k] sin((k + 1) pi tau)``.
    start, ends:
        ``(4,)`` start and ``(L, 4)`` end orientations (with jitter).
    a, b:
        ``(L,)`` Beta speed-profile shapes.
    n_samples:
        ``(L,)`` samples per trajectory (at ``sampling_hz``).
    """

    subject_index: NDArray[np.int64]
    task_index: NDArray[np.int64]
    replicate_index: NDArray[np.int64]
    predictors: FloatArray
    coefficients: FloatArray
    start: FloatArray
    ends: FloatArray
    a: FloatArray
    b: FloatArray
    n_samples: NDArray[np.int64]


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
        n_b, n_g = len(des["blocks"]), len(des["grips"])
        j = np.arange(len(self.all_tasks))
        pods = np.radians(np.asarray(list(des["pods"].values()), dtype=np.float64))
        blocks = np.radians(np.asarray(list(des["blocks"].values()), dtype=np.float64))
        grips = np.radians(np.asarray(list(des["grips"].values()), dtype=np.float64))
        zeros = np.zeros(j.size)
        pod = quat.expmap(np.stack([zeros, pods[j // (n_b * n_g)], zeros], axis=1))
        b = blocks[(j // n_g) % n_b]
        block = quat.expmap(np.stack([zeros, b[:, 0], b[:, 1]], axis=1))
        grip = quat.expmap(np.stack([grips[j % n_g], zeros, zeros], axis=1))
        return quat.multiply(quat.multiply(quat.multiply(self.start, pod), block), grip)

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

    def _check_subjects(self, subjects: range | None) -> range:
        n_sub = int(self.config.get("design.n_subjects"))
        subjects = range(n_sub) if subjects is None else subjects
        if (
            not isinstance(subjects, range)
            or subjects.step != 1
            or subjects.start < 0
            or subjects.stop > n_sub
            or len(subjects) == 0
        ):
            raise ValueError(
                f"subjects must be a non-empty contiguous range within range({n_sub}); "
                f"got {subjects!r}"
            )
        return subjects

    def parameters(self, subjects: range | None = None) -> CohortParameters:
        """The ground truth of every trajectory of the given subjects (default: all).

        Per trajectory: subject, task and replicate indices, predictors, the residual's
        sine coefficients, the end orientation, the Beta shapes and the sample count;
        :meth:`generate` turns these into quaternions.
        """
        subjects = self._check_subjects(subjects)
        c = self.config.data
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

        coefs, ends, log_a, log_b, durations = [], [], [], [], []
        subj_idx, task_idx, rep_idx, preds = [], [], [], []
        for i in subjects:
            d = self._subject_draws(i)
            keep = d.keep_u[req] >= dropout  # (J_req, R)
            jj, rr = np.nonzero(keep)
            tj = req[jj]
            coefs.append(
                common[None]
                + task_coef[tj]
                + s_subj * sw * d.curve[None]
                + s_st * sw * d.task_curves[tj]
                + s_trial * sw * d.trial_curves[tj, rr]
            )
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
            subj_idx.append(np.full(tj.size, i, dtype=np.int64))
            task_idx.append(tj)
            rep_idx.append(rr.astype(np.int64))
            preds.append(np.tile([i % 2, d.age, d.height], (tj.size, 1)).astype(np.float64))
        subj = np.concatenate(subj_idx)
        if subj.size == 0:
            raise ValueError(f"no trajectories generated for subjects {subjects!r}")
        D = np.concatenate(durations)
        return CohortParameters(
            subject_index=subj,
            task_index=np.concatenate(task_idx),
            replicate_index=np.concatenate(rep_idx),
            predictors=np.concatenate(preds),
            coefficients=np.concatenate(coefs),
            start=self.start.copy(),
            ends=np.concatenate(ends),
            a=np.exp(np.concatenate(log_a)),
            b=np.exp(np.concatenate(log_b)),
            n_samples=np.maximum(MIN_SAMPLES, np.rint(D * self.hz).astype(np.int64) + 1),
        )

    def true_residuals(
        self, subjects: range | None = None, n_points: int = DEFAULT_N_POINTS
    ) -> FloatArray:
        """The generated residual curves ``r_l`` on the uniform grid, ``(L, n_points, 3)``.

        This is the ground truth the pipeline's measured slerp residuals estimate; they
        differ because the observed speed profile absorbs the part of ``r_l`` along the
        slerp's axis and because of noise, jitter and interpolation.
        """
        prm = self.parameters(subjects)
        basis = sine_basis(normalised_grid(n_points), self.harmonics)
        return np.einsum("nk,lkc->lnc", basis, prm.coefficients)

    def generate(self, subjects: range | None = None) -> OrientationDataset:
        """Generate the trajectories of the given subject indices (default: all).

        The result for ``range(a, b)`` equals the matching slice of the full cohort bit
        for bit (independent random streams per subject).
        """
        subjects = self._check_subjects(subjects)
        prm = self.parameters(subjects)
        L = prm.subject_index.size
        n = prm.n_samples
        offsets = np.concatenate([[0], np.cumsum(n)])
        idx = np.repeat(np.arange(L), n)
        k = np.arange(offsets[-1]) - offsets[idx]
        t = k / self.hz
        tau = k / (n[idx] - 1.0)
        alpha = beta_alpha(tau, prm.a[idx], prm.b[idx])
        slerp = quat.slerp(prm.start, prm.ends[idx], alpha, validate=False)
        r = np.einsum("nk,nkc->nc", sine_basis(tau, self.harmonics), prm.coefficients[idx])
        q = quat.multiply(slerp, quat.expmap(r))
        noise_sd = float(self.config.get("residual.noise_rad")) if self.noise else 0.0
        if noise_sd > 0:
            # trajectories are subject-major, so each subject's samples are contiguous
            per_subject = np.bincount(prm.subject_index - subjects.start, minlength=len(subjects))
            sample_bounds = offsets[np.concatenate([[0], np.cumsum(per_subject)])]
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

        names = np.asarray(self.subject_names)[prm.subject_index]
        tasks = np.asarray(self.all_tasks)[prm.task_index]
        reps = np.asarray(self.replicate_names)[prm.replicate_index]
        ids = np.char.add(np.char.add(np.char.add(np.char.add(names, "-"), tasks), "-"), reps)
        bounds = offsets[1:-1]
        P = prm.predictors
        return OrientationDataset(
            name=f"cohort:{self.config.name}",
            quaternions=tuple(np.split(q, bounds)),
            times=tuple(np.split(t, bounds)),
            trajectory_ids=ids.astype(str),
            subjects=names.astype(str),
            tasks=tasks.astype(str),
            replicates=prm.replicate_index.copy(),
            predictors={"sex": P[:, 0].copy(), "age": P[:, 1].copy(), "height_cm": P[:, 2].copy()},
            simulated=True,
        )

    def iter_chunks(self, chunk_subjects: int = 64) -> Iterator[OrientationDataset]:
        """Yield the cohort in chunks of ``chunk_subjects`` subjects (bounded memory)."""
        if chunk_subjects < 1:
            raise ValueError(f"chunk_subjects must be >= 1; got {chunk_subjects}")
        n_sub = int(self.config.get("design.n_subjects"))
        for start in range(0, n_sub, chunk_subjects):
            yield self.generate(range(start, min(n_sub, start + chunk_subjects)))


@dataclass(frozen=True)
class TrajectorySample:
    """One trajectory drawn from a dataset, with everything a consumer needs.

    ``quaternions`` ``(n, 4)`` (w, x, y, z) and ``times`` ``(n,)`` seconds; ``subject``,
    ``task`` and ``replicate`` labels; ``predictors`` name -> value; ``split`` is
    ``"train"`` or ``"test"`` (split by subject, see
    :func:`motion_envs.datasets.splits.split_by_subject`); ``index`` is the row in the
    dataset.
    """

    index: int
    trajectory_id: str
    quaternions: FloatArray
    times: FloatArray
    subject: str
    task: str
    replicate: int
    predictors: dict[str, float]
    split: str


def split_labels(
    dataset: OrientationDataset, test_fraction: float = 0.25, seed: int = 0
) -> NDArray[np.str_]:
    """``(L,)`` ``"train"``/``"test"`` per trajectory, the split of ``split_by_subject``."""
    from motion_envs.datasets.splits import held_out_subjects

    test = np.isin(dataset.subjects, held_out_subjects(dataset.subjects, test_fraction, seed))
    return np.where(test, "test", "train")


def draw_trajectory(
    dataset: OrientationDataset,
    index: int | None = None,
    rng: np.random.Generator | int | None = None,
    split: str = "all",
    test_fraction: float = 0.25,
    split_seed: int = 0,
) -> TrajectorySample:
    """Draw one trajectory of any :class:`OrientationDataset` (a cohort or real data).

    Give ``index`` (a row of the dataset) or ``rng`` (a ``numpy.random.Generator`` or a
    seed; the trajectory is drawn uniformly among those of ``split``: ``"all"``,
    ``"train"`` or ``"test"``, the split by subject with ``test_fraction`` and
    ``split_seed``).
    """
    if split not in ("all", "train", "test"):
        raise ValueError(f"split must be 'all', 'train' or 'test'; got {split!r}")
    labels = split_labels(dataset, test_fraction, split_seed)
    if index is None:
        if rng is None:
            raise ValueError("give index or rng")
        gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        pool = np.arange(len(dataset)) if split == "all" else np.flatnonzero(labels == split)
        index = int(pool[gen.integers(pool.size)])
    elif rng is not None:
        raise ValueError("give index or rng, not both")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
        raise ValueError(f"index must be an integer; got {index!r}")
    if not -len(dataset) <= index < len(dataset):
        raise ValueError(f"index must be in [0, {len(dataset)}); got {index}")
    i = int(index) % len(dataset)
    if split != "all" and labels[i] != split:
        raise ValueError(f"trajectory {i} is in the {labels[i]!r} split, not {split!r}")
    return TrajectorySample(
        index=i,
        trajectory_id=str(dataset.trajectory_ids[i]),
        quaternions=dataset.quaternions[i],
        times=dataset.times[i],
        subject=str(dataset.subjects[i]),
        task=str(dataset.tasks[i]),
        replicate=int(dataset.replicates[i]),
        predictors={k: float(v[i]) for k, v in dataset.predictors.items()},
        split=str(labels[i]),
    )


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
