"""Signal conditioning for comparisons: the matched low-pass and the fit accuracy phi."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import signal

__all__ = ["lowpass", "fit_accuracy", "LOWPASS_HZ", "LOWPASS_ORDER"]

#: **Assumption**: cut-off of the zero-phase low-pass applied alike to measured and
#: simulated accelerations before they are compared (MODEL.md section 7), Hz. It keeps
#: the drive and its first harmonics at 0.5-1.5 Hz and removes the 170 Hz plate mode that
#: force noise excites.
LOWPASS_HZ = 30.0
#: Butterworth order of that low-pass (applied forwards and backwards: twice this).
LOWPASS_ORDER = 4


@lru_cache(maxsize=32)
def _butter_sos(order: int, cutoff: float, fs: float) -> np.ndarray:
    """Butterworth design, cached: it cost as much as the filtering itself (0.5 ms), and
    the likelihood filters every evaluation with the same design."""
    return signal.butter(order, cutoff, fs=fs, output="sos")


def lowpass(x, fs: float, cutoff: float = LOWPASS_HZ, order: int = LOWPASS_ORDER) -> np.ndarray:
    """Zero-phase Butterworth low-pass of ``x`` (last axis) sampled at ``fs`` Hz.

    The same filter must be applied to measured and simulated signals alike. Ends ring
    as any zero-phase filter does; the padding is scipy's odd extension.
    """
    if not 0 < cutoff < fs / 2:
        raise ValueError(f"low-pass cut-off {cutoff} Hz must lie in (0, {fs / 2:g}) Hz")
    sos = _butter_sos(int(order), float(cutoff), float(fs)).copy()  # scipy wants it writable
    return signal.sosfiltfilt(sos, np.asarray(x, dtype=float), axis=-1)


def fit_accuracy(a_est, a_m) -> float | np.ndarray:
    """The paper's fit accuracy phi (eq. 5) as a fraction: 1 - ||a_est - a_m|| / ||a_m - mean||.

    ``a_est`` may carry leading axes (several simulations against one measurement).
    """
    a_m = np.asarray(a_m, dtype=float)
    a_est = np.asarray(a_est, dtype=float)
    spread = np.linalg.norm(a_m - a_m.mean())
    if spread == 0:
        raise ValueError("the measured acceleration is constant: phi is undefined")
    return 1.0 - np.linalg.norm(a_est - a_m, axis=-1) / spread
