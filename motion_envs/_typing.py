"""The array type aliases shared by every layer (one home instead of one per module)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["FloatArray"]

#: A float64 numpy array of any shape: positions, times, parameters, errors.
FloatArray = NDArray[np.float64]
