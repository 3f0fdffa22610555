"""
One row of Table 1 by hand
==========================

Faraway & Choe's Table 1 scores orientation models by the median over reaches of the
max over time of the error. This example computes its ``null`` row (one mean residual
curve for everyone, degree-2 Bézier control points) in-sample by hand on the built-in
``vr-kitchen`` reaches, and checks it against :func:`motion_envs.models.criteria.table1`.
"""

import numpy as np

from motion_envs.datasets import load_orientation_dataset
from motion_envs.models.bezier_models import NullBezierModel
from motion_envs.models.criteria import median_max_error, table1
from motion_envs.models.slerp_residual import slerp_residuals

ds = load_orientation_dataset("vr-kitchen")
R = slerp_residuals(ds.ragged)  # (L, 50, 3): each reach's rotation off the slerp path
model = NullBezierModel(degree=2).fit(R)
by_hand = median_max_error(R, model.predict(n=len(R)))
rows = table1(ds.ragged, ds.subjects, ds.tasks).criteria
print(f"{len(R)} reaches of {len(np.unique(ds.subjects))} people")
print(f"null (d=2): by hand {by_hand:.4f} rad, table1 {rows['null_d2']:.4f} rad")
assert np.isclose(by_hand, rows["null_d2"])
print({k: round(v, 3) for k, v in rows.items() if k in ("within_subject", "slerp_empirical")})
