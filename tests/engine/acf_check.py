#!/usr/bin/env python3
"""Independent check of the engine's sample autocovariance (seed eq. 9).

    R_j = (1/N) sum_{i=0}^{N-1-j} (x_i - m)(x_{i+j} - m),   m = (1/N) sum x_i

Reads a series (one value a line, %.17g) and prints "acf j value" for
j = 0 .. max_lag, computed two ways with numpy — direct dot products and the
zero-padded FFT (Wiener–Khinchin: the inverse transform of |X|^2 with at least
2N points is the circular autocorrelation without wrap-around) — and exits
non-zero when they disagree beyond 1e-9 of R_0.

Usage: acf_check.py SERIES_FILE MAX_LAG
"""
import sys

import numpy as np


def main():
    x = np.loadtxt(sys.argv[1], dtype=np.float64)
    max_lag = int(sys.argv[2])
    n = x.size
    c = x - x.mean()
    direct = np.array([np.dot(c[: n - j], c[j:]) / n for j in range(max_lag + 1)])
    size = 1 << int(np.ceil(np.log2(2 * n)))
    spectrum = np.fft.rfft(c, size)
    via_fft = np.fft.irfft(spectrum * np.conj(spectrum), size)[: max_lag + 1] / n
    if np.max(np.abs(direct - via_fft)) > 1e-9 * direct[0]:
        print("direct and FFT estimates disagree", file=sys.stderr)
        return 1
    for j, v in enumerate(direct):
        print("acf %d %.17g" % (j, v))
    return 0


if __name__ == "__main__":
    sys.exit(main())
