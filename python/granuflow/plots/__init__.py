"""Plots as files: time series and size distributions of runs (scene `plots:`), design-space maps,
calibration parity plots. matplotlib is imported only when a plot is drawn, NumPy only when a plot module is first
used (checking a scene's `plots:` before a run needs neither)."""
from .spec import plot_specs

__all__ = ["CLIP_FRACTION", "plot_psd", "plot_series", "supported_formats", "plot_specs"]


def __getattr__(name: str):
    if name in __all__:
        from . import series

        return getattr(series, name)
    raise AttributeError(f"module 'granuflow.plots' has no attribute '{name}'")
