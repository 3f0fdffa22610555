"""The native vector environments' step as one compiled loop (numba backend).

:func:`batch_step` advances every sub-environment by one step in a single call: action
check and clipping, the step kernel (:func:`~motion_envs.envs._kernels.orientation_step_scalar`
or :func:`~motion_envs.envs._kernels.position_step_scalar`, compiled unchanged), the
reward (:func:`~motion_envs.envs._kernels.orientation_reward` /
:func:`~motion_envs.envs._kernels.position_reward`, compiled unchanged), the episode
counters, the next observation, and the autoreset of Gymnasium's three
:class:`~gymnasium.vector.AutoresetMode` s. Same expressions in the same order as the
single environments and the numpy path of :mod:`motion_envs.envs.vector`, correctly
rounded ``+ - * / sqrt`` and libm's ``sin``/``cos`` (as ``math``), no fast-math, so the
results are bit-identical (tested).

State layout (shared with the numpy path of :mod:`motion_envs.envs.vector`):

* ``steps[l, k]`` (float64): the step row of trajectory ``l`` at grid point ``k`` (the
  task's ``steps``), and one extra row ``k = n`` holding the trajectory's start state
  (``dim`` values), the lower and upper bounds of the current state in the observation
  (``dim`` each; infinite when not clipped), ``residual_scale`` and the reward weights;
* ``si[i]`` (int64): trajectory index, grid point ``k``, elapsed steps, autoreset flag,
  position in the trajectory pool, then the pool (the next trajectory indices);
* ``sf[i]`` (float64): current state (``dim`` values), running max error, running max
  geodesic error (orientation);
* ``out_f`` rows: reward, then the info terms (orientation: error, geodesic error,
  reward_residual, reward_geodesic, reward_action, tau, max_error, max_geodesic_error;
  position: error, reward_distance, reward_action, tau, max_error, unused);
* ``out_b`` rows: terminated, truncated, mask of the step infos, mask of the
  sub-environments reset in this step.

Importing this module imports numba (the ``fast`` extra); the first call compiles
(38 s measured on a shared 2-core machine under load average 15), then it is cached on
disk (3 s to load there).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from motion_envs.envs import _kernels as K

__all__ = ["DISABLED", "NEXT_STEP", "ORIENTATION", "POSITION", "SAME_STEP", "batch_step"]

# autoreset modes and environment kinds (integers for the compiled code)
NEXT_STEP, SAME_STEP, DISABLED = 0, 1, 2
ORIENTATION, POSITION = 0, 1
# si columns
IDX, K_, ELAPSED, AUTORESET, PTR, POOL = 0, 1, 2, 3, 4, 5

# error_model="numpy": no zero-division checks (no divisor can be 0; the kernels guard
# their small-angle cases); never fastmath, which would reorder the arithmetic
_jit = njit(cache=True, error_model="numpy")
_orientation_step = _jit(K.orientation_step_scalar)
_position_step = _jit(K.position_step_scalar)
_orientation_reward = _jit(K.orientation_reward)
_position_reward = _jit(K.position_reward)


@_jit
def _reset_env(i, si, sf, steps, obs_table, dim, cur_lo, out_obs):  # type: ignore[no-untyped-def]
    """Start sub-environment ``i`` on the next trajectory of its pool; its first observation."""
    idx = si[i, POOL + si[i, PTR]]
    si[i, PTR] += 1
    start = steps[idx, steps.shape[1] - 1]
    si[i, IDX] = idx
    si[i, K_] = 0
    si[i, ELAPSED] = 0
    si[i, AUTORESET] = 0
    for j in range(dim):
        sf[i, j] = start[j]
    sf[i, dim] = 0.0
    sf[i, dim + 1] = 0.0
    _copy_row(obs_table[idx, 0], out_obs[i])
    _write_current(i, sf, start, dim, cur_lo, out_obs)


@_jit
def _copy_row(src, dst):  # type: ignore[no-untyped-def]
    for j in range(src.shape[0]):
        dst[j] = src[j]


@_jit
def _write_current(i, sf, extra, dim, cur_lo, out_obs):  # type: ignore[no-untyped-def]
    """The current state into the observation, clipped to its bounds (in ``extra``)."""
    for j in range(dim):
        v = sf[i, j]
        lo = extra[dim + j]
        hi = extra[2 * dim + j]
        v = lo if v < lo else v
        out_obs[i, cur_lo + j] = hi if v > hi else v


@_jit
def batch_step(  # type: ignore[no-untyped-def]  # numba infers the signature at compile time
    kind,
    mode,
    max_steps,
    cur_lo,
    steps,
    obs_table,
    si,
    sf,
    final_obs,
    actions,
    out_obs,
    out_f,
    out_b,
):
    """One step of every sub-environment; see the module docstring for the arrays.

    Returns ``(status, a, n_reset, n_exhausted)``: ``status`` 0 and ``a`` the number of
    terminated sub-environments; or, with nothing changed, ``status`` 1 (a non-finite
    action, ``a`` its sub-environment) or 2 (``DISABLED`` mode and sub-environment ``a``
    ended without a reset). ``n_exhausted`` counts the pools to refill.
    """
    N, d = actions.shape
    n_steps = steps.shape[1] - 1
    dim = sf.shape[1] - 2
    extra = steps[0, n_steps]
    scale = extra[3 * dim]
    w = extra[3 * dim + 1 :]
    for i in range(N):
        if mode == DISABLED and si[i, AUTORESET] != 0:
            return 2, i, 0, 0
        for j in range(d):
            if not math.isfinite(actions[i, j]):
                return 1, i, 0, 0
    a = np.empty(d)
    q = np.empty(d)
    n_term = 0
    n_reset = 0
    n_exhausted = 0
    n_pool = si.shape[1] - POOL
    for i in range(N):
        if mode == NEXT_STEP and si[i, AUTORESET] != 0:
            _reset_env(i, si, sf, steps, obs_table, dim, cur_lo, out_obs)
            out_f[0, i] = 0.0
            out_b[0, i] = False
            out_b[1, i] = False
            out_b[2, i] = False
            out_b[3, i] = True
            n_reset += 1
            if si[i, PTR] >= n_pool:
                n_exhausted += 1
            continue
        for j in range(d):
            v = actions[i, j]
            a[j] = -1.0 if v < -1.0 else (1.0 if v > 1.0 else v)
        idx = si[i, IDX]
        kk = si[i, K_]
        row = steps[idx, kk]
        if kind == ORIENTATION:
            qo, err, geo = _orientation_step(row, a[0], a[1], a[2], scale)
            r_res, r_geo, r_act, reward = _orientation_reward(
                err, geo, a[0], a[1], a[2], w[0], w[1], w[2]
            )
            sf[i, 0] = qo[0]
            sf[i, 1] = qo[1]
            sf[i, 2] = qo[2]
            sf[i, 3] = qo[3]
            if geo > sf[i, dim + 1]:
                sf[i, dim + 1] = geo
            out_f[1, i] = err
            out_f[2, i] = geo
            out_f[3, i] = r_res
            out_f[4, i] = r_geo
            out_f[5, i] = r_act
            tau_row = 6
        else:
            err = _position_step(row, a, scale, q)
            sq = 0.0
            for j in range(d):
                sq = sq + a[j] * a[j]
            r_dist, r_act, reward = _position_reward(err, sq, w[0], w[1])
            for j in range(d):
                sf[i, j] = q[j]
            out_f[1, i] = err
            out_f[2, i] = r_dist
            out_f[3, i] = r_act
            tau_row = 4
        out_f[0, i] = reward
        out_f[tau_row, i] = kk / (n_steps - 1)
        if err > sf[i, dim]:
            sf[i, dim] = err
        kk += 1
        si[i, K_] = kk
        si[i, ELAPSED] += 1
        terminated = kk == n_steps
        truncated = si[i, ELAPSED] >= max_steps
        out_b[0, i] = terminated
        out_b[1, i] = truncated
        if terminated:
            n_term += 1
            out_f[tau_row + 1, i] = sf[i, dim]
            out_f[tau_row + 2, i] = sf[i, dim + 1]
        _copy_row(obs_table[idx, kk], out_obs[i])
        _write_current(i, sf, extra, dim, cur_lo, out_obs)
        ended = terminated or truncated
        if mode == SAME_STEP and ended:
            _copy_row(out_obs[i], final_obs[i])
            _reset_env(i, si, sf, steps, obs_table, dim, cur_lo, out_obs)
            out_b[2, i] = False
            out_b[3, i] = True
            n_reset += 1
            if si[i, PTR] >= n_pool:
                n_exhausted += 1
        else:
            out_b[2, i] = True
            out_b[3, i] = False
            si[i, AUTORESET] = 1 if ended else 0
    return 0, n_term, n_reset, n_exhausted
