"""Type aliases shared by the core modules."""

from typing import Any

import numpy as np
import numpy.typing as npt

# Floating rather than float64 alone: numpy's linear algebra is typed to return the former.
FloatArray = npt.NDArray[np.floating[Any]]
IntArray = npt.NDArray[np.integer[Any]]
