#!/usr/bin/python3
"""An independent bench-run simulator: a unit on a rotary table, written from
shared/spec (bench-run format, catalogue of effects) and the physics alone,
to check the insdiag engine on data its own code did not generate.

Usage:
  benchsim.py --out RUN.csv [--preset nav] [--profile positions] [--rate-hz 50]
              [--duration 3600] [--seed 1] [--ramp-accel DEG_S2] [--jitter 1.0]
              [--fault NAME=VALUE[@ONSET_S]]... [--fault PARAM*FACTOR]...
              [--set PARAM=VALUE]... [--datasheet yes|no] [--unit-type INS-2000|none]
              [--serial S]
  benchsim.py --raw-log --out LOG [--preset nav|mems] [--raw-format csv|f64]
              [--raw-output increments|rates] [--quantise yes|no] [--gyro-lsb Q]
              [--acc-lsb Q] [--turn-on-biases yes|no] [--orientation up|side|inverted]
              [--tilt-deg T] [--heading-deg H] [--sway-urad A --sway-hz F]
              [--settle-urad A --settle-hz F --settle-tau-s TAU] [--lever-arm-m L]
              [--gyro-flicker-dph B --acc-flicker-ug B] [--warmup-gyro-dps W --warmup-acc-mg W --warmup-tau-s T]
A raw log is what the unit's own logger writes on a stand (rawlog.py): samples
only, for `insdiag import --attitude level`; its truth says the import's units.
Faults: gyro_bias_step.x=3e-6@1500.3, acc_bias_ramp.y=1e-7@900,
gyro_turn_on_bias.z=1e-6, gyro_scale_factor.x=5e-5 (a family without an axis:
every axis), gyro_bias_rw.y=1e-9 (rate random walk density), and
multipliers of the preset's parameters: gyro_bias_gm.x.sigma*3,
gyro_bias_gm.y.tau*0.1, gyro_arw.z*2. --set gives the unit another class than
the preset's (gyro_bias_gm.x.sigma=4.8e-7, SI units): the datasheet states the
values after --set and before --fault. The truth goes to RUN.csv.truth.json.
"""
import argparse
import json
import math
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kinematics  # noqa: E402
import profiles  # noqa: E402
import rawlog  # noqa: E402

# The standard gravity of the µg and mg the options state (BIPM, SI Brochure, 9th ed., 2019).
STANDARD_GRAVITY_MPS2 = 9.80665
import sensors  # noqa: E402
import unit_classes  # noqa: E402

AXES = unit_classes.AXES
DEG = unit_classes.DEG
PRESETS = unit_classes.PRESETS

FAULT = re.compile(r"^(?P<name>[a-z_]+(\.[xyz])?(\.(sigma|tau))?)(=(?P<value>[^@]+)(@(?P<onset>.+))?|\*(?P<factor>.+))$")


def set_parameters(specs, parameters):
    """The preset's parameters with NAME=VALUE overrides applied."""
    for spec in specs:
        name, eq, value = spec.partition("=")
        if not eq or name not in parameters:
            raise ValueError(f"--set {spec}: expected PARAM=VALUE with a parameter of the preset "
                             f"({', '.join(sorted(parameters))})")
        try:
            parameters[name] = float(value)
        except ValueError:
            raise ValueError(f"--set {spec}: '{value}' is not a number") from None
        if not parameters[name] > 0:
            raise ValueError(f"--set {spec}: must be positive")


def parse_faults(specs, parameters):
    """Effects to inject, and the preset's parameters with multipliers applied."""
    effects = []
    for spec in specs:
        m = FAULT.match(spec)
        if not m:
            raise ValueError(f"--fault {spec}: expected NAME=VALUE[@ONSET_S] or PARAM*FACTOR")
        name = m.group("name")
        if m.group("factor") is not None:
            if name not in parameters:
                raise ValueError(f"--fault {spec}: no parameter '{name}' in the preset")
            parameters[name] *= float(m.group("factor"))
            continue
        family, _, axis = name.partition(".")
        for a in (axis,) if axis else AXES:
            effects.append(dict(family=family, axis=a, value=float(m.group("value")),
                                onset_s=float(m.group("onset")) if m.group("onset") else None))
    return effects


def apply_effects(measured, true_input, effects, edges, rng):
    """Adds the effects to the measured interval means, in place."""
    dt = edges[1] - edges[0]
    n = len(edges) - 1
    for e in effects:
        sensor = "gyro" if e["family"].startswith("gyro") else "acc"
        kind = e["family"].split("_", 1)[1]
        i = AXES.index(e["axis"])
        column = measured[sensor][:, i]
        if kind == "turn_on_bias":
            column += e["value"]
        elif kind == "scale_factor":
            column += e["value"] * true_input[sensor][:, i]
        elif kind == "bias_step":
            column += sensors.step_means(edges, e["onset_s"], e["value"])
        elif kind == "bias_ramp":
            column += sensors.ramp_means(edges, e["onset_s"], e["value"])
        elif kind == "bias_rw":
            column += sensors.random_walk_means(rng, e["value"], dt, n)
        else:
            raise ValueError(f"--fault {e['family']}: this simulator does not inject that family")


def simulate(config):
    """Writes the run to config['out'] and its truth beside it; returns the truth."""
    rng = np.random.default_rng(config["seed"])
    rate_hz, duration_s = config["rate_hz"], config["duration_s"]
    latitude = config["latitude_deg"] * DEG
    gravity = kinematics.normal_gravity_mps2(latitude, config["height_m"])
    parameters = PRESETS[config["preset"]]()
    set_parameters(config["set"], parameters)
    nominal_parameters = dict(parameters)
    effects = parse_faults(config["faults"], parameters)
    yaw, roll = profiles.build(config["profile"], duration_s, rng, config["ramp_accel_deg_s2"], config["jitter_s"])

    n = int(round(duration_s * rate_hz))
    dt = 1.0 / rate_hz
    edges = np.arange(n + 1) * dt  # sample k covers (edges[k], edges[k+1]]
    breakpoints = yaw.breakpoints() + roll.breakpoints()

    def integrand(t):
        w, f, psi = kinematics.true_rates_and_forces(t, yaw, roll, latitude, gravity)
        return np.concatenate([w, f, np.sin(psi)[:, None], np.cos(psi)[:, None]], axis=1)

    means = kinematics.interval_means(edges, breakpoints, integrand)
    true_rate, true_force = means[:, 0:3], means[:, 3:6]

    measured = {"gyro": true_rate.copy(), "acc": true_force.copy()}
    true_input = {"gyro": true_rate, "acc": true_force}
    for sensor, noise in (("gyro", "gyro_arw"), ("acc", "acc_vrw")):
        for i, a in enumerate(AXES):
            measured[sensor][:, i] += sensors.gauss_markov_means(
                rng, parameters[f"{sensor}_bias_gm.{a}.sigma"], parameters[f"{sensor}_bias_gm.{a}.tau"], dt, n)
            measured[sensor][:, i] += sensors.white_noise(rng, parameters[f"{noise}.{a}"], dt, n)
    apply_effects(measured, true_input, effects, edges, rng)

    C = kinematics.body_attitude(*[m.evaluate(edges[1:])[0] for m in (yaw, roll)])
    ref_roll, ref_pitch, ref_yaw = kinematics.euler_zyx(C)
    write_csv(config, nominal_parameters, edges[1:], measured, ref_roll, ref_pitch, ref_yaw)
    truth = dict(preset=config["preset"], profile=config["profile"], rate_hz=rate_hz, duration_s=duration_s,
                 seed=config["seed"], parameters=parameters, effects=effects,
                 ramp_accel_deg_s2=config["ramp_accel_deg_s2"], gravity_mps2=gravity)
    with open(config["out"] + ".truth.json", "w") as f:
        json.dump(truth, f, indent=1)
    return truth


def simulate_raw(config):
    """A raw log (rawlog.py) of the preset's unit with --set and --fault applied."""
    if config["preset"] not in rawlog.OUTPUTS:
        raise ValueError(f"--raw-log: no output class for preset {config['preset']}")
    parameters = PRESETS[config["preset"]]()
    set_parameters(config["set"], parameters)
    effects = parse_faults(config["faults"], parameters)
    return rawlog.simulate_raw(config, parameters, effects, apply_effects)


def write_csv(config, datasheet, times, measured, ref_roll, ref_pitch, ref_yaw):
    lines = ["# format: insdiag-bench-run/1", f"# unit_serial: {config['serial']}"]
    if config["unit_type"] != "none":
        lines.append(f"# unit_type: {config['unit_type']}")
    lines += [f"# site_latitude_deg: {config['latitude_deg']}", f"# site_longitude_deg: {config['longitude_deg']}",
              f"# site_height_m: {config['height_m']}", "# bench: independent simulator (tests/benchsim)"]
    if config["datasheet"] == "yes":
        lines += unit_classes.datasheet_lines(datasheet)
    lines.append("t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw")
    table = np.column_stack([times, measured["gyro"], measured["acc"], ref_roll, ref_pitch, ref_yaw])
    with open(config["out"], "w") as f:
        f.write("\n".join(lines) + "\n")
        write_rows(f, table, ["%.6f"] + ["%.12g"] * 9)


def write_rows(f, table, fmt, rows_per_chunk=20000):
    """The text np.savetxt(f, table, fmt=fmt, delimiter=",") writes, byte for
    byte: each row is `",".join(fmt) % row`, but formatted a chunk of rows at
    a time, not row by row in Python (a third of a 100 Hz run's simulation)."""
    row = ",".join(fmt) + "\n"
    for start in range(0, len(table), rows_per_chunk):
        chunk = table[start:start + rows_per_chunk]
        f.write((row * len(chunk)) % tuple(chunk.ravel().tolist()))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True)
    p.add_argument("--preset", default="nav", choices=sorted(PRESETS))
    p.add_argument("--profile", default="positions", choices=sorted(profiles.PROFILES))
    p.add_argument("--rate-hz", type=float, default=50.0)
    p.add_argument("--duration", type=float, default=3600.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--ramp-accel", type=float, default=None, help="rate changes ramp at this deg/s² (default: steps)")
    p.add_argument("--jitter", type=float, default=1.0, help="holds lengthened by up to this many seconds (seeded)")
    p.add_argument("--fault", action="append", default=[])
    p.add_argument("--set", action="append", default=[], help="a preset parameter's value, PARAM=VALUE (SI)")
    p.add_argument("--datasheet", default="yes", choices=["yes", "no"])
    p.add_argument("--unit-type", default="INS-2000")
    p.add_argument("--serial", default=None)
    p.add_argument("--latitude-deg", type=float, default=48.137)
    p.add_argument("--longitude-deg", type=float, default=11.575)
    p.add_argument("--height-m", type=float, default=519.0)
    r = p.add_argument_group("raw log (rawlog.py): a unit's own logger on a stand, samples only")
    r.add_argument("--raw-log", action="store_true", help="write a raw log (t, gyro xyz, acc xyz), not a bench run")
    r.add_argument("--raw-format", default="csv", choices=["csv", "f64"])
    r.add_argument("--raw-output", default=None, choices=["increments", "rates"],
                   help="default: the preset's (nav and tactical: increments; mems: rates)")
    r.add_argument("--quantise", default="yes", choices=["yes", "no"])
    r.add_argument("--gyro-lsb", type=float, default=None, help="gyro quantum [rad, or rad/s for rates]")
    r.add_argument("--acc-lsb", type=float, default=None, help="accelerometer quantum [m/s, or m/s² for rates]")
    r.add_argument("--turn-on-biases", default="yes", choices=["yes", "no"])
    r.add_argument("--orientation", default="up", help="up, side, inverted or ROLL,PITCH,YAW [deg]")
    r.add_argument("--tilt-deg", type=float, default=1.0, help="roll and pitch drawn within ±this")
    r.add_argument("--heading-deg", type=float, default=None, help="default: drawn over the circle")
    r.add_argument("--sway-urad", type=float, default=0.0)
    r.add_argument("--sway-hz", type=float, default=1.0)
    r.add_argument("--settle-urad", type=float, default=0.0)
    r.add_argument("--settle-hz", type=float, default=2.0)
    r.add_argument("--settle-tau-s", type=float, default=1.0)
    r.add_argument("--lever-arm-m", type=float, default=0.1, help="sensors above the stand's pivot")
    r.add_argument("--gyro-flicker-dph", type=float, default=0.0, help="bias instability: the gyros' Allan floor [°/h]")
    r.add_argument("--acc-flicker-ug", type=float, default=0.0, help="bias instability: the accelerometers' Allan floor [µg]")
    r.add_argument("--warmup-gyro-dps", type=float, default=0.0, help="the gyros' warm-up bias at power-up [°/s]")
    r.add_argument("--warmup-acc-mg", type=float, default=0.0, help="the accelerometers' warm-up bias at power-up [mg]")
    r.add_argument("--warmup-tau-s", type=float, default=600.0, help="the warm-up's time constant [s]")
    a = p.parse_args(argv)
    config = dict(out=a.out, preset=a.preset, profile=a.profile, rate_hz=a.rate_hz, duration_s=a.duration,
                  seed=a.seed, ramp_accel_deg_s2=a.ramp_accel, jitter_s=a.jitter, faults=a.fault, set=a.set,
                  datasheet=a.datasheet, unit_type=a.unit_type, serial=a.serial or f"BSIM-{a.seed}",
                  latitude_deg=a.latitude_deg, longitude_deg=a.longitude_deg, height_m=a.height_m)
    if a.raw_log:
        orientation = a.orientation
        if orientation not in rawlog.ORIENTATIONS:
            try:
                orientation = tuple(float(v) for v in orientation.split(","))
                assert len(orientation) == 3
            except (ValueError, AssertionError):
                print(f"benchsim: --orientation {a.orientation}: expected up, side, inverted or ROLL,PITCH,YAW",
                      file=sys.stderr)
                return 2
        config.update(raw_format=a.raw_format, raw_output=a.raw_output, quantise=a.quantise == "yes",
                      gyro_lsb=a.gyro_lsb, acc_lsb=a.acc_lsb, turn_on_biases=a.turn_on_biases == "yes",
                      orientation=orientation, tilt_deg=a.tilt_deg, heading_deg=a.heading_deg,
                      sway_urad=a.sway_urad, sway_hz=a.sway_hz, settle_urad=a.settle_urad, settle_hz=a.settle_hz,
                      settle_tau_s=a.settle_tau_s, lever_arm_m=a.lever_arm_m,
                      gyro_flicker_rad_s=a.gyro_flicker_dph * math.pi / 180.0 / 3600.0,
                      acc_flicker_mps2=a.acc_flicker_ug * 1e-6 * STANDARD_GRAVITY_MPS2,
                      warmup_gyro_rad_s=a.warmup_gyro_dps * math.pi / 180.0,
                      warmup_acc_mps2=a.warmup_acc_mg * 1e-3 * STANDARD_GRAVITY_MPS2, warmup_tau_s=a.warmup_tau_s)
    try:
        if a.raw_log:
            simulate_raw(config)
        else:
            simulate(config)
    except ValueError as e:
        print(f"benchsim: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
