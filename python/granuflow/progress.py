"""Progress bars for long runs (sweeps, maps, calibration starts, benchmarks): on a terminal only, never when the
output is piped or the caller asked for quiet."""
from __future__ import annotations

import sys


def wanted(progress: bool | None) -> bool:
    """``progress`` as given; None means: only when stderr is a terminal."""
    return sys.stderr.isatty() if progress is None else bool(progress)


def bar(progress: bool | None, total: int, desc: str, unit: str = "run"):
    """A tqdm bar on stderr, or None (not wanted, or tqdm not installed)."""
    if not wanted(progress):
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # tqdm is optional (Debian python3-tqdm)
        return None
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False)
