"""Siteswaps: notation, validity and ball count against an independent count of landings
on the time line, each throw's flight against Shannon's theorem, and which patterns the
cascade juggler can play (``motion-bench juggling --pattern``)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion_envs.datasets.juggling import (
    ballistic_position,
    cascade_timing,
    format_siteswap,
    parse_siteswap,
    siteswap_balls,
    siteswap_flights,
)
from motion_envs.envs.juggling import HAND_SPEED_LIMIT
from motion_envs.models.juggling import cascade_fit, check_pattern


def _landings(throws: tuple[int, ...], beats: int) -> tuple[list[int], list[int]]:
    """Independent of the permutation test: repeat ``throws`` on the time line from beat
    0 and, for each beat ``j`` from ``max(throws)`` on (the steady state), count the
    throws ``i <= j`` that come down on ``j`` (``i + t_i = j``) and the balls in the air
    just after ``j`` (``i <= j < i + t_i``)."""
    p, top = len(throws), max(throws)
    t = [throws[i % p] for i in range(beats)]
    arrive = [sum(1 for i in range(j + 1) if i + t[i] == j) for j in range(top, beats - top)]
    air = [sum(1 for i in range(j + 1) if i + t[i] > j) for j in range(top, beats - top)]
    return arrive, air


@pytest.mark.parametrize(
    ("text", "throws", "balls"),
    [
        ("3", (3,), 3),
        ("441", (4, 4, 1), 3),
        ("531", (5, 3, 1), 3),
        ("51", (5, 1), 3),
        ("423", (4, 2, 3), 3),
        ("5", (5,), 5),
        ("4", (4,), 4),
        ("330", (3, 3, 0), 2),
        (" B97531 ", (11, 9, 7, 5, 3, 1), 6),
        ("a", (10,), 10),
    ],
)
def test_known_siteswaps(text, throws, balls):
    assert parse_siteswap(text) == throws
    assert format_siteswap(throws) == text.strip().lower()
    assert siteswap_balls(throws) == balls
    arrive, air = _landings(throws, 12 * len(throws) + 4 * max(throws))
    assert set(arrive) == {1} and set(air) == {balls}


@pytest.mark.parametrize("text", ["45", "432", "543", "321", "0", "00"])
def test_invalid_siteswaps_are_refused(text):
    throws = parse_siteswap(text)
    with pytest.raises(ValueError, match=r"not valid|no ball"):
        siteswap_balls(throws)
    if max(throws) > 0:  # the time line agrees: some beat gets two balls or none
        arrive, _ = _landings(throws, 12 * len(throws) + 4 * max(throws))
        assert set(arrive) != {1}


@pytest.mark.parametrize(
    ("bad", "match"),
    [("", "empty"), ("4-1", r"character 2 \('-'\)"), ("3 3", "character 2"), (3, "string")],
)
def test_parse_siteswap_errors_name_the_character(bad, match):
    with pytest.raises(ValueError, match=match):
        parse_siteswap(bad)


def test_negative_throws_are_refused():
    with pytest.raises(ValueError, match=">= 0"):
        siteswap_balls((3, -1))
    with pytest.raises(ValueError, match="at least one"):
        siteswap_balls(())


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_every_permutation_construction_is_valid_with_the_average_balls(data):
    """A siteswap is valid iff its landing beats permute the beats: building ``t_i =
    (pi(i) - i) mod p + p k_i`` from any permutation ``pi`` gives every valid one; the
    time line sees one landing per beat and the average throw in the air."""
    p = data.draw(st.integers(1, 6))
    perm = data.draw(st.permutations(range(p)))
    extra = data.draw(st.lists(st.integers(0, 2), min_size=p, max_size=p))
    throws = tuple((perm[i] - i) % p + p * extra[i] for i in range(p))
    if sum(throws) == 0:
        return
    balls = siteswap_balls(throws)
    assert balls * p == sum(throws)
    arrive, air = _landings(throws, 8 * p + 4 * max(throws))
    assert set(arrive) == {1} and set(air) == {balls}


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(0, 9), min_size=1, max_size=5))
def test_validity_agrees_with_the_time_line(throws):
    t = tuple(throws)
    arrive, _ = _landings(t, 8 * len(t) + 4 * max(t)) if max(t) > 0 else ([0], [0])
    ok = set(arrive) == {1}
    if ok:
        assert siteswap_balls(t) == sum(t) // len(t)
    else:
        with pytest.raises(ValueError):
            siteswap_balls(t)


@settings(max_examples=100, deadline=None)
@given(st.floats(0.2, 2.0), st.floats(0.05, 0.95))
def test_cascade_flight_is_shannons_theorem(flight, ratio):
    """``F_3 = 3 b - D`` at the cascade's beat and dwell is the flight Shannon's theorem
    started from; ``F_h`` grows by one beat per unit of throw."""
    t = cascade_timing(flight, ratio)
    f = siteswap_flights((3, 5, 0, 1), t.beat, t.dwell)
    assert f[0] == pytest.approx(flight, rel=1e-12)
    assert f[1] - f[0] == pytest.approx(2 * t.beat, rel=1e-12)
    assert f[2] == 0.0
    assert f[3] == pytest.approx(t.beat - t.dwell, rel=1e-12)


@pytest.mark.parametrize(("beat", "dwell"), [(0.0, 0.1), (math.nan, 0.1), (0.3, -0.1)])
def test_flight_arguments(beat, dwell):
    with pytest.raises(ValueError, match=r"beat|dwell"):
        siteswap_flights((3,), beat, dwell)


# -- the cascade juggler's patterns ----------------------------------------------------------
G = 9.81


@pytest.fixture(scope="module")
def pattern():
    return cascade_fit(G).pattern


def test_the_cascade_fits_with_its_own_toss(pattern):
    c = check_pattern("3", pattern, G, HAND_SPEED_LIMIT)
    assert c.fits and c.reasons == () and c.balls == 3
    (n,) = c.throws
    period, beat = pattern.timing()
    assert (c.beat, c.dwell) == (beat, pattern.dwell_ratio * period)
    assert n.flight == pytest.approx(pattern.flight, rel=1e-12)
    assert n.release_speed == pytest.approx(pattern.release_velocity[1], rel=1e-12)
    assert n.crossing


def test_five_needs_a_release_above_the_hand_limit(pattern):
    c = check_pattern("5", pattern, G, HAND_SPEED_LIMIT)
    assert not c.fits
    assert any("5 balls" in r for r in c.reasons)
    assert any(f"{HAND_SPEED_LIMIT:g} m/s limit" in r for r in c.reasons)
    (n,) = c.throws
    assert n.release_speed > HAND_SPEED_LIMIT
    # oracle: the ball released from the cascade's release point at that vertical speed
    # is at the cascade's catch height after the throw's flight, and peaks at the apex
    p0, f3 = pattern.release_position, pattern.flight
    z_catch = ballistic_position(p0, pattern.release_velocity, f3, G)[1]
    v = np.array([0.0, n.release_speed])
    assert ballistic_position(p0, v, n.flight, G)[1] == pytest.approx(z_catch, abs=1e-9)
    t = np.linspace(0.0, n.flight, 20001)
    z = p0[1] + n.release_speed * t - 0.5 * G * t * t
    assert z.max() - p0[1] == pytest.approx(n.apex, abs=1e-6)
    # with no speed limit to speak of, only the ball count stays
    assert check_pattern("5", pattern, G, 100.0).reasons == ("it has 5 balls, the juggler's fit 3",)


def test_441_needs_a_dwell_shorter_than_a_beat(pattern):
    c = check_pattern("441", pattern, G, HAND_SPEED_LIMIT)
    assert not c.fits and c.balls == 3
    assert [n.value for n in c.throws] == [4, 1]
    assert c.throws[1].flight == pytest.approx(c.beat - c.dwell) and c.throws[1].flight <= 0
    assert any("a throw of 1 would fly" in r for r in c.reasons)
    assert any("not a cascade" in r for r in c.reasons)


@pytest.mark.parametrize("text", ["423", "4", "330"])
def test_patterns_that_are_not_a_cascade(pattern, text):
    c = check_pattern(text, pattern, G, HAND_SPEED_LIMIT)
    assert not c.fits and any("not a cascade" in r for r in c.reasons)


def test_check_pattern_arguments(pattern):
    with pytest.raises(ValueError, match="not valid"):
        check_pattern("45", pattern, G, HAND_SPEED_LIMIT)
    with pytest.raises(ValueError, match="gravity"):
        check_pattern("3", pattern, 0.0, HAND_SPEED_LIMIT)
    with pytest.raises(ValueError, match="speed_limit"):
        check_pattern("3", pattern, G, -1.0)


def test_pattern_cli_refuses_what_does_not_fit(tmp_path, capsys):
    from baselines.cli import build_parser, main

    assert build_parser().parse_args(["juggling", "--pattern", " 441"]).pattern == "441"
    with pytest.raises(SystemExit):
        build_parser().parse_args(["juggling", "--pattern", "45"])
    assert "land on the same beat" in capsys.readouterr().err
    for text, why in (
        ("7", "the world holds at most 5"),
        ("501", "empty beats"),
        ("3333", "not registered"),
    ):
        assert main(["juggling", "--pattern", text, "--out", str(tmp_path / text)]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and "argument --pattern" in err and why in err
        assert not (tmp_path / text).exists()


def test_pattern_results_carry_the_throws_needs(tmp_path):
    from baselines.cli import main

    argv = ["juggling", "--pattern", "3", "--levels", "easy", "--episodes", "2",
            "--max-catches", "1", "--out", str(tmp_path)]  # fmt: skip
    assert main(argv) == 0
    (throw,) = json.loads((tmp_path / "results.json").read_text())["pattern"]["throws"]
    assert throw["value"] == 3 and throw["crossing"] is True
    assert 0 < throw["release_speed"] < HAND_SPEED_LIMIT and throw["flight"] > 0


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=12))
def test_any_text_is_a_siteswap_or_a_value_error(text):
    """Whatever a user types after ``--pattern``: throws and a ball count, or a
    ``ValueError`` (never another exception)."""
    try:
        throws = parse_siteswap(text)
    except ValueError:
        return
    assert all(0 <= h < 36 for h in throws) and len(throws) == len(text.strip())
    try:
        balls = siteswap_balls(throws)
    except ValueError:
        return
    assert balls * len(throws) == sum(throws)


def test_a_short_flight_may_need_a_throw_down_beyond_the_limit(pattern):
    """With a dwell ratio near 1/2 a throw of 1 flies a few ms; falling from the release
    height to the catch height in that time needs a fast downward release, which the
    speed limit refuses too (the oracle: the ballistic closed form)."""
    from dataclasses import replace

    c = check_pattern("51", replace(pattern, dwell_ratio=0.48), G, HAND_SPEED_LIMIT)
    one = c.throws[-1]
    assert 0 < one.flight < 0.05 and one.release_speed < -HAND_SPEED_LIMIT and one.apex == 0
    assert any(f"a throw of 1 needs a {-one.release_speed:.2f} m/s" in r for r in c.reasons)
    p0, f3 = pattern.release_position, pattern.flight
    z_catch = ballistic_position(p0, pattern.release_velocity, f3, G)[1]
    z = ballistic_position(p0, np.array([0.0, one.release_speed]), one.flight, G)[1]
    assert z == pytest.approx(z_catch, abs=1e-9)
