"""
Fit the models on your own arrays
=================================

Five tasks in 30 lines of the public API: fit, predict from conditions, eq. 9, eq. 10,
orientation at given times, save and load (SIMULATED reaches at 120 Hz; docs/models.md).
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from motion_envs.geometry import expmap, minimum_jerk, sine_series, slerp
from motion_envs.models import OrientationModel, SineSeriesRegression

rng, rate, tau = np.random.default_rng(0), 120.0, np.linspace(0, 1, 121)  # 1 s movements
starts = rng.normal(scale=0.02, size=(24, 3))
ends = starts + rng.choice([-0.3, 0.3], size=(24, 3)) * [1, 1, 0] + rng.normal(0, 0.01, (24, 3))
reaches = minimum_jerk.minimum_jerk(starts, ends, tau) + rng.normal(0, 5e-4, (24, 121, 3))
model = SineSeriesRegression(n_sines=6).fit(np.hstack([starts, ends]), list(reaches), rate=rate)
y0, y1 = np.zeros(3), np.array([0.3, -0.3, 0.0])
q = np.r_[y0, y1]  # the conditions Q of eq. 6: start and end
y = model.predict(q, duration=1.0, times=[0.0, 0.5, 1.0], start=y0, end=y1)  # eqs. 7-8
p = model.plan(q, 1.0, start=y0, end=y1, final_velocity=[0, 0, -0.1])  # eq. 9, ends held
v_half = sine_series.velocity(p, 0.5, 1.0)  # executed state at tau = 0.5
p2 = model.correct(p, 0.5, sine_series.evaluate(p, 0.5), [0.32, -0.3, 0], 1.0, v_half)  # eq. 10
turns = [slerp(expmap([0, 0, 0.1 * i]), expmap([0.8, 0, 0]), tau) for i in range(6)]
orientation = OrientationModel(degree=2).fit(None, turns, rate=rate)
q_t = orientation.predict(expmap([0, 0, 0.2]), expmap([0.8, 0, 0]), [0.0, 0.25, 0.5, 1.0])
out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp())
again = SineSeriesRegression.load(model.save(out / "reach_model.json"))
assert np.array_equal(again.predict(q, 1.0, [0.0, 0.5, 1.0], start=y0, end=y1), y)
print("eq. 7-8 mid-point", y[1].round(3), "| eq. 9 end velocity", sine_series.velocity(p, 1.0, 1.0))
print("eq. 10 new end", sine_series.evaluate(p2, 1.0), "| quaternion at 0.25 s", q_t[1].round(3))
