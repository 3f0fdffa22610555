"""One hand of the analytic cascade juggler (:class:`CascadeHand`): the one-ball
juggler's episode controller in the hand's own frame, scheduled by the pattern (see
:mod:`~motion_envs.models.juggling._cascade_control`), with the controller's tunables
(:class:`CascadeTunables`: frozen fields, no module globals)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES, JugglingState, ballistic_position
from motion_envs.models.juggling._cascade import CascadePattern
from motion_envs.models.juggling._controller import ControlOptions, JugglingController
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._model import plan_catch

__all__ = ["DEFAULT_TUNABLES", "CascadeHand", "CascadeTunables"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CascadeTunables:
    """The cascade controller's tunables (a variant is ``dataclasses.replace``).

    The first three were chosen on TRAINING seeds only (Cascade-v0's zero-action juggler
    episodes, seeds ``SPLIT_SEEDS["train"] + i``, levels easy and medium; objective: mean
    catches before the first drop summed over the levels) by
    ``experiments/cascade_constants.py``, one at a time; a value replaces the current one
    only if it beats it by two paired standard errors. First with 40 episodes, at most 10
    catches, over {0.3, 0.5, 0.7}, {0.6, 0.75, 0.9} and {0.2, 0.3, 0.4}; re-chosen after
    the next-beat fix with 80 episodes, at most 100 catches, over {0.3, 0.5, 0.7, 1.0},
    {0.6, 0.75, 0.9} and {0.1, 0.2, 0.3, 0.5}: no other value beat these, so they were
    kept.

    Attributes
    ----------
    catch_window:
        Beats: a hand's catch reach may last from the shortest training catch to the
        longest plus this share of a beat (the flights scatter more than one hand's catch
        reach did in the demonstrations; a late ball is waited for).
    release_armed:
        Share of the nominal toss's release time after which a toss's release is armed
        (0.6-0.9 play identically).
    reaim_after:
        Beats after the end of its catch plan at which an empty hand re-plans its catch.
    toss_clearance:
        m: the horizontal distance a falling ball's centre must keep from a tossing hand's
        column (:meth:`CascadeHand.toss_shift`): the palm's half width (4.5 cm) plus the
        ball's radius (3.5 cm) plus 2 cm. Hand-set from the geometry, then checked on
        training seeds.
    """

    catch_window: float = 0.5
    release_armed: float = 0.75
    reaim_after: float = 0.3
    toss_clearance: float = 0.1

    def __post_init__(self) -> None:
        for name in ("catch_window", "release_armed", "reaim_after", "toss_clearance"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"CascadeTunables.{name} must be finite and >= 0; got {value!r}")
        if self.release_armed > 1:
            armed = self.release_armed
            raise ValueError(f"CascadeTunables.release_armed must be <= 1; got {armed}")


#: The tunables the cascade juggler plays with.
DEFAULT_TUNABLES = CascadeTunables()


class CascadeHand(JugglingController):
    """One hand of the cascade: the one-ball juggler's episode controller in the hand's
    own frame, its go-down and return timed by the pattern and its catch aimed at the
    oldest ball queued for it (module docstring).

    ``index``: 0 right, 1 left; ``beat``, ``lead``: s; ``first_release``: s, the time of the
    hand's first beat; ``tunables``: the controller's (:class:`CascadeTunables`).
    ``own_ball``: the ball the hand released last (-1 before its first
    release); ``own_flight``: that ball's measured ``(position, velocity)`` in the own
    frame while it flies, else None (set by :class:`CascadeController` each step).
    """

    outgoing: tuple[float, FloatArray, FloatArray] | None
    last_release: float | None

    def __init__(
        self,
        model: AnalyticJuggler,
        options: ControlOptions,
        pattern: CascadePattern,
        index: int,
        beat: float,
        first_release: float,
        tunables: CascadeTunables = DEFAULT_TUNABLES,
    ) -> None:
        super().__init__(model.model, options)
        self.tunables = tunables
        self.pattern = pattern
        self.index = index
        self.beat = float(beat)
        self.first_release = float(first_release)

    # -- the toss out of the way of the hand's own last ball ------------------------
    def _draw_end(self, phase: str) -> FloatArray:
        """The one-ball juggler's draw; the return's and the toss's end moved sideways
        by :meth:`toss_shift` (the draw itself unchanged, so the generator's stream is
        too). The toss keeps the side its return moved to: a hand already beside the
        ball does not cross under it."""
        end = super()._draw_end(phase)
        if phase == "return":
            self._shift = self.toss_shift()
            end[0] += self._shift
        elif phase == "toss":
            end[0] += self.toss_shift(int(np.sign(self._shift)))
        return end

    def toss_shift(self, side: int = 0) -> float:
        """m along the own ``x``: how far the coming toss moves aside so that the hand's
        own last ball (``own_flight``, its measured flight) does not fall onto the
        tossing palm; 0 when it passes clear.

        The toss's column is the ``x`` span from home to the nominal release; its band the
        heights from home to the nominal release, each widened by the tunables'
        ``toss_clearance``. If the ball's predicted centre, falling through the band,
        comes within ``toss_clearance`` of the column, the column moves away from the
        ball until it clears it: to ``side`` (+1 out, -1 in) if given, else to the side
        opposite the ball's mean ``x`` there."""
        if self.own_flight is None:
            return 0.0
        p, v = self.own_flight
        clearance = self.tunables.toss_clearance
        home, release = self.model.home_, self.pattern.release_position
        lo, hi = float(min(home[0], release[0])), float(max(home[0], release[0]))
        bottom = float(min(home[1], release[1])) - clearance
        top = float(max(home[1], release[1])) + clearance
        g = self.task.gravity
        ts = np.linspace(0.0, 2.0 * self.pattern.flight, 401)
        pts = ballistic_position(p, v, ts, g)
        band = (v[1] - g * ts < 0.0) & (pts[:, 1] >= bottom) & (pts[:, 1] <= top)
        if not band.any():
            return 0.0
        xa, xb = float(pts[band, 0].min()), float(pts[band, 0].max())
        if xb <= lo - clearance or xa >= hi + clearance:
            return 0.0
        if side == 0:  # the ball falls on the outer side: toss further in, and vice versa
            side = -1 if xa + xb >= lo + hi else 1
        if side < 0:
            return min((xa - clearance) - hi, 0.0)
        return max((xb + clearance) - lo, 0.0)

    # -- timing by the pattern ------------------------------------------------------
    def _draw_duration(self, phase: str) -> float:
        lo, hi = self.model.phases_[phase].duration_range
        t = self._t_phase
        if phase == "return":
            return float(max(self.next_release() - self.pattern.lead - t, lo))
        if phase == "go_down" and self.incoming:
            p, v, t_r = self._incoming_belief()
            end = self.model.phases_["catch"].end_mean
            ts = np.linspace(0.0, 2.0 * self.pattern.flight, 201)
            pts = ballistic_position(p, v, ts, self.task.gravity)
            t_arrive = t_r + float(ts[int(np.argmin(np.linalg.norm(pts - end, axis=1)))])
            return float(min(max(t_arrive - self.pattern.catch_duration - t, lo), hi))
        return super()._draw_duration(phase)

    def next_release(self) -> float:
        """s, when this hand should release next: the mean of its own beat (its last
        release plus two beats) and the other hand's (the other hand's last release plus
        the odd number of beats nearest to this hand's own beat); the first beat before
        any release."""
        own, other = self.last_release, self.other_release
        if own is None:
            return self.first_release
        mine = own + 2.0 * self.beat
        if other is None:
            return mine
        m = round((mine - other - self.beat) / (2.0 * self.beat))
        theirs = other + self.beat + 2.0 * self.beat * m
        return 0.5 * (mine + theirs)

    def _incoming_belief(self) -> tuple[FloatArray, FloatArray, float]:
        _, t_r, p, v = self.incoming[0]
        return p, v, t_r

    def start_phase(self, phase: str, t: float, start: FloatArray) -> None:
        """As the one-ball juggler's, the catch on the oldest queued ball (if any), its
        duration chosen in the catch window (the tunables' ``catch_window``)."""
        self._t_phase = t
        if phase == "catch" and self.incoming:
            p, v, t_r = self._incoming_belief()
            self.release_belief = (t_r, p, v)
            self._catch_ball = self.incoming[0][0]
        if phase == "toss":
            self.tosses += 1
        if phase != "catch":
            super().start_phase(phase, t, start)
            return
        fit = self.model.phases_["catch"]
        lo, hi = fit.duration_range
        window = (lo, hi + self.tunables.catch_window * self.beat)
        duration, end = plan_catch(start, *self.belief_at(t), self.task.gravity, window,
                                   fit.end_mean)  # fmt: skip
        p_plan = fit.model.plan(np.concatenate([start, end]), duration, start, end)
        self.phase = phase
        self.t_start = t
        self.duration = duration
        self.coefficients = p_plan
        self.end = p_plan[0] + p_plan[1]
        self._grid_from(0)
        self.end_k = -1
        self.plans.append((phase, t, duration, p_plan.copy()))
        self.k = 0

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """The one-ball juggler's command; an empty hand in the catch phase re-plans its
        catch on the ball now first in its queue when that is another ball than the one
        planned on (the planned one went elsewhere) or when the plan ended more than
        the tunables' ``reaim_after`` beats ago without a catch. A hand that holds a ball in its
        go-down or catch (a ball that came early) ends its catch there: the return starts."""
        if self.phase in ("go_down", "catch") and state.held:
            self.phase = "catch"
            return super().command(replace(state, caught=True))
        if (
            self.phase == "catch"
            and self.incoming
            and not state.held
            and not state.caught
            and (
                self.incoming[0][0] != self._catch_ball
                or self.k * self.task.dt > self.duration + self.tunables.reaim_after * self.beat
            )
        ):
            self.start_phase("catch", state.time, np.asarray(state.hand_pos, dtype=np.float64))
        return super().command(state)

    def next_phase(
        self, time: float, hand: FloatArray, last_commands: tuple[FloatArray, FloatArray]
    ) -> None:
        """End the phase; at the end of a toss record the efference copy of the release
        (``outgoing``, own frame) instead of believing in the own ball."""
        if self.phase == "toss":
            v = (last_commands[1] - last_commands[0]) / self.task.dt
            self.outgoing = (time, last_commands[1].copy(), v)
            self.last_release = time
        nxt = PHASES[(PHASES.index(self.phase) + 1) % len(PHASES)]
        self.start_phase(nxt, time, hand)

    def reset_hand(
        self,
        state: JugglingState,
        rng: np.random.Generator,
        incoming: list[tuple[int, float, FloatArray, FloatArray]],
    ) -> None:
        """Start the episode: the toss at once (``first_release <= lead``) or a wait at
        the hand's position until ``lead`` before the first beat (a return phase)."""
        self.incoming = incoming
        self.outgoing = None
        self.last_release = None
        self.other_release: float | None = None
        self._catch_ball = -1
        self.own_ball = -1
        self.own_flight: tuple[FloatArray, FloatArray] | None = None
        self._shift = 0.0
        self.tosses = 0
        self._t_phase = state.time
        self._rng = rng
        self.plans = []
        self.corrections = []
        here = np.asarray(state.hand_pos, dtype=np.float64)
        self._last = [here, here]
        self.release_belief = (0.0, here, np.zeros(2))
        wait = self.first_release - self.pattern.lead - state.time
        if wait <= self.task.dt:
            self.start_phase("toss", state.time, here.copy())
            return
        # wait at rest (a constant plan of the return phase)
        self.phase = "return"
        self.t_start = state.time
        self.duration = wait
        self.coefficients = np.zeros((2, 2))
        self.coefficients[0] = here
        self.end = here.copy()
        n = math.ceil(wait / self.task.dt - 1e-9)
        self.grid = np.tile(here, (n + 1, 1))
        self.end_k = n
        self.plans.append(("return", state.time, wait, self.coefficients.copy()))
        self.k = 0
