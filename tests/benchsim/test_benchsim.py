"""Self-tests of the independent bench-run simulator against the physics."""
import contextlib
import io
import json
import math
from decimal import Decimal, getcontext
import os
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchsim  # noqa: E402
import kinematics  # noqa: E402
import rawlog  # noqa: E402
import sensors  # noqa: E402

DEG = math.pi / 180.0


def so3_log(R):
    angle = math.acos(max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0)))
    if angle < 1e-12:
        return np.zeros(3)
    return angle / (2.0 * math.sin(angle)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def motion_with_step_mid_sample():
    yaw, roll = kinematics.AxisMotion(), kinematics.AxisMotion()
    roll.add_piece(0.0, 0.0, 0.0)
    roll.add_piece(0.3, 0.0, 0.0)
    roll.add_piece(0.5, 0.0, 0.0)  # still roll at 0: yaw starts inside a sample
    yaw.add_piece(1.037, 10.0 * DEG, 0.0)  # a rate step at 1.037 s
    yaw.add_piece(2.0, 0.0, 20.0 * DEG, keep_rate=True)  # then a ramp
    roll.add_piece(2.6, 5.0 * DEG, 0.0)
    return yaw, roll


class Kinematics(unittest.TestCase):
    def test_body_rate_is_the_derivative_of_the_attitude(self):
        yaw, roll = motion_with_step_mid_sample()
        latitude = 48.0 * DEG
        for t in (1.5, 2.3, 2.9):
            h = 1e-6
            C = kinematics.body_attitude(*[np.array([m.evaluate([t])[0][0]]) for m in (yaw, roll)])[0]
            C2 = kinematics.body_attitude(*[np.array([m.evaluate([t + h])[0][0]]) for m in (yaw, roll)])[0]
            w_nb = so3_log(C.T @ C2) / h
            w_ib, _, _ = kinematics.true_rates_and_forces(np.array([t + h / 2]), yaw, roll, latitude, 9.8)
            w_ie = kinematics.EARTH_RATE_RAD_S * np.array([math.cos(latitude), 0.0, -math.sin(latitude)])
            np.testing.assert_allclose(w_ib[0] - C.T @ w_ie, w_nb, atol=1e-6)

    def test_interval_means_match_a_fine_integral_across_steps_and_ramps(self):
        yaw, roll = motion_with_step_mid_sample()
        edges = np.arange(0.0, 3.01, 0.1)

        def integrand(t):
            w, f, _ = kinematics.true_rates_and_forces(t, yaw, roll, 0.8, 9.8)
            return np.concatenate([w, f], axis=1)

        means = kinematics.interval_means(edges, yaw.breakpoints() + roll.breakpoints(), integrand)
        for k in (10, 20, 26):  # the rate step, the ramp's start, the roll's start
            fine = np.linspace(edges[k], edges[k + 1], 200001)
            values = integrand(fine)
            brute = np.trapz(values, fine, axis=0) / (edges[k + 1] - edges[k])
            # The trapezoid's own error at a rate step is jump·h/2 per interval (≈ 4e-7 here).
            np.testing.assert_allclose(means[k], brute, rtol=0, atol=1e-6)
        # The step's interval exactly: 10 °/s over the 63 ms after 1.037 s, plus the Earth's rate.
        earth_z = -kinematics.EARTH_RATE_RAD_S * math.sin(0.8)
        self.assertAlmostEqual(means[10][2], 10.0 * DEG * 0.63 + earth_z, places=12)
        # Inside the ramp (no breakpoint): the trapezoid is exact to its h², so 1e-9 holds.
        k = 22
        fine = np.linspace(edges[k], edges[k + 1], 20001)
        brute = np.trapz(integrand(fine), fine, axis=0) / (edges[k + 1] - edges[k])
        np.testing.assert_allclose(means[k], brute, rtol=0, atol=1e-9)

    def test_a_still_level_unit_senses_gravity_and_the_earth_rate(self):
        yaw, roll = kinematics.AxisMotion(), kinematics.AxisMotion()
        g = kinematics.normal_gravity_mps2(0.7, 100.0)
        w, f, _ = kinematics.true_rates_and_forces(np.array([5.0]), yaw, roll, 0.7, g)
        np.testing.assert_allclose(f[0], [0.0, 0.0, -g], atol=1e-12)
        np.testing.assert_allclose(w[0], kinematics.EARTH_RATE_RAD_S * np.array([math.cos(0.7), 0, -math.sin(0.7)]),
                                   atol=1e-18)
        self.assertAlmostEqual(kinematics.normal_gravity_mps2(0.0, 0.0), 9.7803253359, places=9)


class SensorErrors(unittest.TestCase):
    def test_gauss_markov_interval_means_have_the_variance_of_a_time_average(self):
        # Var of the mean of a stationary OU over Δ: 2σ²/(βΔ)² (βΔ − 1 + e^{−βΔ}).
        rng = np.random.default_rng(4)
        sigma, tau, dt, n = 2.0, 1.0, 0.5, 400000
        means = sensors.gauss_markov_means(rng, sigma, tau, dt, n)
        x = dt / tau
        expected = 2.0 * sigma ** 2 / x ** 2 * (x - 1.0 + math.exp(-x))
        # Effective samples ≈ n·Δ/(2τ): a 5σ bound on the relative error of the variance.
        tolerance = 5.0 * math.sqrt(2.0 / (n * dt / (2.0 * tau)))
        self.assertLess(abs(np.var(means) / expected - 1.0), tolerance)
        # Lag-one covariance of the means: σ² (1 − e^{−x})² e^{0}/x² for adjacent intervals.
        lag1 = np.mean((means[1:] - means.mean()) * (means[:-1] - means.mean()))
        expected_lag1 = sigma ** 2 * (1.0 - math.exp(-x)) ** 2 / x ** 2
        self.assertLess(abs(lag1 / expected_lag1 - 1.0), 2 * tolerance)

    def test_gauss_markov_interval_covariance_keeps_its_digits_at_high_rates(self):
        # Against the header's formulas in 60-digit arithmetic: a 30-minute τ
        # at 200 Hz made Var v negative in double precision.
        getcontext().prec = 60
        for tau, dt in ((1800.0, 0.005), (1800.0, 0.01), (300.0, 0.02), (100.0, 0.1), (1.0, 0.5), (1.0, 20.0)):
            _, var_w, cov, var_v = sensors.gauss_markov_interval_covariance(1.0, tau, dt)
            beta, q2, phi = 1 / Decimal(tau), 2 / Decimal(tau), (-Decimal(dt) / Decimal(tau)).exp()
            exact_cov = q2 / beta * ((1 - phi) / beta - (1 - phi * phi) / (2 * beta))
            exact_var_v = q2 / beta ** 2 * (Decimal(dt) - 2 * (1 - phi) / beta + (1 - phi * phi) / (2 * beta))
            self.assertAlmostEqual(cov / float(exact_cov), 1.0, delta=1e-9, msg=(tau, dt))
            self.assertAlmostEqual(var_v / float(exact_var_v), 1.0, delta=1e-9, msg=(tau, dt))
            self.assertGreater(var_w * var_v, cov * cov, msg=(tau, dt))

    def test_random_walk_means_grow_as_the_walk(self):
        rng = np.random.default_rng(5)
        walks = np.array([sensors.random_walk_means(rng, 0.1, 1.0, 100)[-1] for _ in range(4000)])
        # The last interval's mean of a walk from zero: Var = K²(t_{n−1} + Δ/3).
        expected = 0.01 * (99.0 + 1.0 / 3.0)
        self.assertLess(abs(np.var(walks) / expected - 1.0), 5.0 * math.sqrt(2.0 / 4000))

    def test_steps_and_ramps_count_the_share_of_the_sample_after_their_onset(self):
        edges = np.array([0.0, 1.0, 2.0, 3.0])
        np.testing.assert_allclose(sensors.step_means(edges, 1.25, 2.0), [0.0, 1.5, 2.0])
        np.testing.assert_allclose(sensors.ramp_means(edges, 1.5, 1.0), [0.0, 0.125, 1.0])


class Files(unittest.TestCase):
    def run_sim(self, directory, *extra):
        out = os.path.join(directory, "run.csv")
        args = ["--out", out, "--profile", "mixed", "--rate-hz", "10", "--duration", "600", "--seed", "9", *extra]
        self.assertEqual(benchsim.main(args), 0)
        return out

    def test_the_file_has_the_format_and_the_same_seed_the_same_bytes(self):
        with tempfile.TemporaryDirectory() as d1, tempfile.TemporaryDirectory() as d2:
            a = self.run_sim(d1, "--fault", "gyro_bias_step.x=1e-6@300.37")
            b = self.run_sim(d2, "--fault", "gyro_bias_step.x=1e-6@300.37")
            with open(a, "rb") as fa, open(b, "rb") as fb:
                self.assertEqual(fa.read(), fb.read())
            with open(a) as f:
                lines = f.read().splitlines()
            self.assertEqual(lines[0], "# format: insdiag-bench-run/1")
            header = next(line for line in lines if not line.startswith("#"))
            self.assertEqual(header, "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw")
            data = np.loadtxt(a, delimiter=",", comments="#", skiprows=lines.index(header) + 1)
            self.assertEqual(data.shape, (6000, 10))
            self.assertTrue(np.all(np.diff(data[:, 0]) > 0))
            g = np.linalg.norm(data[:10, 4:7], axis=1).mean()
            self.assertLess(abs(g - 9.808), 0.01)
            self.assertTrue(os.path.exists(a + ".truth.json"))

    def test_set_gives_the_unit_another_class_and_its_datasheet_states_it(self):
        with tempfile.TemporaryDirectory() as d:
            sets = [f"--set=gyro_bias_gm.{a}.sigma=4.8e-7" for a in "xyz"]
            out = self.run_sim(d, *sets, "--set=gyro_bias_gm.x.tau=200", "--fault", "gyro_bias_gm.y.sigma*3")
            with open(out) as f:
                metadata = dict(line[2:].split(": ", 1) for line in f.read().splitlines() if line.startswith("# "))
            # The datasheet states the class (after --set), not the fault (--fault).
            self.assertAlmostEqual(float(metadata["gyro_bias_sigma"]), 4.8e-7)
            with open(out + ".truth.json") as f:
                truth = json.load(f)["parameters"]
            self.assertAlmostEqual(truth["gyro_bias_gm.y.sigma"], 3 * 4.8e-7)
            self.assertEqual(truth["gyro_bias_gm.x.tau"], 200.0)

    def test_a_bad_set_is_refused_naming_it(self):
        for bad in ("gyro_bias_gm.w.sigma=1", "gyro_arw.x=abc", "gyro_arw.x=-1", "gyro_arw.x"):
            with self.subTest(bad=bad), tempfile.TemporaryDirectory() as d:
                with contextlib.redirect_stderr(io.StringIO()) as err:
                    code = benchsim.main(["--out", os.path.join(d, "run.csv"), "--duration", "60", f"--set={bad}"])
                self.assertEqual(code, 2)
                self.assertIn(f"--set {bad}", err.getvalue())


def allan_variance(rates, dt, m):
    """Overlapping Allan variance of a rate series at τ = m·Δt (IEEE Std 952, eq. C.4)."""
    theta = np.concatenate([[0.0], np.cumsum(rates) * dt])
    tau = m * dt
    d = theta[2 * m:] - 2.0 * theta[m:-m] + theta[:-2 * m]
    return np.mean(d * d) / (2.0 * tau * tau)


class RawLogs(unittest.TestCase):
    """The raw logs of rawlog.py: samples only, quantised, tilted, turn-on biases."""

    def raw(self, directory, *extra, name="raw.csv"):
        out = os.path.join(directory, name)
        self.assertEqual(benchsim.main(["--raw-log", "--out", out, *extra]), 0)
        with open(out + ".truth.json") as f:
            truth = json.load(f)
        if truth["format"] == "f64":
            data = np.fromfile(out, dtype="<f8").reshape(-1, 7)
        else:
            data = np.loadtxt(out, delimiter=",", comments="#")
        return data, truth

    def test_a_raw_log_holds_samples_only_and_the_same_seed_the_same_bytes(self):
        with tempfile.TemporaryDirectory() as d:
            args = ["--preset", "nav", "--rate-hz", "64", "--duration", "30", "--seed", "3", "--sway-urad", "50",
                    "--settle-urad", "500"]
            a, truth = self.raw(d, *args, name="a.csv")
            b, _ = self.raw(d, *args, name="b.csv")
            with open(os.path.join(d, "a.csv"), "rb") as fa, open(os.path.join(d, "b.csv"), "rb") as fb:
                self.assertEqual(fa.read(), fb.read())
            with open(os.path.join(d, "a.csv")) as f:
                self.assertEqual(f.readline().strip(), "# t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z")
            self.assertEqual(a.shape, (30 * 64, 7))
            np.testing.assert_allclose(a[:, 0], np.arange(1, 30 * 64 + 1) / 64.0, atol=1e-6)
            self.assertEqual(truth["import_units"], "gyro=rad,acc=m/s")
            f64, _ = self.raw(d, *args, "--raw-format", "f64", name="c.bin")
            np.testing.assert_allclose(f64[:, 1:], a[:, 1:], rtol=1e-15, atol=0)

    def test_increments_are_integer_counts_whose_sum_stays_within_one_count_of_the_angle(self):
        with tempfile.TemporaryDirectory() as d:
            q, truth = self.raw(d, "--preset", "nav", "--rate-hz", "64", "--duration", "120", "--seed", "5",
                                "--turn-on-biases", "no", name="q.csv")
            u, _ = self.raw(d, "--preset", "nav", "--rate-hz", "64", "--duration", "120", "--seed", "5",
                            "--turn-on-biases", "no", "--quantise", "no", name="u.csv")
        for col, lsb in ((1, truth["gyro_lsb"]), (2, truth["gyro_lsb"]), (3, truth["gyro_lsb"]),
                         (4, truth["acc_lsb"]), (5, truth["acc_lsb"]), (6, truth["acc_lsb"])):
            counts = q[:, col] / lsb
            np.testing.assert_allclose(counts, np.round(counts), rtol=0, atol=1e-6)
            # The counter's error does not accumulate: Σ counts·q − Θ stays within one quantum.
            gap = np.cumsum(q[:, col]) - np.cumsum(u[:, col])
            self.assertLess(np.max(np.abs(gap)), lsb * (1 + 1e-6), col)
            self.assertGreater(np.max(np.abs(gap)), 0.5 * lsb, col)

    def test_counting_quantisation_adds_q_over_2_tau_to_the_allan_deviation(self):
        # IEEE Std 952, annex C.2: σ²(τ) = 3Q²/τ² with Q = q/√12, i.e. q²/(4τ²), when
        # the angle passes through the quanta at random (here noise of one q a sample).
        rng = np.random.default_rng(11)
        dt, q, n = 0.01, 1e-6, 400000
        rates = rng.standard_normal((n, 1)) * q / dt
        quantised, counts, _ = rawlog.quantise_increments(rng, rates, dt, q)
        np.testing.assert_array_equal(counts, np.round(counts))
        for m in (1, 2, 4, 8, 32):
            expected = q * q / (4.0 * (m * dt) ** 2)
            # The quantisation error's own Allan variance (its estimate's σ ≈ 1 % at m = 32) …
            error = allan_variance(quantised[:, 0] - rates[:, 0], dt, m)
            self.assertAlmostEqual(error / expected, 1.0, delta=0.05, msg=m)
            # … and it adds to the input's, uncorrelated with it.
            excess = allan_variance(quantised[:, 0], dt, m) - allan_variance(rates[:, 0], dt, m)
            self.assertAlmostEqual(excess / expected, 1.0, delta=0.1 * m ** 0.5, msg=m)
        # The signature: σ(τ) ∝ 1/τ where quantisation dominates (no noise: the Earth's
        # rate through the quanta), against 1/√τ for white noise.
        slow = np.full((n, 1), 7.3e-5 * 0.7)
        coarse, _, _ = rawlog.quantise_increments(rng, slow + rng.standard_normal((n, 1)) * 1e-3 * q / dt, dt, q)
        a1, a10 = (math.sqrt(allan_variance(coarse[:, 0], dt, m)) for m in (10, 100))
        self.assertAlmostEqual(math.log10(a1 / a10), 1.0, delta=0.15)

    def test_mems_rates_are_integer_lsbs_with_the_variance_of_rounding(self):
        with tempfile.TemporaryDirectory() as d:
            q, truth = self.raw(d, "--preset", "mems", "--rate-hz", "100", "--duration", "60", "--seed", "6",
                                name="q.csv")
            u, _ = self.raw(d, "--preset", "mems", "--rate-hz", "100", "--duration", "60", "--seed", "6",
                            "--quantise", "no", name="u.csv")
        self.assertEqual(truth["output"], "rates")
        self.assertEqual(truth["import_units"], "gyro=rad/s,acc=m/s2")
        for col, lsb in ((1, truth["gyro_lsb"]), (4, truth["acc_lsb"])):
            counts = q[:, col] / lsb
            np.testing.assert_allclose(counts, np.round(counts), rtol=0, atol=1e-6)
            error = q[:, col] - u[:, col]
            self.assertLessEqual(np.max(np.abs(error)), 0.5 * lsb * (1 + 1e-9))
            # Rounding under noise of several LSB: a uniform error, variance q²/12 (5σ of 6000 draws).
            self.assertAlmostEqual(np.var(error) / (lsb * lsb / 12.0), 1.0, delta=5 * math.sqrt(0.8 / 6000))

    def test_the_tilt_and_heading_are_what_the_specific_force_and_earth_rate_say(self):
        with tempfile.TemporaryDirectory() as d:
            for orientation, tilt in (("up", 2.0), ("side", 0.5), ("inverted", 0.2)):
                data, truth = self.raw(d, "--preset", "nav", "--rate-hz", "64", "--duration", "60", "--seed", "8",
                                       "--orientation", orientation, "--tilt-deg", str(tilt), "--quantise", "no",
                                       "--turn-on-biases", "no", name=f"{orientation}.csv")
                with self.subTest(orientation=orientation):
                    C0 = np.array(truth["C0"])
                    self.assertLessEqual(max(abs(truth["roll0_rad"]), abs(truth["pitch0_rad"])), tilt * DEG)
                    force = data[:, 4:7].sum(axis=0) / 60.0
                    g = truth["gravity_mps2"]
                    # f^b = C₀ᵀ(−g^n): the body's down axis is −f/|f|, within the drift's 30 µg (3e-5 rad).
                    np.testing.assert_allclose(-force / np.linalg.norm(force), C0[2], atol=1e-4)
                    self.assertAlmostEqual(np.linalg.norm(force), g, delta=1e-3)
                    roll, pitch, _ = kinematics.euler_zyx(C0)
                    base = {"up": 0.0, "side": 90.0, "inverted": 180.0}[orientation] * DEG
                    self.assertLess(abs(math.remainder(float(roll) - base, 2 * math.pi)), tilt * DEG * 1.5)
                    self.assertLess(abs(float(pitch)), tilt * DEG * 1.5)
                    # The Earth's rate: C₀ᵀ ω_ie^n within the ARW over a minute (8e-8 rad/s).
                    lat = 48.137 * DEG
                    w_ie = kinematics.EARTH_RATE_RAD_S * np.array([math.cos(lat), 0.0, -math.sin(lat)])
                    np.testing.assert_allclose(data[:, 1:4].sum(axis=0) / 60.0, C0.T @ w_ie, atol=6e-7)

    def test_rocking_turns_the_unit_by_its_angle_and_its_lever_arm_moves_the_force(self):
        with tempfile.TemporaryDirectory() as d:
            data, truth = self.raw(d, "--preset", "nav", "--rate-hz", "100", "--duration", "20", "--seed", "9",
                                   "--quantise", "no", "--turn-on-biases", "no", "--tilt-deg", "0",
                                   "--settle-urad", "2000", "--settle-hz", "3", "--settle-tau-s", "1",
                                   "--sway-urad", "100", "--sway-hz", "0.5", "--lever-arm-m", "0.2")
        rocking = rawlog.Rocking(1e-4, 0.5, truth["rocking"]["sway_phase_rad"], 2e-3, 3.0, 1.0)
        C0, u = np.array(truth["C0"]), np.array(truth["rocking"]["axis_n"])
        t = data[:, 0]
        # The gyros' summed increments about the rocking axis: θ(t) − θ(0), plus the Earth's rate.
        axis_b = C0.T @ u
        turned = np.cumsum(data[:, 1:4] @ axis_b)  # increments [rad]
        lat = 48.137 * DEG
        earth = kinematics.EARTH_RATE_RAD_S * np.array([math.cos(lat), 0.0, -math.sin(lat)]) @ u
        expected = rocking(t)[0] - rocking(np.array([0.0]))[0][0] + earth * t
        np.testing.assert_allclose(turned, expected, atol=2e-6)
        # The settling's first swing: 2 mrad · (2π·3 Hz)² · 0.2 m ≈ 0.14 m/s² across the axis.
        force = data[:, 4:7] * 100.0  # increments [m/s] over 10 ms
        peak = np.max(np.abs(force[:100, :2] - force[-100:, :2].mean(axis=0)))
        self.assertGreater(peak, 0.05)
        self.assertLess(peak, 0.2)

    def test_mems_turn_on_biases_are_of_their_size_and_in_the_samples(self):
        sizes = []
        with tempfile.TemporaryDirectory() as d:
            for seed in range(1, 9):
                data, truth = self.raw(d, "--preset", "mems", "--rate-hz", "100", "--duration", "30",
                                       "--seed", str(seed), "--tilt-deg", "0", "--heading-deg", "0",
                                       name=f"m{seed}.csv")
                lat = 48.137 * DEG
                w_ie = kinematics.EARTH_RATE_RAD_S * np.array([math.cos(lat), 0.0, -math.sin(lat)])
                mean = data[:, 1:4].mean(axis=0) - np.array(truth["C0"]).T @ w_ie
                biases = np.array([truth["turn_on_biases"][f"gyro_turn_on_bias.{a}"] for a in "xyz"])
                # The mean over 30 s: the ARW's 0.005 °/√s gives 1e-3 °/s, the 100-s Gauss–Markov
                # drift's 10 °/h (0.003 °/s); 0.015 °/s is five of their σ, a tenth of the smallest bias.
                np.testing.assert_allclose(mean, biases, atol=0.015 * DEG)
                sizes += list(np.abs(biases) / DEG)
                acc = np.array([truth["turn_on_biases"][f"acc_turn_on_bias.{a}"] for a in "xyz"])
                self.assertTrue(np.all((np.abs(acc) >= 5e-3 * 9.80665) & (np.abs(acc) <= 50e-3 * 9.80665)))
        self.assertGreaterEqual(min(sizes), 0.1)
        self.assertLessEqual(max(sizes), 0.5)
        self.assertGreater(max(sizes) - min(sizes), 0.2)  # spread over the range, not one value


if __name__ == "__main__":
    unittest.main()
