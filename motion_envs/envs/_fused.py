"""The native vector environments' step as one compiled loop (numba backend).

:func:`batch_step_of` compiles, for a :class:`~motion_envs.envs._reach.ReachKind`, the
one loop that advances every sub-environment by one step in a single call: action check
and clipping, the kind's :attr:`~motion_envs.envs._reach.ReachKind.fused_physics` (the
kind's kernel and reward, compiled unchanged), the running maxima of its end keys, the
episode counters, the next observation, and the autoreset of Gymnasium's three
:class:`~gymnasium.vector.AutoresetMode` s. Same expressions in the same order as the
single environments and the numpy path of :mod:`motion_envs.envs._reach_vector`,
correctly rounded ``+ - * / sqrt`` and libm's ``sin``/``cos`` (as ``math``), no
fast-math, so the results are bit-identical (tested).

The loop is written once (:func:`_batch_step`, plain Python); each kind gets its own
compiled copy, with the kind's physics and info layout bound as compile-time globals
(numba inlines them; a function passed as an argument would be neither inlined nor
cached). Each copy is cached on disk under a name holding the kind's name and a digest
of the code of its physics and of the kernels it calls, so editing them compiles it
again (numba itself checks only the timestamp of this file).

State layout (shared with the numpy path of :mod:`motion_envs.envs._reach_vector`):

* ``steps[l, k]`` (float64): the step row of trajectory ``l`` at grid point ``k`` (the
  task's ``steps``), and one extra row ``k = n`` holding the trajectory's start state
  (``dim`` values), the lower and upper bounds of the current state in the observation
  (``dim`` each; infinite when not clipped), ``residual_scale`` and the reward weights;
* ``si[i]`` (int64): trajectory index, grid point ``k``, elapsed steps, autoreset flag,
  position in the trajectory pool, then the pool (the next trajectory indices);
* ``sf[i]`` (float64): current state (``dim`` values), then the running maximum of each
  of the kind's end keys;
* ``out_f`` rows: reward, the kind's step keys, tau, the kind's end keys;
* ``out_b`` rows: terminated, truncated, mask of the step infos, mask of the
  sub-environments reset in this step.

Importing this module imports numba (the ``fast`` extra); the first call of a kind's
loop compiles it (38 s measured on a shared 2-core machine under load average 15), then
it is cached on disk (3 s to load there).
"""

from __future__ import annotations

import hashlib
import math
import types
from typing import Any

import numpy as np
from numba import njit

__all__ = ["DISABLED", "NEXT_STEP", "SAME_STEP", "batch_step_of"]

# autoreset modes (integers for the compiled code)
NEXT_STEP, SAME_STEP, DISABLED = 0, 1, 2
# si columns
IDX, K_, ELAPSED, AUTORESET, PTR, POOL = 0, 1, 2, 3, 4, 5

# error_model="numpy": no zero-division checks (no divisor can be 0; the kernels guard
# their small-angle cases); never fastmath, which would reorder the arithmetic
_jit = njit(cache=True, error_model="numpy")

# bound per kind in its compiled copy of _batch_step (see batch_step_of)
_physics: Any = None
_N_INFO = 0  # number of the kind's step keys
_MAX_SRC: tuple[int, ...] = ()  # per end key: the index of its step key


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
    for j in range(dim, sf.shape[1]):
        sf[i, j] = 0.0  # the running maxima
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


def _batch_step(  # type: ignore[no-untyped-def]  # numba infers the signature at compile time
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
    n_end = len(_MAX_SRC)
    dim = sf.shape[1] - n_end
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
    q = np.empty(dim)
    tau_row = _N_INFO + 1
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
        reward, vals = _physics(row, a, scale, w, q)
        for j in range(dim):
            sf[i, j] = q[j]
        out_f[0, i] = reward
        for j in range(_N_INFO):
            out_f[1 + j, i] = vals[j]
        out_f[tau_row, i] = kk / (n_steps - 1)
        for j in range(n_end):
            v = vals[_MAX_SRC[j]]
            if v > sf[i, dim + j]:
                sf[i, dim + j] = v
        kk += 1
        si[i, K_] = kk
        si[i, ELAPSED] += 1
        terminated = kk == n_steps
        truncated = si[i, ELAPSED] >= max_steps
        out_b[0, i] = terminated
        out_b[1, i] = truncated
        if terminated:
            n_term += 1
            for j in range(n_end):
                out_f[tau_row + 1 + j, i] = sf[i, dim + j]
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


_COMPILED: dict[str, Any] = {}


def _jit_calling(fn: Any, name: str, bound: dict[str, Any], inline: bool = False) -> Any:
    """``fn`` compiled with ``bound`` (and the compiled copy of every Python function it
    calls by global name) as its globals, under the cache name ``name``; with
    ``inline``, ``fn`` and every function it calls are inlined into their callers by
    numba (LLVM's heuristics leave a kind's physics a call, whose array arguments then
    cost reference counts: twice the time of a position step, measured)."""
    env = dict(fn.__globals__)
    env.update(bound)
    for global_name in fn.__code__.co_names:
        value = env.get(global_name)
        if global_name not in bound and isinstance(value, types.FunctionType):
            suffix = "_inline" if inline else ""
            env[global_name] = _jit_calling(value, value.__qualname__ + suffix, {}, inline)
    copy = types.FunctionType(fn.__code__, env, name, fn.__defaults__)
    copy.__qualname__ = name  # numba's cache file name
    copy.__module__ = fn.__module__
    copy.__doc__ = fn.__doc__
    if inline:
        return njit(cache=True, error_model="numpy", inline="always")(copy)
    return _jit(copy)


def _code_digest(fn: Any, h: Any) -> Any:
    """``h`` updated with the code of ``fn`` and of every Python function it calls by
    global name (what :func:`_jit_calling` compiles into the loop)."""
    code = fn.__code__
    h.update(code.co_code + repr(code.co_consts).encode())
    for global_name in code.co_names:
        value = fn.__globals__.get(global_name)
        if isinstance(value, types.FunctionType) and value is not fn:
            _code_digest(value, h)
    return h


def batch_step_of(kind: Any) -> Any:
    """The compiled one-step loop of ``kind`` (a ``ReachKind``): :func:`_batch_step` with
    the kind's ``fused_physics`` and info layout bound; compiled once per process, cached
    on disk (see the module docstring)."""
    physics = kind.fused_physics
    digest = _code_digest(physics, hashlib.sha256()).hexdigest()[:12]
    name = f"batch_step_{kind.name}_{digest}"
    if name not in _COMPILED:
        bound = {
            "_physics": _jit_calling(physics, f"{kind.name}_physics_{digest}", {}, inline=True),
            "_N_INFO": len(kind.step_keys),
            "_MAX_SRC": tuple(kind.step_keys.index(src) for _, src in kind.end_keys),
        }
        _COMPILED[name] = _jit_calling(_batch_step, name, bound)
    return _COMPILED[name]
