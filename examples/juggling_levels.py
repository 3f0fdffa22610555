"""
Juggling levels: a trivial policy against the juggler
=====================================================

The juggling benchmark's levels (easy, medium, hard) add release noise, sensor noise and
latency to the ball-in-hand task. ``fixed_point`` is a trivial policy: the juggler's
toss, then a catch reach to one fixed point (the demonstrations' mean catch point),
blind to the ball; ``juggler`` is the analytic juggler of Lippi, Avizzano & Ruffaldi,
which watches the ball. Six test seeds per level keep this fast; the
benchmark (``motion-bench juggling --levels``) uses 200.
"""

from baselines.juggling_bench import LevelsConfig, run_levels

config = LevelsConfig(
    levels=("easy", "hard"), methods=("juggler", "fixed_point"), episodes=6, max_catches=2
)
doc = run_levels(config)
for level in doc["levels"]:
    for name, m in level["methods"].items():
        lo, hi = m["catch_rate_ci"]
        print(
            f"{level['level']:6s} {name:12s} catch rate {m['catch_rate']:.2f} "
            f"(95 % interval {lo:.2f}-{hi:.2f}), {m['catches']} of {m['tosses']} tosses"
        )
