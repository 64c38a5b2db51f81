"""Raw logs of the independent simulator: what a unit's own logger writes
while the unit sits on a stand, not a bench run. The file holds samples only
(t, gyro x y z, acc x y z) — no reference attitude, no site, no datasheet —
and is made into a bench run by `insdiag import … --attitude level`, as a
user's real record is. Each real-life property below can be switched off;
off, the log is the bench run's samples on a level, surveyed, still unit.

The stand (one unit set down on it, at rest on the Earth):

  attitude   C_b^n(t) = R(u, θ(t)) · C₀,   C₀ = Rz(ψ) Ry(θp) Rx(φ) · B.
             B is the orientation the unit is set down in (`up`: z down, as
             mounted; `side`: on its side, y down, B = Rx(90°); `inverted`:
             B = Rx(180°)). The unit is never set down exactly: roll φ and
             pitch θp are drawn uniformly within ±tilt (a plate's flatness and
             a mount's seating: a few mrad; a unit put down on a bench by
             hand: degrees), and the heading ψ uniformly over the circle (no
             one surveys it). The import must level the unit from its own
             specific force and gyro-compass the heading — or, with a
             consumer gyro's turn-on bias far above the Earth's rate, cannot.
  rocking    θ(t) about one horizontal axis u (drawn uniformly):
               θ(t) = A_w sin(2π f_w t + φ_w)            sway
                    + A_s e^{−t/τ_s} cos(2π f_s t)         settling
             A stand is a spring: it sways at its mode, driven by the floor,
             air and people (µrad–mrad, 0.1–5 Hz), and rings down from the
             unit being set on it in its first seconds. The sensors sit a
             lever arm ℓ above the pivot, p(t) = R(u, θ) p₀, p₀ = [0, 0, −ℓ]
             (NED: up is −z), so the accelerometers feel the tangential and
             centripetal accelerations
               p̈ = θ̈ u × p + θ̇² u × (u × p).
  kinematics (Groves, Principles of GNSS, Inertial and Multisensor Integrated
             Navigation Systems, 2nd ed., eq. 5.42; the mm/s velocities make
             the Coriolis and transport terms below 1e-7 m/s² and are left out)
               ω_ib^b = C^T (θ̇ u + ω_ie^n),   f^b = C^T (p̈ − g^n),
             with g^n = [0, 0, g(L, h)] WGS-84 normal gravity
             (kinematics.normal_gravity_mps2). A sample holds the mean over its
             interval (t[k−1], t[k]], by Gauss–Legendre quadrature
             (kinematics.interval_means); without rocking C is constant and
             the means are exact.

The sensors: the preset's white noise and Gauss–Markov drift (sensors.py),
then flicker and warm-up where asked, then turn-on biases, then the output's
quantisation.

  flicker    bias instability: a 1/f power spectral density S(f) = h₋₁/f
             (one-sided), whose Allan deviation is flat at σ_A = √(2 ln 2 ·
             h₋₁) (IEEE Std 952-1997, annex C: σ_A = 0.664 B with
             S = B²/(2π f)). Made as a sum of first-order Gauss–Markov
             processes with correlation times spaced by a ratio r from one
             sample interval to the log's length, each of variance h₋₁ ln r:
             Σ 4σ²τ/(1 + (2πfτ)²) over log-spaced τ is σ²/(f ln r) within the
             band (Keshner, Proc. IEEE 70(3), 1982). `--gyro-flicker-dph` and
             `--acc-flicker-ug` give σ_A per axis.
  warm-up    a bias that settles after power-up, b(t) = b_w e^{−t/τ_w}, of a
             random sign per axis (`--warmup-gyro-dps`, `--warmup-acc-mg`,
             `--warmup-tau-s`): a MEMS part's die warms by several kelvin over
             its first minutes, and its bias follows.

  turn-on bias  a constant per axis and per power-up, drawn with a random sign
             and a magnitude uniform in [lo, hi]: for the `mems` preset the
             gyros' 0.1–0.5 °/s and accelerometers' 5–50 mg of consumer MEMS
             datasheets (the MPU-6050's ±20 °/s and ±50–80 mg zero-rate and
             zero-g offsets are the worst case; the record in data/real has
             −3.3, −1.1, 0.5 °/s); for `nav` the INS-2000's class, 0.002–0.01
             °/h and 20–100 µg.
  quantisation  increments: an RLG counts fringes, a pulse-rebalanced
             accelerometer counts charge pulses: the logger's sample is the
             change of an integer counter over the interval, so the output is
             an integer number of quanta q and the counters' error never
             accumulates: Σ out = q·(⌊Θ_k/q + r₀⌋ − ⌊r₀⌋) stays within one q of
             the true angle (velocity) Θ_k, r₀ the counter's residue at
             turn-on (uniform). The error is Θ's residue: white in angle when
             the input moves Θ through many quanta at random, which gives the
             Allan deviation of quantisation noise, σ(τ) = √3 Q/τ with
             Q = q/√12, i.e. q/(2τ) (IEEE Std 952-1997, annex C.2). The
             error Θ_k − Σ out = q·(frac(Θ_k/q + r₀) − r₀) has the mean
             q·(½ − r₀): summed velocity increments carry a constant velocity
             of up to ±q/2 from turn-on (0.6 mm/s for 125 µg·s), which a
             zero-velocity reference sees from the first second. Defaults:
             the counts of the navigation-grade RLG log in data/real, 0.1″
             and 125 µg·s.
             rates: a MEMS ADC samples the rate (force) and rounds it to its
             LSB: out = q·round(ω/q), a white error of variance q²/12 per
             sample when the noise spans several LSB. Defaults: the MPU-6050's
             ±250 °/s and ±2 g ranges, 1/131 °/s and 1/16384 g per LSB.

Written as text (`t,gyro_x,…,acc_z`, one record a line, t in s, the
sensors in rad, m/s — increments — or rad/s, m/s² — rates) or as binary
records of seven little-endian float64. The truth (the draws above, C₀, the
start's attitude, the turn-on biases, the quanta) goes to LOG.truth.json,
with the units `insdiag import` must be given."""
import json
import math

import numpy as np

import kinematics
import sensors
import unit_classes

AXES = unit_classes.AXES
DEG = unit_classes.DEG
ARCSEC = DEG / 3600.0
G0 = 9.80665
ORIENTATIONS = {"up": 0.0, "side": 90.0, "inverted": 180.0}  # roll of B [deg]

# Per preset: the output (increments or rates), its quanta [rad, m/s] or
# [rad/s, m/s²], and the turn-on biases' magnitude ranges [rad/s], [m/s²].
OUTPUTS = {
    "nav": dict(output="increments", gyro_lsb=0.1 * ARCSEC, acc_lsb=125e-6 * G0,
                gyro_turn_on=(0.002 * DEG / 3600, 0.01 * DEG / 3600), acc_turn_on=(20e-6 * G0, 100e-6 * G0)),
    "mems": dict(output="rates", gyro_lsb=DEG / 131.0, acc_lsb=G0 / 16384.0,
                 gyro_turn_on=(0.1 * DEG, 0.5 * DEG), acc_turn_on=(5e-3 * G0, 50e-3 * G0)),
}
for _name in ("tactical", "tactical-0.1"):
    OUTPUTS[_name] = dict(OUTPUTS["nav"], gyro_turn_on=(0.5 * DEG / 3600, 2 * DEG / 3600),
                          acc_turn_on=(0.2e-3 * G0, 2e-3 * G0))


def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def axis_rotation(u, angles):
    """R(u, θ) for an array of angles (Rodrigues): shape (n, 3, 3)."""
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    s, c = np.sin(angles)[:, None, None], np.cos(angles)[:, None, None]
    return np.eye(3)[None] + s * K[None] + (1.0 - c) * (K @ K)[None]


class Rocking:
    """θ(t) of the stand and its derivatives (the docstring's sway + settling)."""

    def __init__(self, sway_rad=0.0, sway_hz=1.0, sway_phase=0.0, settle_rad=0.0, settle_hz=2.0, settle_tau_s=1.0):
        self.aw, self.ww, self.pw = sway_rad, 2 * math.pi * sway_hz, sway_phase
        self.as_, self.ws, self.ts = settle_rad, 2 * math.pi * settle_hz, settle_tau_s

    def still(self):
        return self.aw == 0.0 and self.as_ == 0.0

    def __call__(self, t):
        """θ, θ̇, θ̈ at the times t."""
        w, p = self.ww, self.ww * t + self.pw
        th = self.aw * np.sin(p)
        thd = self.aw * w * np.cos(p)
        thdd = -self.aw * w * w * np.sin(p)
        # A e^{−t/τ} cos(ωt): derivatives of a damped cosine.
        a, b = -1.0 / self.ts, self.ws
        e = self.as_ * np.exp(a * t)
        c, s = np.cos(b * t), np.sin(b * t)
        th = th + e * c
        thd = thd + e * (a * c - b * s)
        thdd = thdd + e * ((a * a - b * b) * c - 2 * a * b * s)
        return th, thd, thdd


def stand_means(edges, C0, u, rocking, lever_arm_m, latitude, gravity):
    """Interval means of ω_ib^b and f^b over the samples between `edges`."""
    w_ie = kinematics.EARTH_RATE_RAD_S * np.array([math.cos(latitude), 0.0, -math.sin(latitude)])
    g_n = np.array([0.0, 0.0, gravity])
    n = len(edges) - 1
    if rocking.still():
        w, f = C0.T @ w_ie, C0.T @ (-g_n)
        return np.tile(w, (n, 1)), np.tile(f, (n, 1))
    p0 = np.array([0.0, 0.0, -lever_arm_m])

    def integrand(t):
        th, thd, thdd = rocking(t)
        R = axis_rotation(u, th)
        C = R @ C0
        p = R @ p0
        uxp = np.cross(u, p)
        acc = thdd[:, None] * uxp + (thd * thd)[:, None] * np.cross(u, uxp)
        w_n = thd[:, None] * u[None] + w_ie[None]
        w_b = np.einsum("kji,kj->ki", C, w_n)
        f_b = np.einsum("kji,kj->ki", C, acc - g_n[None])
        return np.concatenate([w_b, f_b], axis=1)

    out = np.empty((n, 6))
    chunk = 20000
    for s in range(0, n, chunk):
        e = edges[s:min(n, s + chunk) + 1]
        out[s:s + len(e) - 1] = kinematics.interval_means(e, [], integrand)
    return out[:, :3], out[:, 3:]


def quantise_increments(rng, rates, dt, lsb):
    """Integer counts of `lsb` per sample from a counter of the running
    integral, its turn-on residue uniform; returns the rates (counts·lsb/dt),
    the counts and the residues r₀ (the velocity the counts lose on average,
    q·(½ − r₀), is an initial velocity of up to half a quantum)."""
    residue = rng.random(rates.shape[1])  # r₀ in [0, 1): ⌊r₀⌋ = 0
    totals = np.floor(np.cumsum(rates * dt, axis=0) / lsb + residue[None])
    counts = np.diff(np.vstack([np.zeros((1, rates.shape[1])), totals]), axis=0)
    return counts * lsb / dt, counts, residue


def quantise_rates(rates, lsb):
    counts = np.round(rates / lsb)
    return counts * lsb, counts


def flicker_means(rng, allan_floor, dt_s, n):
    """Interval means of flicker noise whose Allan deviation is flat at
    `allan_floor` between Δt and the log's length (the docstring's sum)."""
    if allan_floor <= 0.0:
        return np.zeros(n)
    h_minus_1 = allan_floor ** 2 / (2.0 * math.log(2.0))
    ratio = math.sqrt(10.0)
    taus = dt_s * ratio ** np.arange(int(math.ceil(math.log(n) / math.log(ratio))) + 1)
    sigma = math.sqrt(h_minus_1 * math.log(ratio))
    return sum(sensors.gauss_markov_means(rng, sigma, float(tau), dt_s, n) for tau in taus)


def draw_turn_on(rng, lo_hi):
    lo, hi = lo_hi
    return [float(rng.choice([-1.0, 1.0]) * rng.uniform(lo, hi)) for _ in AXES]


def simulate_raw(config, parameters, effects, apply_effects):
    """Writes the raw log to config['out'] and its truth; returns the truth.
    `apply_effects(measured, true_input, effects, edges, rng)` adds the
    faults as benchsim.simulate does."""
    rng = np.random.default_rng(config["seed"])
    rate_hz, duration_s = config["rate_hz"], config["duration_s"]
    latitude = config["latitude_deg"] * DEG
    gravity = kinematics.normal_gravity_mps2(latitude, config["height_m"])
    out_class = dict(OUTPUTS[config["preset"]])
    for key in ("gyro_lsb", "acc_lsb"):
        if config.get(key) is not None:
            out_class[key] = config[key]
    output = config.get("raw_output") or out_class["output"]

    # The stand: the draws come first and in a fixed order, so that switching
    # a property off leaves the others' draws as they were.
    tilt = config["tilt_deg"] * DEG
    roll0, pitch0 = rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt)
    heading_draw = rng.uniform(0.0, 2 * math.pi)
    heading = heading_draw if config.get("heading_deg") is None else config["heading_deg"] * DEG
    base = config["orientation"]
    B = rx(ORIENTATIONS[base] * DEG) if base in ORIENTATIONS else \
        rz(base[2] * DEG) @ ry(base[1] * DEG) @ rx(base[0] * DEG)
    C0 = rz(heading) @ ry(pitch0) @ rx(roll0) @ B
    axis_angle = rng.uniform(0.0, 2 * math.pi)
    u = np.array([math.cos(axis_angle), math.sin(axis_angle), 0.0])
    sway_phase = rng.uniform(0.0, 2 * math.pi)
    rocking = Rocking(config["sway_urad"] * 1e-6, config["sway_hz"], sway_phase,
                      config["settle_urad"] * 1e-6, config["settle_hz"], config["settle_tau_s"])
    gyro_turn_on = draw_turn_on(rng, out_class["gyro_turn_on"])
    acc_turn_on = draw_turn_on(rng, out_class["acc_turn_on"])
    if not config["turn_on_biases"]:
        gyro_turn_on, acc_turn_on = [0.0] * 3, [0.0] * 3
    noise_rng = np.random.default_rng([config["seed"], 1])

    n = int(round(duration_s * rate_hz))
    dt = 1.0 / rate_hz
    edges = np.arange(n + 1) * dt
    true_rate, true_force = stand_means(edges, C0, u, rocking, config["lever_arm_m"], latitude, gravity)
    measured = {"gyro": true_rate.copy(), "acc": true_force.copy()}
    for sensor, noise in (("gyro", "gyro_arw"), ("acc", "acc_vrw")):
        for i, a in enumerate(AXES):
            measured[sensor][:, i] += sensors.gauss_markov_means(
                noise_rng, parameters[f"{sensor}_bias_gm.{a}.sigma"], parameters[f"{sensor}_bias_gm.{a}.tau"], dt, n)
            measured[sensor][:, i] += sensors.white_noise(noise_rng, parameters[f"{noise}.{a}"], dt, n)
    flicker_rng = np.random.default_rng([config["seed"], 3])
    warmup_rng = np.random.default_rng([config["seed"], 4])
    for sensor, floor in (("gyro", config.get("gyro_flicker_rad_s", 0.0)), ("acc", config.get("acc_flicker_mps2", 0.0))):
        for i in range(3):
            measured[sensor][:, i] += flicker_means(flicker_rng, floor, dt, n)
    warmup = {"gyro": config.get("warmup_gyro_rad_s", 0.0), "acc": config.get("warmup_acc_mps2", 0.0)}
    warmup_biases = {}
    for sensor in ("gyro", "acc"):
        signs = warmup_rng.choice([-1.0, 1.0], size=3)
        warmup_biases[sensor] = (signs * warmup[sensor]).tolist()
        if warmup[sensor] > 0.0:
            tau = config["warmup_tau_s"]
            # The interval mean of b_w e^{−t/τ} over (t[k−1], t[k]].
            decay = tau * (np.exp(-edges[:-1] / tau) - np.exp(-edges[1:] / tau)) / dt
            measured[sensor] += decay[:, None] * np.array(warmup_biases[sensor])[None]
    measured["gyro"] += np.array(gyro_turn_on)[None]
    measured["acc"] += np.array(acc_turn_on)[None]
    apply_effects(measured, {"gyro": true_rate, "acc": true_force}, effects, edges, noise_rng)

    quantised = config["quantise"]
    q_rng = np.random.default_rng([config["seed"], 2])
    values, residues = {}, {}
    for sensor in ("gyro", "acc"):
        lsb = out_class[f"{sensor}_lsb"]
        if not quantised:
            values[sensor] = measured[sensor] * (dt if output == "increments" else 1.0)
        elif output == "increments":
            _, counts, residue = quantise_increments(q_rng, measured[sensor], dt, lsb)
            values[sensor] = counts * lsb
            residues[sensor] = residue.tolist()
        else:
            values[sensor] = quantise_rates(measured[sensor], lsb)[0]
    times = edges[1:]
    table = np.column_stack([times, values["gyro"], values["acc"]])
    if config["raw_format"] == "f64":
        with open(config["out"], "wb") as f:
            f.write(table.astype("<f8").tobytes())
    else:
        with open(config["out"], "w") as f:
            f.write("# t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z\n")
            np.savetxt(f, table, fmt=["%.6f"] + ["%.17g"] * 6, delimiter=",")

    C_start = axis_rotation(u, np.array([rocking(np.array([0.0]))[0][0]]))[0] @ C0
    r_s, p_s, y_s = (float(v) for v in kinematics.euler_zyx(C_start))
    units = "gyro=rad,acc=m/s" if output == "increments" else "gyro=rad/s,acc=m/s2"
    truth = dict(
        raw_log=True, preset=config["preset"], rate_hz=rate_hz, duration_s=duration_s, seed=config["seed"],
        format=config["raw_format"], output=output, quantised=quantised,
        gyro_lsb=out_class["gyro_lsb"], acc_lsb=out_class["acc_lsb"], counter_residues=residues,
        import_columns="t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z", import_units=units,
        site=[config["latitude_deg"], config["longitude_deg"], config["height_m"]], gravity_mps2=gravity,
        orientation=base, tilt_deg=config["tilt_deg"], roll0_rad=roll0, pitch0_rad=pitch0, heading_rad=heading,
        C0=C0.tolist(), start_rpy_rad=[r_s, p_s, y_s],
        rocking=dict(axis_n=u.tolist(), sway_rad=rocking.aw, sway_hz=config["sway_hz"], sway_phase_rad=sway_phase,
                     settle_rad=rocking.as_, settle_hz=config["settle_hz"], settle_tau_s=config["settle_tau_s"],
                     lever_arm_m=config["lever_arm_m"]),
        flicker=dict(gyro_allan_floor_rad_s=config.get("gyro_flicker_rad_s", 0.0),
                     acc_allan_floor_mps2=config.get("acc_flicker_mps2", 0.0)),
        warmup=dict(gyro_rad_s=warmup_biases["gyro"], acc_mps2=warmup_biases["acc"],
                    tau_s=config.get("warmup_tau_s", 0.0)),
        turn_on_biases={**{f"gyro_turn_on_bias.{a}": gyro_turn_on[i] for i, a in enumerate(AXES)},
                        **{f"acc_turn_on_bias.{a}": acc_turn_on[i] for i, a in enumerate(AXES)}},
        parameters=parameters, effects=effects)
    with open(config["out"] + ".truth.json", "w") as f:
        json.dump(truth, f, indent=1)
    return truth
