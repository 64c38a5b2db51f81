#!/usr/bin/python3
"""Independent overlapping Allan deviation and noise-term fit (engine_allan_test).

Computes, with numpy in extended precision and a formulation of its own, the
overlapping Allan deviation of each channel pooled over static segments, the
equivalent degrees of freedom of NIST SP 1065 Table 5, and (on request) the
weighted least-squares fit of the IEEE Std 952 Annex C terms with
scipy.optimize. Written from the published formulas, not from the C++ code.

Input (one of):
  --samples FILE  little-endian binary: int64 rows, int64 cols, then rows x cols
                  float64; column 0 is the segment index, columns 1..6 the rates
                  gyro x, y, z [rad/s] and acc x, y, z [m/s^2] of the samples analysed
  --csv FILE      a bench-run CSV (insdiag-bench-run/1) whose reference attitude
                  never changes: the whole run is one segment
Options:
  --tau0 S        sample interval (--csv: the median step of t)
  --m 1,2,...     cluster sizes
  --fit CH[@LABEL]:TERMS[:DELTA]   fit channel CH (gyro_x ... acc_z) with TERMS
                  from Q,N,B,K,R,M (M: first-order Markov sigma, tau); DELTA: model
                  discrepancy (sd of ln sigma^2) added to every point's variance;
                  LABEL tells several fits of one channel apart
Output lines:
  adev CH M ADEV EDF
  fit CH[@LABEL] PARAM VALUE        PARAM: Q N B K R markov_sigma markov_tau (SI units)
  fitcost CH[@LABEL] COST
"""
import argparse
import math
import sys

import numpy as np
from scipy import optimize, special

CHANNELS = ["gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"]


# --------------------------------------------------------------------------
# Input

def read_samples(path):
    with open(path, "rb") as f:
        rows, cols = np.frombuffer(f.read(16), dtype="<i8")
        data = np.frombuffer(f.read(int(rows) * int(cols) * 8), dtype="<f8").reshape(int(rows), int(cols))
    segments = []
    ids = data[:, 0]
    for sid in np.unique(ids):
        segments.append(data[ids == sid, 1:7])
    return segments


def read_csv(path):
    header = None
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if header is None:
                header = [h.strip() for h in line.split(",")]
                continue
            rows.append(line)
    data = np.loadtxt(rows, delimiter=",")
    col = {name: i for i, name in enumerate(header)}
    ref = data[:, [col["ref_roll"], col["ref_pitch"], col["ref_yaw"]]]
    if np.any(ref != ref[0]):
        sys.exit("allan_check: the reference attitude changes; --csv handles still runs only")
    t = data[:, col["t"]]
    rates = data[:, [col[c] for c in CHANNELS]]
    return [rates], float(np.median(np.diff(t)))


# --------------------------------------------------------------------------
# Overlapping Allan variance: differences of consecutive overlapping cluster
# means, from cumulative sums in extended precision.

def allan(segments, channel, m_list):
    sums = []
    for seg in segments:
        x = seg[:, channel].astype(np.longdouble)
        s = np.concatenate([[np.longdouble(0)], np.cumsum(x - x.mean())])
        sums.append(s)
    out = []
    for m in m_list:
        total = np.longdouble(0)
        count = 0
        for s in sums:
            if len(s) - 2 * m < 1:
                continue
            cluster = s[m:] - s[:-m]               # sums of m samples starting at k
            diff = cluster[m:] - cluster[:-m]      # next cluster minus this one
            total += np.sum(diff * diff)
            count += len(diff)
        out.append(float(total / (2 * m * m * count)) if count else float("nan"))
    return np.array(out)


# --------------------------------------------------------------------------
# Equivalent degrees of freedom (NIST SP 1065, Table 5), noise type from the
# local log-log slope of the deviation.

def edf_one(alpha, n, m):
    """n phase points, cluster m."""
    big_m = n - 2 * m
    if big_m < 1:
        return 0.0
    if alpha == 2:
        v = (n + 1) * (n - 2 * m) / (2 * (n - m))
    elif alpha == 1:
        a = math.log((n - 1) / (2 * m))
        b = math.log((2 * m + 1) * (n - 1) / 4)
        v = math.exp(math.sqrt(a * b)) if a > 0 and b > 0 else 1.0
    elif alpha == 0:
        v = (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m * m / (4 * m * m + 5)
    elif alpha == -1:
        v = 2 * (n - 2) ** 2 / (2.3 * n - 4.9) if m == 1 else 5 * n * n / (4 * m * (n + 3 * m))
    else:
        v = (n - 2) / (m * (n - 3) ** 2) * ((n - 1) ** 2 - 3 * m * (n - 1) + 4 * m * m) if n > 3 else 1.0
    return min(max(v, 1.0), big_m)


def edf_curve(tau, adev, m_list, seg_lengths, window=0.5):
    lt, la = np.log(tau), np.log(adev)
    out = []
    for j in range(len(tau)):
        sel = np.abs(np.log10(tau / tau[j])) <= window + 1e-12
        slope = np.polyfit(lt[sel], la[sel], 1)[0] if sel.sum() >= 2 else -0.5
        if slope < -0.75:
            w = sum(edf_one(2, n + 1, m_list[j]) for n in seg_lengths)
            f = sum(edf_one(1, n + 1, m_list[j]) for n in seg_lengths)
            out.append(min(w, f))  # white or flicker phase: the smaller
        else:
            alpha = 0 if slope < -0.25 else (-1 if slope < 0.25 else -2)
            out.append(sum(edf_one(alpha, n + 1, m_list[j]) for n in seg_lengths))
    return np.array(out)


# --------------------------------------------------------------------------
# IEEE 952 terms: sigma^2 = 3Q^2/t^2 + N^2/t + (2ln2/pi)B^2 + K^2 t/3 + R^2 t^2/2 + Markov

FLICKER = 2 * math.log(2) / math.pi


def markov_shape(u):
    u = np.asarray(u, dtype=float)
    out = np.empty_like(u)
    small = u < 0.05
    us = u[small]
    # series of (2u - 3 + 4e^-u - e^-2u)/u^2 for small u
    out[small] = sum(((-1) ** k) * (4 - 2 ** k) / math.factorial(k) * us ** (k - 2) for k in range(3, 14))
    ub = u[~small]
    out[~small] = (2 * ub - 3 + 4 * np.exp(-ub) - np.exp(-2 * ub)) / ub ** 2
    return out


U_PEAK = optimize.minimize_scalar(lambda u: -markov_shape(np.array([u]))[0], bounds=(0.5, 6), method="bounded").x


def basis(term, tau, markov_tau=None):
    return {"Q": tau ** -2.0, "N": tau ** -1.0, "B": np.ones_like(tau), "K": tau, "R": tau ** 2,
            "M": markov_shape(tau / markov_tau) if markov_tau else None}[term]


def model_log(params, terms, tau):
    total = np.zeros_like(tau)
    i = 0
    for t in terms:
        if t == "M":
            total += np.exp(params[i]) * markov_shape(tau / np.exp(params[i + 1]))
            i += 2
        else:
            total += np.exp(params[i]) * basis(t, tau)
            i += 1
    return np.log(total)


def fit(tau, avar, edf, terms, delta):
    half = edf / 2
    y = np.log(avar) - (special.digamma(half) - np.log(half))
    sd = np.sqrt(special.polygamma(1, half) + delta ** 2)
    t_lo, t_hi = 3 * tau[0] / U_PEAK, tau[-1] / U_PEAK

    def nnls_start(markov_tau):
        cols = [basis(t, tau, markov_tau) for t in terms]
        a = np.column_stack(cols) / avar[:, None] / sd[:, None]
        scale = np.linalg.norm(a, axis=0)
        c, res = optimize.nnls(a / scale, 1 / sd)
        return c / scale, res

    if "M" in terms:
        grid = [t for t in t_lo * np.sqrt(10.0) ** np.arange(0, 30) if t <= t_hi] or [t_lo]
        best = min(((nnls_start(t), t) for t in grid), key=lambda r: r[0][1])
        coef, markov_tau = best[0][0], best[1]
    else:
        coef, markov_tau = nnls_start(None)[0], None
    x0, lower, upper = [], [], []
    for t, c in zip(terms, coef):
        env = np.min(avar / basis(t, tau, markov_tau))
        x0.append(math.log(c if c > 0 else 1e-3 * env))
        lower.append(math.log(env) - 40 if t != "M" else math.log(np.min(avar)) - 40)
        upper.append(math.log(env) + 5 if t != "M" else math.log(np.max(avar) * 100 * tau[-1] / tau[0]) + 5)
        if t == "M":
            x0.append(math.log(min(max(markov_tau, t_lo * 1.1), t_hi / 1.1)))
            lower.append(math.log(t_lo))
            upper.append(math.log(t_hi))
    x0 = np.clip(x0, np.array(lower) + 1e-6, np.array(upper) - 1e-6)

    def residual(p):
        return (y - model_log(p, terms, tau)) / sd

    best = None
    for shift in (0.0, 1.0, -1.0):
        start = np.clip(x0 + shift, np.array(lower) + 1e-6, np.array(upper) - 1e-6)
        r = optimize.least_squares(residual, start, bounds=(lower, upper), method="trf", xtol=1e-14,
                                   ftol=1e-14, gtol=1e-14, max_nfev=20000)
        if best is None or r.cost < best.cost:
            best = r
    values = {}
    i = 0
    for t in terms:
        c = math.exp(best.x[i])
        if t == "Q":
            values["Q"] = math.sqrt(c / 3)
        elif t == "N":
            values["N"] = math.sqrt(c)
        elif t == "B":
            values["B"] = math.sqrt(c / FLICKER)
        elif t == "K":
            values["K"] = math.sqrt(3 * c)
        elif t == "R":
            values["R"] = math.sqrt(2 * c)
        elif t == "M":
            values["markov_sigma"] = math.sqrt(c)
            values["markov_tau"] = math.exp(best.x[i + 1])
            i += 1
        i += 1
    return values, 2 * best.cost


def main():
    ap = argparse.ArgumentParser()
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--samples")
    src.add_argument("--csv")
    ap.add_argument("--tau0", type=float)
    ap.add_argument("--m", required=True)
    ap.add_argument("--fit", action="append", default=[])
    args = ap.parse_args()
    if args.csv:
        segments, tau0 = read_csv(args.csv)
    else:
        segments, tau0 = read_samples(args.samples), None
    tau0 = args.tau0 or tau0
    if not tau0:
        sys.exit("allan_check: --tau0 is required with --samples")
    m_list = [int(v) for v in args.m.split(",")]
    lengths = [len(s) for s in segments]
    tau = tau0 * np.array(m_list, dtype=float)
    requests = []
    for spec in args.fit:
        parts = spec.split(":")
        requests.append((parts[0], parts[1].split(","), float(parts[2]) if len(parts) > 2 else 0.0))
    for c, name in enumerate(CHANNELS):
        avar = allan(segments, c, m_list)
        edf = edf_curve(tau, np.sqrt(avar), m_list, lengths)
        for m, a, v in zip(m_list, avar, edf):
            print(f"adev {name} {m} {math.sqrt(a):.17g} {v:.10g}")
        for label, terms, delta in requests:
            if label.split("@")[0] != name:
                continue
            values, cost = fit(tau, avar, edf, terms, delta)
            for k, v in values.items():
                print(f"fit {label} {k} {v:.12g}")
            print(f"fitcost {label} {cost:.12g}")


if __name__ == "__main__":
    main()
