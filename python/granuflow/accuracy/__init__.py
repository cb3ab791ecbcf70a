"""How accurate a result is, and results as accurate as asked for.

* :mod:`.estimate`: the numerical error of a result from re-solves on refined grids and at a tighter tolerance
  (``simulate(error_estimate=True)``, ``granuflow run --error-estimate``);
* :mod:`.target`: a result whose estimated error is below a target (``accuracy:`` in a scene,
  ``simulate(accuracy=0.01)``, ``granuflow run --accuracy 1%``), the grid and tolerance chosen by the estimate;
* :mod:`.grid_check`: the cheap check every plain run makes of its size grid (one solve on a grid twice as fine).
"""
from .estimate import (MIN_RTOL, ORDER_RANGE, REFINEMENTS, TOLERANCE_FACTOR, ErrorEstimate, OutputError,
                       estimate, not_corresponding, richardson, richardson_series)

__all__ = ["MIN_RTOL", "ORDER_RANGE", "REFINEMENTS", "TOLERANCE_FACTOR", "ErrorEstimate", "OutputError", "estimate",
           "not_corresponding", "richardson", "richardson_series"]
