"""Sensor errors of the independent bench-run simulator, sampled exactly as
interval means over each sample (t[k−1], t[k]] (the spec's gyro and
accelerometer columns are increments over the interval divided by Δt).

Per sensor axis (shared/spec/effects.md, measured = true + error):
  white noise     density N (ARW, VRW; IEEE Std 952-1997, annex C): the interval
                  mean of white noise has variance N²/Δt.
  Gauss–Markov    ḃ = −b/τ + σ√(2/τ) ξ. With β = 1/τ, φ = e^{−βΔt} and
                  q² = 2βσ², over one interval from b₀ (Maybeck, Stochastic
                  Models, Estimation and Control, vol. 1, §4.9; the integral
                  state as in Van Loan, IEEE Trans. AC 23(3), 1978):
                    b₁ = φ b₀ + w,   Δt·m = b₀ (1 − φ)/β + v,
                    Var w = σ²(1 − φ²),
                    Cov(w, v) = (q²/β) [(1 − φ)/β − (1 − φ²)/(2β)],
                    Var v = (q²/β²) [Δt − 2(1 − φ)/β + (1 − φ²)/(2β)].
  rate random walk ḃ = K ξ: Var w = K²Δt, Cov(w, v) = K²Δt²/2, Var v = K²Δt³/3.
  constants       turn-on bias c; scale factor s·(mean true input) (linear, so the
                  mean of the error is the error of the mean).
  faults          step c·1(t ≥ t₀): interval mean c·(share of the interval after t₀);
                  ramp r·(t − t₀)·1(t ≥ t₀): interval mean r·∫(t − t₀)⁺ dt / Δt.
"""
import numpy as np


def white_noise(rng, density, dt_s, n):
    return rng.standard_normal(n) * density / np.sqrt(dt_s)


def _correlated_pairs(rng, var_w, cov_wv, var_v, n):
    """n draws of (w, v) with the given 2×2 covariance."""
    L = np.linalg.cholesky(np.array([[var_w, cov_wv], [cov_wv, var_v]]) + 1e-300 * np.eye(2))
    z = rng.standard_normal((n, 2))
    pairs = z @ L.T
    return pairs[:, 0], pairs[:, 1]


def gauss_markov_interval_covariance(sigma, tau_s, dt_s):
    """φ, Var w, Cov(w, v) and Var v of one interval (the header's formulas)."""
    beta = 1.0 / tau_s
    x = beta * dt_s
    phi = np.exp(-x)
    one_minus_phi = -np.expm1(-x)
    q2 = 2.0 * beta * sigma * sigma
    var_w = sigma * sigma * -np.expm1(-2.0 * x)
    # Rearranged to keep their digits: (1 − φ) − (1 − φ²)/2 = (1 − φ)²/2, and
    # Var v = (q²/β³) g(βΔt) with g(x) = x − (1 − φ)(3 − φ)/2, whose terms
    # cancel to x³/3 − x⁴/4 + 7x⁵/60 − … when βΔt is small (a
    # navigation-grade τ at 100 Hz and more): there the series.
    cov = q2 * one_minus_phi ** 2 / (2.0 * beta ** 2)
    g = x ** 3 / 3.0 - x ** 4 / 4.0 + 7.0 * x ** 5 / 60.0 if x < 1e-3 else x - one_minus_phi * (3.0 - phi) / 2.0
    return phi, var_w, cov, q2 / beta ** 3 * g


def gauss_markov_means(rng, sigma, tau_s, dt_s, n):
    """Interval means of a stationary Gauss–Markov process over n samples of Δt."""
    if sigma <= 0.0:
        return np.zeros(n)
    beta = 1.0 / tau_s
    phi, var_w, cov, var_v = gauss_markov_interval_covariance(sigma, tau_s, dt_s)
    w, v = _correlated_pairs(rng, var_w, cov, var_v, n)
    # b_k = φ b_{k−1} + w_k: a first-order recursion, run by scipy's lfilter.
    from scipy.signal import lfilter
    b0 = rng.standard_normal() * sigma
    starts = np.empty(n)
    starts[0] = b0
    ends = lfilter([1.0], [1.0, -phi], w, zi=[phi * b0])[0]
    starts[1:] = ends[:-1]
    return (starts * (1.0 - phi) / beta + v) / dt_s


def random_walk_means(rng, density, dt_s, n):
    """Interval means of a rate random walk started at zero with the run."""
    if density <= 0.0:
        return np.zeros(n)
    k2 = density * density
    w, v = _correlated_pairs(rng, k2 * dt_s, k2 * dt_s ** 2 / 2.0, k2 * dt_s ** 3 / 3.0, n)
    ends = np.cumsum(w)
    starts = np.concatenate([[0.0], ends[:-1]])
    return (starts * dt_s + v) / dt_s


def step_means(edges_s, onset_s, size):
    """Interval means of size·1(t ≥ t₀) over intervals between consecutive edges."""
    t0, t1 = edges_s[:-1], edges_s[1:]
    share = np.clip((t1 - onset_s) / (t1 - t0), 0.0, 1.0)
    return size * share


def ramp_means(edges_s, onset_s, rate):
    """Interval means of rate·(t − t₀)⁺: ∫(t − t₀)⁺ = ((t₁ − t₀)⁺² − (t_a − t₀)⁺²)/2."""
    t0, t1 = edges_s[:-1], edges_s[1:]
    a = np.clip(t0 - onset_s, 0.0, None)
    b = np.clip(t1 - onset_s, 0.0, None)
    return rate * (b * b - a * a) / (2.0 * (t1 - t0))
