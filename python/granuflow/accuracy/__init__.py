"""How accurate a result is, and results as accurate as asked for.

* :mod:`.estimate`: the numerical error of a result from re-solves on refined grids and at a tighter tolerance
  (``simulate(error_estimate=True)``, ``granuflow run --error-estimate``);
* :mod:`.target`: a result whose estimated error is below a target (``accuracy:`` in a scene,
  ``simulate(accuracy=0.01)``, ``granuflow run --accuracy 1%``), the grid and tolerance chosen by the estimate;
* :mod:`.grid_check`: the cheap check every plain run makes of its size grid (one solve on a grid twice as fine).
"""
__all__ = ["MIN_RTOL", "ORDER_RANGE", "REFINEMENTS", "TOLERANCE_FACTOR", "ErrorEstimate", "OutputError", "estimate",
           "not_corresponding", "richardson", "richardson_series"]


def __getattr__(name: str):
    # The names of .estimate on first use: a plain run's grid check needs none of them (nor their imports).
    if name in __all__:
        import importlib

        # importing binds the submodule as .estimate, which its function of that name replaces, as an eager import
        # would ("from . import estimate" would ask this __getattr__ for it again)
        module = importlib.import_module(".estimate", __name__)
        globals().update({n: getattr(module, n) for n in __all__})
        return globals()[name]
    raise AttributeError(f"module 'granuflow.accuracy' has no attribute '{name}'")
