"""Recorded data as numpy arrays, and the sine fit the FRF uses."""
from dataclasses import dataclass, field
from typing import Dict, List, Tuple

import numpy as np


@dataclass
class Recording:
    """Samples of named registers: ``t`` (s, from the start) and one array per name."""

    t: np.ndarray
    data: Dict[str, np.ndarray]
    events: List[Tuple[float, str]] = field(default_factory=list)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[name]

    @property
    def names(self) -> Tuple[str, ...]:
        return tuple(self.data)

    def __len__(self) -> int:
        return len(self.t)

    def as_array(self) -> np.ndarray:
        """Columns t, then every name in order."""
        return np.column_stack([self.t] + [self.data[n] for n in self.data])

    def save_csv(self, path: str) -> None:
        np.savetxt(path, self.as_array(), delimiter=",", header=",".join(("t",) + self.names), comments="",
                   fmt="%.9g")

    def intervals(self) -> np.ndarray:
        """Sample-to-sample intervals (s): how regular the link let the polling be."""
        return np.diff(self.t)


@dataclass
class FrfResult:
    """Frequency response: f (Hz), complex H, and the fraction of the response's
    variance the fitted sine explains (1 = clean, low = noise or nonlinearity)."""

    f_Hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray

    @property
    def magnitude_dB(self) -> np.ndarray:
        return 20.0 * np.log10(np.abs(self.h))

    @property
    def phase_deg(self) -> np.ndarray:
        return np.degrees(np.angle(self.h))


def sine_fit(t: np.ndarray, y: np.ndarray, f_Hz: float) -> Tuple[complex, float]:
    """Least-squares fit of y ~ a sin(wt) + b cos(wt) + c at irregular times ``t``.
    Returns the complex amplitude a + jb (the phasor of sin(wt)) and the residual's
    mean square."""
    w = 2.0 * np.pi * f_Hz
    basis = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    residual = y - basis @ coef
    return complex(coef[0], coef[1]), float(np.mean(residual ** 2))
