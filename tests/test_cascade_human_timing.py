"""The pattern timing measurer (motion_envs.models.juggling.timing): a synthetic
three-ball cascade whose timing is worked by hand, the simulated jugglers' own timing
recovered from their trajectories (checked against the world's events), and bad
recordings refused in one line naming the file."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from _helpers import load_experiment
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motion_envs.models.juggling.timing import (
    PatternTrajectories,
    TimingOptions,
    detect_throws,
    measure_timing,
    read_pattern_markers,
)
from tests.test_mocap import write_c3d, write_tsv

G = 9.81

# The hand-worked oracle: a three-ball cascade at beat b = 0.25 s and dwell ratio 0.7.
# D = 0.7 * 2 * 0.25 = 0.35 s, F = 3 b - D = 0.40 s, V = 2 b - D = 0.15 s; 4 throws per
# second, 2 per hand; the apex above the release g F^2 / 8 = 9.81 * 0.16 / 8 = 0.1962 m;
# each hand's x from its release point (own 0.1 m) to its catch point (own 0.3 m): a span
# of 0.2 m; release and catch points 0.1 m and 0.3 m from the midline.
BEAT, RATIO = 0.25, 0.7
DWELL, FLIGHT, VACANT = 0.35, 0.40, 0.15
APEX = 0.1962


def cascade(
    beat: float = BEAT,
    dwell: float = DWELL,
    rate: float = 200.0,
    seconds: float = 8.0,
    offset: tuple[float, float] = (0.0, 0.0),
    noise: float = 0.0,
    seed: int = 0,
) -> PatternTrajectories:
    """The synthetic three-ball cascade: beat k at ``k beat``, thrown by hand ``k % 2``
    (0 right at x > 0), ball ``k % 3``, from the thrower's release point (own x 0.1, z 1)
    to the other hand's catch point (own x 0.3, z 1) in ``3 beat - dwell``; in hand the
    ball follows its hand's carry (a half-cosine in x, dipping 0.1 m), an empty hand its
    vacant path (dipping 0.05 m). The hand markers sit at the ball's centre minus
    ``offset``; Gaussian ``noise`` (m) on every marker."""
    flight, vacant = 3 * beat - dwell, 2 * beat - dwell
    t = np.arange(0.0, seconds, 1.0 / rate)
    sign = np.array([1.0, -1.0])

    def carry(h: int, s: np.ndarray) -> np.ndarray:
        x = 0.3 - 0.2 * (1 - np.cos(np.pi * s / dwell)) / 2
        return np.stack([sign[h] * x, 1.0 - 0.1 * np.sin(np.pi * s / dwell)], axis=-1)

    def empty(h: int, s: np.ndarray) -> np.ndarray:
        x = 0.1 + 0.2 * (1 - np.cos(np.pi * s / vacant)) / 2
        return np.stack([sign[h] * x, 1.0 - 0.05 * np.sin(np.pi * s / vacant)], axis=-1)

    point = np.empty((t.size, 2, 2))  # where each hand holds a ball
    for h in range(2):
        s = np.mod(t - h * beat, 2 * beat)  # since the hand's last release
        point[:, h] = np.where((s < vacant)[:, None], empty(h, s), carry(h, s - vacant))
    balls = np.empty((t.size, 3, 2))
    for j in range(3):
        k = np.floor((t / beat - j) / 3) * 3 + j  # the ball's last throw's beat
        tau = t - k * beat
        thrower = (k % 2).astype(int)
        sg = sign[thrower]
        vx = (-0.3 * sg - 0.1 * sg) / flight
        fly = np.stack([0.1 * sg + vx * tau, 1.0 + G * flight / 2 * tau - G / 2 * tau**2], -1)
        held = point[np.arange(t.size), 1 - thrower]
        balls[:, j] = np.where((tau < flight)[:, None], fly, held)
    hands = point - np.asarray(offset)
    rng = np.random.default_rng(seed)
    hands = hands + rng.normal(0.0, noise, hands.shape)
    balls = balls + rng.normal(0.0, noise, balls.shape)
    return PatternTrajectories(t=t, hands=hands, balls=balls, source="synthetic cascade")


def check_oracle(timing, tol_t: float) -> None:
    assert timing.beat == pytest.approx(BEAT, rel=2e-3)
    assert timing.throws_per_second == pytest.approx(1 / BEAT, rel=0.01)
    # per hand: the tempo times the hand's share of the counted throws (+-1 of ~30)
    assert timing.throws_per_second_per_hand == pytest.approx((2.0, 2.0), rel=0.05)
    assert timing.dwell == pytest.approx(DWELL, abs=tol_t)
    assert timing.dwell_ratio == pytest.approx(RATIO, abs=2 * tol_t / (2 * BEAT))
    assert set(timing.count_by_value) == {3}
    assert timing.flight_by_value[3] == pytest.approx(FLIGHT, abs=tol_t)
    assert timing.height_by_value[3] == pytest.approx(APEX, abs=0.01)
    assert timing.hand_span == pytest.approx((0.2, 0.2), abs=0.01)
    assert timing.release_offset == pytest.approx(0.1, abs=0.01)
    assert timing.catch_offset == pytest.approx(0.3, abs=0.01)


def test_synthetic_cascade_every_event_at_its_time():
    """Every release on its beat, every catch a flight later, the thrower and catcher
    the hands of the cascade, the ball's value 3; at 200 Hz within one frame."""
    traj = cascade()
    flights = detect_throws(traj, TimingOptions(contact_radius=0.02))
    assert len(flights) >= 25
    for f in flights:
        k = round(f.release / BEAT)
        assert f.release == pytest.approx(k * BEAT, abs=0.0051)
        assert f.catch == pytest.approx(k * BEAT + FLIGHT, abs=0.0051)
        assert (f.thrower, f.catcher, f.ball) == (k % 2, 1 - k % 2, k % 3)
    timing = measure_timing(traj, TimingOptions(contact_radius=0.02))
    check_oracle(timing, 0.006)
    assert set(timing.holds) == {0}


@pytest.mark.parametrize(
    ("rate", "offset", "noise", "radius", "tol"),
    [
        (240.0, (0.0, 0.04), 0.0, 0.08, 0.006),  # a marker 4 cm under the ball's centre
        (200.0, (0.02, 0.03), 0.001, 0.08, 0.012),  # and 1 mm of marker noise
        (120.0, (0.0, 0.0), 0.0005, 0.05, 0.012),  # a slower camera
    ],
)
def test_synthetic_cascade_with_offsets_noise_and_rates(rate, offset, noise, radius, tol):
    traj = cascade(beat=BEAT, rate=rate, offset=offset, noise=noise)
    check_oracle(measure_timing(traj, TimingOptions(contact_radius=radius)), tol)


def test_other_tempo_and_dwell_and_missing_frames():
    """Another beat and dwell ratio (b = 0.3 s, r = 0.6: D = 0.36 s, F = 0.54 s), with
    frames missing: a whole flight of one ball, then a hand for 20 ms."""
    traj = cascade(beat=0.3, dwell=0.36)
    balls, hands = traj.balls.copy(), traj.hands.copy()
    balls[400:420, 1] = np.nan
    hands[700:704, 0] = np.nan
    traj = PatternTrajectories(traj.t, hands, balls, "gappy")
    timing = measure_timing(traj, TimingOptions(contact_radius=0.02))
    assert timing.beat == pytest.approx(0.3, rel=2e-3)
    assert timing.dwell_ratio == pytest.approx(0.6, abs=0.02)
    assert timing.flight_by_value[3] == pytest.approx(0.54, abs=0.006)
    assert timing.height_by_value[3] == pytest.approx(G * 0.54**2 / 8, abs=0.01)


def siteswap(
    throws: tuple[int, ...], beat: float, dwell: float, seconds: float = 9.0, rate: float = 200.0
) -> PatternTrajectories:
    """A synthetic vanilla siteswap (values >= 2; a 2 held): beat k at ``k beat`` by hand
    ``k % 2``; a throw of ``h`` released from the thrower's release point (own x 0.1, z 1)
    lands in hand ``(k + h) % 2``'s catch point (own x 0.3, z 1) at ``(k + h) beat -
    dwell`` and is next released on the first beat ``k + h + 2m`` whose value is not 2.
    Between a catch and its hand's next release the hand carries the ball (half-cosine in
    x, a 0.1 m dip); between a release and the next catch it moves empty (a 0.05 m dip)."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    sign = np.array([1.0, -1.0])
    p = len(throws)

    def value(k: int) -> int:
        return throws[k % p]

    def next_release(landing: int) -> int:
        while value(landing) == 2:
            landing += 2
        return landing

    k0, k1 = -24, int(seconds / beat) + 24
    flights = []  # (ball, release beat, catch time)
    ball_of: dict[int, int] = {}
    n_balls = 0
    for k in range(k0, k1):
        if value(k) == 2:
            continue
        if k not in ball_of:
            ball_of[k] = n_balls
            n_balls += 1
        land = k + value(k)
        ball_of[next_release(land)] = ball_of[k]
        flights.append((ball_of[k], k, land * beat - dwell))
    events = {0: [], 1: []}  # per hand: (time, "catch" | "release")
    for _, k, tc in flights:
        events[k % 2].append((k * beat, "release"))
        events[(k + value(k)) % 2].append((tc, "catch"))
    hands = np.full((t.size, 2, 2), np.nan)
    for h in range(2):
        ev = sorted(events[h])
        for (ta, kind), (tb, _) in itertools.pairwise(ev):
            m = (t >= ta) & (t < tb)
            u = (t[m] - ta) / (tb - ta)
            ease = (1 - np.cos(np.pi * u)) / 2
            if kind == "catch":  # carry: catch point -> release point
                x, dip = 0.3 - 0.2 * ease, 0.1
            else:
                x, dip = 0.1 + 0.2 * ease, 0.05
            hands[m, h, 0] = sign[h] * x
            hands[m, h, 1] = 1.0 - dip * np.sin(np.pi * u)
    balls = np.full((t.size, n_balls, 2), np.nan)
    for j, k, tc in flights:
        thrower, catcher = k % 2, (k + value(k)) % 2
        tr = k * beat
        m = (t >= tr) & (t < tc)
        tau = t[m] - tr
        f = tc - tr
        vx = (0.3 * sign[catcher] - 0.1 * sign[thrower]) / f
        balls[m, j] = np.stack(
            [0.1 * sign[thrower] + vx * tau, 1.0 + G * f / 2 * tau - G / 2 * tau**2], -1
        )
        nxt = next_release(k + value(k)) * beat
        m = (t >= tc) & (t < nxt)
        balls[m, j] = hands[m, catcher]
    return PatternTrajectories(t, hands, balls, f"synthetic {throws}")


@pytest.mark.parametrize(
    ("throws", "flights", "heights", "tempo", "holds"),
    [
        # 423 at b = 0.25 s, D = 0.35 s: F4 = 1.00 - 0.35 = 0.65 s, F3 = 0.75 - 0.35 =
        # 0.40 s; apex g F^2 / 8 = 0.5181 m and 0.1962 m; two throws in three beats:
        # 2/3 / 0.25 = 2.667 throws/s; each 4 lands on a 2: held one hand period.
        ((4, 2, 3), {4: 0.65, 3: 0.40}, {4: 0.5181, 3: 0.1962}, 8 / 3, {4: 1, 3: 0}),
        # the fountain: F4 = 0.65 s, every beat a throw: 4 throws/s
        ((4,), {4: 0.65}, {4: 0.5181}, 4.0, {4: 0}),
        # the five-ball cascade: F5 = 1.25 - 0.35 = 0.90 s, apex 9.81 * 0.81 / 8 = 0.9933 m
        ((5,), {5: 0.90}, {5: 0.9933}, 4.0, {5: 0}),
    ],
)
def test_synthetic_siteswaps_with_holds(throws, flights, heights, tempo, holds):
    """Other siteswaps worked by hand at b = 0.25 s and D = 0.35 s (r = 0.7), the 2 of
    423 held: the values, their flights and heights, the beats held, the tempo."""
    traj = siteswap(throws, BEAT, DWELL)
    assert traj.balls.shape[1] == sum(throws) // len(throws)
    timing = measure_timing(traj, TimingOptions(contact_radius=0.02, skip_start=0.5))
    assert timing.beat == pytest.approx(BEAT, rel=2e-3)
    assert set(timing.count_by_value) == set(flights)
    for v, f in flights.items():
        assert timing.flight_by_value[v] == pytest.approx(f, abs=0.006)
        # the apex above the release: a release placed half a frame late lowers it by
        # v_z * 2.5 ms (1.1 cm for the five-ball cascade's 4.4 m/s)
        assert timing.height_by_value[v] == pytest.approx(heights[v], abs=0.015)
        assert timing.dwell_by_value[v] == pytest.approx(DWELL, abs=0.006)
    for v, n in zip(timing.values, timing.holds, strict=True):
        if v:
            assert n == holds[v]
    assert timing.dwell_ratio == pytest.approx(RATIO, abs=0.02)
    # each ball's last throw has no value: at the ends a throw or hold of ~40 may be off
    assert timing.throws_per_second == pytest.approx(tempo, rel=0.03)
    assert timing.throws_per_second_per_hand == pytest.approx((tempo / 2, tempo / 2), rel=0.06)


def test_a_carried_ball_is_no_flight():
    """The ball carried 10 cm from a hand marker (beyond contact_radius) is not ballistic:
    no flight is found where the ball only follows the hand."""
    t = np.arange(0.0, 2.0, 0.005)
    hand = np.stack([0.2 * np.sin(2 * np.pi * t), 1.0 + 0.1 * np.cos(2 * np.pi * t)], -1)
    hands = np.stack([hand, hand * (-1.0, 1.0)], axis=1)
    balls = (hand + np.array([0.0, 0.1]))[:, None, :]
    traj = PatternTrajectories(t, hands, balls, "carried")
    assert detect_throws(traj, TimingOptions(contact_radius=0.05)) == []
    with pytest.raises(ValueError, match="carried: 0 throws detected"):
        measure_timing(traj)


@pytest.fixture(scope="module")
def experiment():
    return load_experiment("cascade_human_timing")


def world_beat(events) -> float:
    """s: the mean gap between consecutive releases of the world (after 1 s), over the
    gaps shorter than 1.5 times the shortest quarter's (a held 2 leaves a double gap)."""
    rel = np.sort([e[0] for e in events if e[2] == "release" and e[0] >= 1.0])
    gaps = np.diff(rel)
    return float(gaps[gaps < 1.5 * np.percentile(gaps, 25)].mean())


def world_dwell(events, beat: float) -> float:
    """The median time from a catch to the same ball's next release, less the whole hand
    periods it was held over (the world's own events)."""
    out = []
    for when, ball, kind in events:
        if kind != "catch" or when < 1.0:
            continue
        nxt = [e[0] for e in events if e[1] == ball and e[2] == "release" and e[0] > when]
        if nxt:
            d = nxt[0] - when
            out.append(d - 2 * beat * math.floor(d / (2 * beat)))
    return float(np.median(out))


@pytest.mark.parametrize(("pattern", "ratio_tol"), [("3-human", 0.03), ("5", 0.1), ("423", 0.2)])
def test_simulated_juggler_recovered(experiment, pattern, ratio_tol):
    """From the SIMULATED positions alone: every release and catch within one 5 ms period
    of the world's, the beat within 0.5 % of the world's releases' (and 2 % of the
    juggler's nominal beat: the fitted juggler plays ~1.5 % faster than its own), the
    dwell within 10 ms of the world's events' and the dwell ratio near the juggler's
    planned one (its catches fall late of the plan: the five-ball juggler's by 10-30 ms,
    423's 3s far later); the throws per second 1 / b but for the held beats (423: 2/3)."""
    traj, nominal, events = experiment.simulate(pattern, 2026, "easy", 30)
    assert traj.simulated and "SIMULATED" in traj.source
    timing = measure_timing(traj, TimingOptions(contact_radius=0.02, skip_start=1.0))
    assert experiment.event_error(timing, events) <= 0.0051
    assert timing.beat == pytest.approx(world_beat(events), rel=0.005)
    assert timing.beat == pytest.approx(nominal["beat"], rel=0.02)
    assert timing.dwell == pytest.approx(world_dwell(events, timing.beat), abs=0.01)
    assert timing.dwell_ratio == pytest.approx(nominal["dwell_ratio"], abs=ratio_tol)
    share = 2 / 3 if pattern == "423" else 1.0
    assert timing.throws_per_second == pytest.approx(share / timing.beat, rel=0.03)
    expected = {"3-human": {3}, "5": {5}, "423": {3, 4}}[pattern]
    main = {v for v, n in timing.count_by_value.items() if n >= 0.2 * len(timing.flights)}
    assert main == expected


def test_recording_round_trip_tsv_and_c3d(tmp_path):
    """The synthetic cascade written as a Qualisys TSV (mm, Z up) and as a C3D (mm, Y up,
    the left hand missing in two gaps) is read back and measured as the oracle says."""
    traj = cascade(rate=120.0, seconds=10.0)
    n = traj.t.size
    names = ["RH", "LH", "B1", "B2", "B3"]
    xz = np.concatenate([traj.hands, traj.balls], axis=1)
    pts = np.zeros((n, 5, 3))
    pts[:, :, 0], pts[:, :, 2] = xz[:, :, 0], xz[:, :, 1]
    pts[:, :, 1] = 0.4  # the pattern's plane 0.4 m in front
    write_tsv(tmp_path / "c.tsv", pts * 1000.0, names, rate=120.0)
    read = read_pattern_markers(tmp_path / "c.tsv", ["RH", "LH"], ["B1", "B2", "B3"])
    assert not read.simulated
    check_oracle(measure_timing(read, TimingOptions(contact_radius=0.05)), 0.012)
    write_c3d(tmp_path / "c.c3d", pts, names)
    read = read_pattern_markers(tmp_path / "c.c3d", ["RH", "LH"], ["B1", "B2", "B3"], up="y")
    assert np.isnan(read.hands[300:303, 1]).all()
    check_oracle(measure_timing(read, TimingOptions(contact_radius=0.05)), 0.012)


def test_recording_csv(tmp_path):
    traj = cascade(rate=200.0)
    cols = {"t": traj.t}
    for i, m in enumerate(["R", "L"]):
        cols[f"{m}_x"], cols[f"{m}_z"] = traj.hands[:, i, 0], traj.hands[:, i, 1]
    for i in range(3):
        cols[f"b{i}_x"], cols[f"b{i}_z"] = traj.balls[:, i, 0], traj.balls[:, i, 1]
    import pandas as pd

    frame = pd.DataFrame(cols)
    frame.loc[50:52, "b1_x"] = np.nan  # empty cells: missing samples
    frame.to_csv(tmp_path / "c.csv", index=False)
    read = read_pattern_markers(tmp_path / "c.csv", ["R", "L"], ["b0", "b1", "b2"])
    assert np.isnan(read.balls[50:53, 1, 0]).all()
    check_oracle(measure_timing(read, TimingOptions(contact_radius=0.02)), 0.006)


def bad(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def test_bad_recordings_one_line_naming_the_file(tmp_path):
    header = "t,R_x,R_z,L_x,L_z,b_x,b_z\n"
    rows = "".join(f"{i / 100},0,1,0,1,0,1\n" for i in range(20))
    cases = [
        (bad(tmp_path, "cols.csv", "t,R_x,R_z\n0,0,1\n"), "missing column"),
        (bad(tmp_path, "cell.csv", header + rows + "0.2,0,1,0,1,x,1\n"), "line(s) 22"),
        (bad(tmp_path, "back.csv", header + rows + "0.1,0,1,0,1,0,1\n"), "not strictly"),
        (bad(tmp_path, "short.csv", header + "0,0,1,0,1,0,1\n"), "at least 10"),
        (bad(tmp_path, "x.txt", "hello"), "unknown motion capture format"),
        (bad(tmp_path, "empty.csv", ""), "empty"),
    ]
    for path, what in cases:
        with pytest.raises(ValueError) as err:
            read_pattern_markers(path, ["R", "L"], ["b"])
        message = str(err.value)
        assert str(path) in message and what in message and "\n" not in message, message
    with pytest.raises(FileNotFoundError, match=r"nope\.csv"):
        read_pattern_markers(tmp_path / "nope.csv", ["R", "L"], ["b"])
    ok = bad(tmp_path, "ok.csv", header + rows)
    with pytest.raises(ValueError, match="two hand markers"):
        read_pattern_markers(ok, ["R"], ["b"])
    with pytest.raises(ValueError, match="named twice"):
        read_pattern_markers(ok, ["R", "L"], ["R"])
    with pytest.raises(ValueError, match="unit applies to C3D"):
        read_pattern_markers(ok, ["R", "L"], ["b"], unit="mm")
    gone = bad(tmp_path, "gone.csv", header + rows.replace(",0,1\n", ",,\n"))
    with pytest.raises(ValueError, match="marker 'b' has no sample"):
        read_pattern_markers(gone, ["R", "L"], ["b"])
    slow = bad(tmp_path, "slow.csv", header + "".join(f"{i / 10},0,1,0,1,0,1\n" for i in range(20)))
    with pytest.raises(ValueError, match="10 Hz; measuring a timing needs at least 50 Hz"):
        read_pattern_markers(slow, ["R", "L"], ["b"])
    with pytest.raises(ValueError, match=r"TimingOptions\.contact_radius"):
        TimingOptions(contact_radius=-1.0)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    data=st.binary(max_size=2048),
    keep=st.integers(min_value=0, max_value=2000),
    suffix=st.sampled_from([".csv", ".tsv"]),
)
def test_corrupted_recordings_are_one_line_value_errors(tmp_path, data, keep, suffix):
    """Fuzz: a valid CSV or Qualisys TSV cut short and followed by arbitrary bytes is read
    or refused with one ValueError line naming the file, never another error."""
    traj = cascade(rate=100.0)
    path = tmp_path / f"r{suffix}"
    if suffix == ".csv":
        lines = ["t,R_x,R_z,L_x,L_z,b0_x,b0_z"]
        lines += [
            f"{t},{h[0, 0]},{h[0, 1]},{h[1, 0]},{h[1, 1]},{b[0, 0]},{b[0, 1]}"
            for t, h, b in zip(traj.t[:80], traj.hands, traj.balls, strict=False)
        ]
        path.write_bytes("\n".join(lines).encode()[:keep] + data)
    else:
        points = 1000.0 * np.concatenate(
            [np.insert(traj.hands[:80, i], 1, 0.0, axis=1)[:, None] for i in range(2)]
            + [np.insert(traj.balls[:80, 0], 1, 0.0, axis=1)[:, None]],
            axis=1,
        )
        write_tsv(path, points, ["R", "L", "b0"], rate=100.0)
        path.write_bytes(path.read_bytes()[:keep] + data)
    try:
        read_pattern_markers(path, ["R", "L"], ["b0"])
    except ValueError as err:
        message = str(err)
        assert str(path) in message and "\n" not in message, message


def test_experiment_measures_a_recording(experiment, tmp_path, capsys):
    """``--recording``: the synthetic cascade as a TSV, measured by the experiment's CLI
    (the JSON it prints and writes with --out)."""
    import json

    traj = cascade(rate=200.0)
    xz = np.concatenate([traj.hands, traj.balls], axis=1)
    pts = np.zeros((traj.t.size, 5, 3))
    pts[:, :, 0], pts[:, :, 2] = xz[:, :, 0], xz[:, :, 1]
    write_tsv(tmp_path / "c.tsv", pts * 1000.0, ["R", "L", "a", "b", "c"], rate=200.0)
    out = tmp_path / "out.json"
    argv = ["--recording", str(tmp_path / "c.tsv"), "--hands", "R,L", "--balls", "a,b,c"]
    experiment.main([*argv, "--contact-radius", "0.02", "--out", str(out)])
    doc = json.loads(out.read_text())
    assert doc["recording"]["beat"] == pytest.approx(BEAT, rel=2e-3)
    assert doc["recording"]["dwell_ratio"] == pytest.approx(RATIO, abs=0.03)
    assert doc["recording"]["simulated"] is False
    assert doc["published"][0]["url"].startswith("http")
    assert '"dwell_ratio"' in capsys.readouterr().out


def test_experiment_cli_errors(experiment, tmp_path, capsys):
    with pytest.raises(SystemExit) as ex:
        experiment.main(["--recording", str(tmp_path / "x.csv")])
    assert ex.value.code == 2
    with pytest.raises(SystemExit) as ex:
        experiment.main(["--recording", str(tmp_path / "no.csv"), "--hands", "R,L", "--balls", "b"])
    assert ex.value.code == 2
    assert "no.csv does not exist" in capsys.readouterr().err
