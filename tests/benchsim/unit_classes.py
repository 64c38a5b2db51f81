"""The classes of unit the independent simulator draws (its presets), and the
datasheet a bench-run file states for one: one home for both, read by
benchsim.py and by the sweeps in scripts/, which give the same classes to the
project's simulator as parameters. Plain Python (no numpy), so that any
interpreter can import it."""
import json
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
AXES = "xyz"
DEG = math.pi / 180.0
MICRO_G = 9.80665e-6


def nav_preset():
    """The INS-2000 nominal values (data/unit-types/INS-2000.json)."""
    with open(os.path.join(ROOT, "data", "unit-types", "INS-2000.json")) as f:
        nominal = {p["name"]: p["value"] for p in json.load(f)["nominal"]}
    preset = {}
    for sensor, noise in (("gyro", "gyro_arw"), ("acc", "acc_vrw")):
        for a in AXES:
            preset[f"{sensor}_bias_gm.{a}.sigma"] = nominal[f"{sensor}_bias_gm.{a}.sigma"]
            preset[f"{sensor}_bias_gm.{a}.tau"] = nominal[f"{sensor}_bias_gm.{a}.tau"]
            preset[f"{noise}.{a}"] = nominal[f"{noise}.{a}"]
    return preset


def uniform_preset(gyro_sigma, gyro_tau, arw, acc_sigma, acc_tau, vrw):
    """Every axis alike (SI: rad/s, s, rad/√s, m/s², s, m/s²/√Hz)."""
    p = {}
    for a in AXES:
        p.update({f"gyro_bias_gm.{a}.sigma": gyro_sigma, f"gyro_bias_gm.{a}.tau": gyro_tau, f"gyro_arw.{a}": arw,
                  f"acc_bias_gm.{a}.sigma": acc_sigma, f"acc_bias_gm.{a}.tau": acc_tau, f"acc_vrw.{a}": vrw})
    return p


PRESETS = {
    "nav": nav_preset,
    "tactical": lambda: uniform_preset(1.0 * DEG / 3600, 300.0, 0.1 * DEG / 60, 1000 * MICRO_G, 300.0, 50 * MICRO_G),
    # The drift of the unit in issue 17's bias-step report (0.1 °/h, τ 200 s).
    "tactical-0.1": lambda: uniform_preset(0.1 * DEG / 3600, 200.0, 0.01 * DEG / 60, 50 * MICRO_G, 300.0,
                                           20 * MICRO_G),
    "mems": lambda: uniform_preset(10.0 * DEG / 3600, 100.0, 0.3 * DEG / 60, 500 * MICRO_G, 100.0, 100 * MICRO_G),
}


def datasheet_lines(parameters):
    """The bench-run format's datasheet keys for a class: the axes' mean noise
    and τ, and the RMS of their drift σ."""
    mean = lambda key: sum(parameters[f"{key}.{a}"] for a in AXES) / len(AXES)
    rms = lambda key: math.sqrt(sum(parameters[f"{key}.{a}.sigma"] ** 2 for a in AXES) / len(AXES))
    tau = lambda key: sum(parameters[f"{key}.{a}.tau"] for a in AXES) / len(AXES)
    return [f"# gyro_arw: {mean('gyro_arw'):.12g}", f"# gyro_bias_sigma: {rms('gyro_bias_gm'):.12g}",
            f"# gyro_bias_tau: {tau('gyro_bias_gm'):.12g}", f"# acc_vrw: {mean('acc_vrw'):.12g}",
            f"# acc_bias_sigma: {rms('acc_bias_gm'):.12g}", f"# acc_bias_tau: {tau('acc_bias_gm'):.12g}"]
