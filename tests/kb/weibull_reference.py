#!/usr/bin/python3
"""Independent maximum-likelihood fit of a 2-parameter Weibull with right
censoring (scipy), the cross-check of kb/reliability.h (FitWeibull).

Input: a CSV of `hours,failed` lines (failed 1 or 0). Output: one line
`shape scale b10 mtbf_lower mtbf_upper` where the MTBF bounds are the
time-terminated chi-square bounds at 90 % for the same data's total hours and
failures. The fit minimises the negative log-likelihood
  -[sum_F (ln b - b ln e + (b-1) ln t) - sum_all (t/e)^b]
directly over (ln b, ln e) with Nelder-Mead from the least-squares start of a
median-rank regression: a different route from the profile-score root in C++.
"""
import sys
import numpy as np
from scipy import optimize, stats

data = np.loadtxt(sys.argv[1], delimiter=",", ndmin=2)
t, failed = data[:, 0], data[:, 1] > 0.5
tf = t[failed]

def nll(theta):
    b, e = np.exp(theta)
    return -(np.sum(np.log(b) - b * np.log(e) + (b - 1) * np.log(tf)) - np.sum((t / e) ** b))

# Start: Weibull plot of the failures alone (Bernard's median ranks).
x = np.sort(np.log(tf))
f = (np.arange(1, len(x) + 1) - 0.3) / (len(x) + 0.4)
slope, intercept = np.polyfit(x, np.log(-np.log(1 - f)), 1)
start = np.array([np.log(slope), -intercept / slope])
res = optimize.minimize(nll, start, method="Nelder-Mead",
                        options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000, "maxfev": 40000})
b, e = np.exp(res.x)
b10 = e * (-np.log(0.9)) ** (1 / b)
T, r = t.sum(), failed.sum()
lower = 2 * T / stats.chi2.ppf(0.95, 2 * r + 2)
upper = 2 * T / stats.chi2.ppf(0.05, 2 * r)
print(f"{b:.12g} {e:.12g} {b10:.12g} {lower:.12g} {upper:.12g}")
