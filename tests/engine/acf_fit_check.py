#!/usr/bin/env python3
"""Independent check of the engine's exponential fit (seed eq. 8) by another
estimator: the exact Gaussian maximum likelihood of a first-order
Gauss-Markov series sampled every dt (an AR(1); Hamilton, Time Series
Analysis, 1994, section 5.2), zero-mean as the base model's drift (seed eq. 6,
whose fit also counts the series' mean against it):

    x_0 ~ N(0, sigma^2),
    x_k | x_{k-1} ~ N(phi x_{k-1}, sigma^2 (1 - phi^2)),  phi = exp(-dt / tau).

The negative log-likelihood is minimised with scipy over (ln sigma, ln tau);
the covariance of the estimates is the inverse of its Hessian there, by central
differences. Prints "ml NAME value se_of_log" for sigma and tau.

Usage: acf_fit_check.py SERIES_FILE DT_S
"""
import sys

import numpy as np
from scipy.optimize import minimize


def negative_log_likelihood(p, x, dt):
    log_sigma, log_tau = p
    sigma2 = np.exp(2.0 * log_sigma)
    phi = np.exp(-dt / np.exp(log_tau))
    innovation_var = sigma2 * (1.0 - phi * phi)
    e = x[1:] - phi * x[:-1]
    return 0.5 * (np.log(2.0 * np.pi * sigma2) + x[0] ** 2 / sigma2 +
                  e.size * np.log(2.0 * np.pi * innovation_var) + np.dot(e, e) / innovation_var)


def hessian(f, p, steps):
    n = p.size
    h = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            ei = np.zeros(n)
            ej = np.zeros(n)
            ei[i] = steps[i]
            ej[j] = steps[j]
            h[i, j] = (f(p + ei + ej) - f(p + ei - ej) - f(p - ei + ej) + f(p - ei - ej)) / (4.0 * steps[i] * steps[j])
    return h


def main():
    x = np.loadtxt(sys.argv[1], dtype=np.float64)
    dt = float(sys.argv[2])
    r0 = np.dot(x, x) / x.size
    r1 = np.dot(x[:-1], x[1:]) / x.size
    # Start from the lag-one moment estimate of phi.
    phi0 = min(max(r1 / r0, 1e-6), 1.0 - 1e-9)
    start = np.array([0.5 * np.log(r0), np.log(-dt / np.log(phi0))])
    f = lambda p: negative_log_likelihood(p, x, dt)
    result = minimize(f, start, method="Nelder-Mead",
                      options={"xatol": 1e-10, "fatol": 1e-10, "maxiter": 20000, "maxfev": 40000})
    if not result.success:
        print("likelihood maximisation failed: " + result.message, file=sys.stderr)
        return 1
    p = result.x
    covariance = np.linalg.inv(hessian(f, p, np.array([1e-3, 1e-3])))
    print("ml sigma %.17g %.17g" % (np.exp(p[0]), np.sqrt(covariance[0, 0])))
    print("ml tau_s %.17g %.17g" % (np.exp(p[1]), np.sqrt(covariance[1, 1])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
