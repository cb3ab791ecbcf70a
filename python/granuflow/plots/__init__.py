"""Plots as files: time series and size distributions of runs (scene `plots:`), design-space maps,
calibration parity plots. matplotlib is imported only when a plot is drawn."""
from .series import CLIP_FRACTION, plot_psd, plot_series, supported_formats
from .spec import plot_specs

__all__ = ["CLIP_FRACTION", "plot_psd", "plot_series", "supported_formats", "plot_specs"]
