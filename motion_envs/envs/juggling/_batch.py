"""The state of ``N`` juggling worlds as one batch, and their control periods.

:class:`WorldBatch` holds the :class:`~motion_envs.envs.juggling._world.HandsWorld` state
of the worlds of ``parts`` (single environments, each with its ``world``) as arrays with
one row per world, and steps them with
:func:`~motion_envs.envs.juggling._period.world_periods` (compiled by numba,
``backend="numba"``, or plain Python: bit-identical). A single environment is the batch
of one: its rows ARE its world's arrays (``HandsWorld`` keeps its state as a batch of
one), so nothing is copied; a native vector environment's batch copies each world's rows
in at its reset (:meth:`WorldBatch.load_world`).

Threads (``threads=``, numba backend): the worlds' control periods (MuJoCo's ``mj_step``
and the servo, the bulk of a step) run in up to ``threads`` threads, each on its own
contiguous block of worlds; the compiled periods release the GIL (as MuJoCo's own
bindings do around ``mj_step``). Each world is stepped by exactly the code that steps it
in one thread (its own model and data, nothing shared), so the result does not depend on
the number of threads (tested bit for bit).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES
from motion_envs.envs.juggling import _period

__all__ = ["MIN_ENVS_PER_THREAD", "WORLD_ROWS", "WorldBatch"]

#: Fewest worlds a thread is given (below, handing work to a thread costs more than it
#: saves).
MIN_ENVS_PER_THREAD = 8
#: The world state's arrays (``HandsWorld``'s names) a batch holds, one row per world.
WORLD_ROWS = ("ref", "vref", "z_before", "holder", "thrower", "left", "dropped", "k")
_EVENTS = ("caught", "released", "_target", "_armed")


#: Rows of noise an episode draws ahead at a time (sensor and release scatter).
NOISE_BLOCK = 64


class WorldBatch:
    """The worlds of ``parts`` (each with a ``world``) as one batch (see the module
    docstring); a subclass adds its task's step. ``backend``: ``"numba"`` or
    ``"python"``; ``threads``: threads stepping the periods (numba backend)."""

    #: Attributes made from the worlds by :meth:`link` (not pickled: made again).
    LINKED: tuple[str, ...] = ("_compiled", "_datas", "_worlds", "_entries", "_periods")

    def __init__(self, parts: Sequence[Any], backend: str, threads: int = 1) -> None:
        self.parts = list(parts)
        self.n = len(self.parts)
        self.backend = backend
        self.threads = threads
        self._pool: ThreadPoolExecutor | None = None
        world = self.parts[0].world
        self._ball_geoms = world.ball_geoms.copy()
        self._constants = world.constants.copy()
        if self.n == 1:  # the batch of one: the world's own arrays
            for name in (*WORLD_ROWS, *_EVENTS):
                setattr(self, "_" + name.lstrip("_"), getattr(world, name))
        else:
            n, hands, balls = self.n, world.spec.hands, world.spec.balls
            self._ref = np.zeros((n, hands, 2))
            self._vref = np.zeros((n, hands, 2))
            self._z_before = np.zeros((n, hands))
            self._holder = np.full((n, balls), -1, dtype=np.int64)
            self._thrower = np.full((n, balls), -1, dtype=np.int64)
            self._left = np.zeros((n, balls), dtype=np.bool_)
            self._dropped = np.zeros((n, balls), dtype=np.bool_)
            self._k = np.zeros(n, dtype=np.int64)
            self._caught = np.full((n, hands), -1, dtype=np.int64)
            self._released = np.full((n, hands), -1, dtype=np.int64)
            self._target = np.zeros((n, hands, 2))
            self._armed = np.zeros((n, hands), dtype=np.bool_)
        self._linked = False

    # -- the links to the worlds (made again after unpickling) ------------------------------
    def link(self) -> None:
        """What the periods read and write in place: each world's ``MjModel``/``MjData``
        address and array views (:data:`LINKED`)."""
        worlds = [p.world for p in self.parts]
        self._datas = [w.data for w in worlds]
        self._entries: dict[str, Callable[..., Any]] = {}
        if self.backend == "numba":
            from motion_envs.envs.juggling import _compiled

            self._compiled: Any = _compiled
            if self.n == 1 and worlds[0].backend == "numba":
                self._worlds: tuple[Any, ...] = worlds[0]._links  # (1, n) views
            else:
                self._worlds = _compiled.world_links(worlds)
            self._periods: Callable[..., None] = _compiled.world_periods
        else:
            self._compiled = None
            ms, ds = [w.model for w in worlds], [w.data for w in worlds]
            self._worlds = (
                [m._address for m in ms], [d._address for d in ds],
                [d.qpos for d in ds], [d.qvel for d in ds], [d.ctrl for d in ds],
                [d.sensordata for d in ds], [m.geom_contype for m in ms],
                [m.geom_conaffinity for m in ms],
            )  # fmt: skip
            self._periods = _period.world_periods
        self._linked = True

    def setup_draws(self, first: Any) -> None:
        """The noise the episodes draw ahead, in blocks of :data:`NOISE_BLOCK` rows per
        episode: the sensor's (``first``'s position and velocity std), the release
        scatter's (its world's speed and angle std), and the catch and toss counts."""
        n = self.n
        self._noisy = first.position_std > 0 or first.velocity_std > 0
        self._noise_std = np.array([first.position_std] * 2 + [first.velocity_std] * 2)
        self._noise = np.zeros((n, NOISE_BLOCK, 4))
        self._noise_at = np.full(n, NOISE_BLOCK, dtype=np.int64)  # next unused row
        world = first.world
        self._rel_std = np.array([world.release_speed_std, world.release_angle_std])
        self._scatter = bool(self._rel_std.any())
        self._rel_noise = np.zeros((n, NOISE_BLOCK, 2))
        self._rel_at = np.full(n, NOISE_BLOCK, dtype=np.int64)
        self._counts = np.zeros((n, 2), dtype=np.int64)  # catches, tosses

    def link_steps(self, compiled: str, plain: Any) -> None:
        """The step kernels and the likeness's k-d trees, for the backend: the module
        ``compiled`` (its dotted name; numba) or ``plain`` (the same functions as plain
        Python), the first part's likeness as compiled trees or as it is, and the trees'
        search stack."""
        likeness = self.parts[0].likeness
        if self.backend == "numba":
            from motion_envs.envs.juggling._compiled_likeness import likeness_forest

            self._kernels: Any = importlib.import_module(compiled)
            trees = [self._compiled.likeness_tree(likeness.trees[p].data) for p in PHASES]
            self._trees: Any = likeness_forest(trees)
        else:
            self._kernels = plain
            self._trees = likeness
        self._stack = np.empty(256, dtype=np.int64)

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in self.LINKED:
            state.pop(key, None)
        state["_pool"] = None  # threads are not pickled: made again when needed
        state["_linked"] = False  # linked at the next use (the parts may still be loading)
        return state

    def close(self) -> None:
        """Stop the threads (made again when needed)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    # -- the worlds' state ----------------------------------------------------------------
    def load_world(self, i: int) -> None:
        """Copy world ``i``'s state (after its reset) into the batch (nothing to copy in
        the batch of one: its rows are the world's)."""
        if self.n == 1:
            return
        w = self.parts[i].world
        for name in WORLD_ROWS:
            getattr(self, "_" + name)[i] = getattr(w, name)[0]

    def world_periods(
        self,
        envs: NDArray[np.int64],
        target: NDArray[np.float64] | None = None,
        armed: NDArray[np.bool_] | None = None,
    ) -> None:
        """One control period of the worlds ``envs`` toward ``target (m, H, 2)`` with
        ``armed (m, H)`` (None: as already in ``_target`` and ``_armed``), in threads;
        what each hand caught and released is in ``_caught`` and ``_released``."""
        if target is not None:
            self._target[envs], self._armed[envs] = target, armed
        self.in_threads(self._periods, envs, *self.period_args())

    def period_args(self) -> tuple[Any, ...]:
        """:func:`~motion_envs.envs.juggling._period.world_periods`' arguments after
        ``envs``: the worlds' links and the batch's state arrays."""
        return (
            self._worlds, self._ball_geoms, self._target, self._armed, self._ref,
            self._vref, self._z_before, self._holder, self._thrower, self._left,
            self._dropped, self._k, self._constants, self._caught, self._released,
        )  # fmt: skip

    def qv(self, envs: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The worlds' ``qpos`` and ``qvel`` rows for ``envs``, ``(m, nq)`` each."""
        datas = [self._datas[i] for i in envs.tolist()]
        return np.array([d.qpos for d in datas]), np.array([d.qvel for d in datas])

    def in_threads(self, periods: Callable[..., None], envs: NDArray[np.int64], *args: Any) -> None:
        """``periods(envs, *args)`` (a kernel that releases the GIL and touches only its
        worlds' rows), ``envs`` split into contiguous blocks run in up to ``threads``
        threads, the caller's thread among them."""
        periods = self.entry(periods, envs, *args)
        blocks = self.blocks(envs.size)
        if blocks <= 1:
            periods(envs, *args)
            return
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.threads - 1, thread_name_prefix="juggling")
        first, *rest = np.array_split(envs, blocks)
        futures = [self._pool.submit(periods, block, *args) for block in rest]
        periods(first, *args)
        for future in futures:
            future.result()

    def blocks(self, n: int) -> int:
        """In how many threads' blocks :meth:`in_threads` runs ``n`` worlds (1 or less:
        in the caller's thread alone)."""
        return min(self.threads, n // MIN_ENVS_PER_THREAD)

    def entry(self, kernel: Any, *args: Any) -> Callable[..., Any]:
        """The compiled ``kernel``'s entry point for ``args`` (numba backend:
        :func:`~motion_envs.envs.juggling._compiled.entry_point`, found once per kernel),
        or ``kernel`` itself (plain Python)."""
        if self._compiled is None:
            return kernel  # type: ignore[no-any-return]
        name = kernel.py_func.__name__
        found = self._entries.get(name)
        if found is None:
            found = self._entries[name] = self._compiled.entry_point(kernel, *args)
        return found
