#!/usr/bin/python3
"""The importers on real samples, checked against numpy (importers_real_test).

The real ring-laser-gyro record (data/real/rlg-static-psins.imu, the PSINS
toolbox's SIMU layout) is read here with numpy, independently of the C++:
its counts become body-axis rates by the header's scales and the interval.
The same samples are re-encoded in two more layouts — NovAtel RAWIMUSA
records (their CRC from zlib, other logs interleaved) and little-endian
binary records — because no real RAWIMUSA series with a licence that allows
it was found (docs/IMPORT.md, "Real data"). `insdiag import` turns each into a
bench run, and then:

  1. every imported sample equals numpy's conversion within 1e-8 of the
     channel's largest value (the writer's round trip, and the 5.8e-11 s
     resolution of RAWIMUSA's 2.6e5-s times);
  2. `insdiag analyze --allan` on the PSINS and RAWIMUSA imports gives the
     overlapping Allan deviation numpy computes from the raw counts, at every
     cluster time the engine reports, within a relative 1e-8 (the differences
     are printed). The analysis repairs the samples it reports as spikes
     (OUTLIER intervals of the sensor channels) with the median of their
     eleven neighbours (engine/include/insdiag/engine/monitor/sample_screening.h);
     numpy applies the same repair to the samples the report names, and the
     difference without it is printed too. Where the report's Allan curve
     names a jump of the channel's mean (`jumpTimesS`), numpy pools the
     pieces between the jumps, as the engine does (allan.h, "Jumps").
  3. A record a NovAtel receiver wrote (data/real/novatel-rawimusxa-edie.asc:
     one RAWIMUSXA record, MIT licence, data/real/README.md) through the
     novatel-rawimusxa preset: its CRC checked by zlib here, its sample equal
     to numpy's conversion of its counts within 1e-8 (the interval from
     4.8e5-s times, as in 1.), and its specific force gravity's size and
     pointing down (body z). One record has no Allan curve.

Usage: import_real_check.py INSDIAG_BINARY SOURCE_DIR WORK_DIR
Exit status 0 when every check holds.
"""
import json
import math
import os
import subprocess
import sys
import zlib

import numpy as np

ARCSEC_RAD = math.pi / 180 / 3600
CHANNELS = ["gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"]


def read_psins(path):
    """Header numbers and counts of a PSINS SIMU log."""
    header, rows = [], []
    with open(path, encoding="ascii") as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("%"):
                continue
            values = [float(v) for v in line.split()]
            if len(header) < 3:
                header.append(values)
            else:
                rows.append(values)
    return header, np.array(rows)


def body_rates(header, counts):
    """Counts (X-right, Y-forward, Z-up) to body rates (x-forward, y-right, z-down)."""
    dt = header[1][4] * 1e-3
    g = header[1][5]
    gyro = counts[:, 0:3] * np.array(header[2][0:3]) * ARCSEC_RAD / dt
    acc = counts[:, 3:6] * np.array(header[2][3:6]) * 1e-6 * g / dt
    turn = lambda v: np.column_stack([v[:, 1], v[:, 0], -v[:, 2]])
    return turn(gyro), turn(acc), dt


def write_rawimusa(path, counts, dt):
    """NovAtel short ASCII RAWIMUSA: z acc, -y acc, x acc, z gyro, -y gyro, x gyro."""
    week, sow0 = 2336, 259200.0
    with open(path, "w", encoding="ascii") as f:
        for k, c in enumerate(counts.astype(np.int64)):
            sow = sow0 + (k + 1) * dt
            body = "RAWIMUSA,%d,%.3f;%d,%.9f,00000077,%d,%d,%d,%d,%d,%d" % (
                week, sow, week, sow, c[5], -c[4], c[3], c[2], -c[1], c[0])
            crc = (zlib.crc32(body.encode(), 0xFFFFFFFF) ^ 0xFFFFFFFF) & 0xFFFFFFFF
            f.write("%%%s*%08x\n" % (body, crc))
            if k % 1000 == 0:  # another log of the same receiver, to be skipped
                f.write("#BESTPOSA,COM1,0,80.0,FINESTEERING,%d,%.3f,00000000,0000,0;SOL_COMPUTED*00000000\n" % (week, sow))


def write_binary(path, counts, dt):
    """A 32-byte header, then per record: f64 time, six i32 counts (the
    bytes struct.pack("<d6i", …) gives a record, written in one go)."""
    records = np.empty(len(counts), dtype=[("t", "<f8"), ("counts", "<i4", (6,))])
    records["t"] = np.arange(1, len(counts) + 1) * dt
    records["counts"] = counts.astype(np.int64)
    with open(path, "wb") as f:
        f.write(b"IMU-LOG\0" + bytes(24))
        f.write(records.tobytes())


def read_run(path):
    """The samples' first seven columns (t and the six sensors), parsed by
    numpy's reader: the metadata lines (#) and the column header (t,) skipped."""
    return np.loadtxt(path, delimiter=",", comments=("#", "t,"), usecols=range(7), ndmin=2, encoding="utf-8")


# θ of each piece of a series, computed once for all its cluster times: the
# key is the series (its identity: the arrays live as long as the check) and
# the piece.
_THETA = {}


def integrated(rate, tau0, key):
    """θ = [0, cumsum(rate·τ₀)] in long double, cached under `key`."""
    if key is None or key not in _THETA:
        theta = np.concatenate([[0.0], np.cumsum(rate.astype(np.longdouble) * tau0)])
        if key is None:
            return theta
        _THETA[key] = (rate, theta)  # the series kept alive with its θ, so that its id stays its own
    return _THETA[key][1]


def squared_differences(rate, tau0, m, key=None):
    """Σ D_m(k)² over the overlapping second differences of θ, and their count."""
    theta = integrated(rate, tau0, key)
    n = len(theta)
    if n - 2 * m < 1:
        return 0.0, 0
    d = theta[2 * m:] - 2 * theta[m:n - m] + theta[:n - 2 * m]
    return np.sum(d * d), n - 2 * m


def adev(rate, tau0, m, times, jumps):
    """Overlapping Allan deviation (IEEE Std 952 Annex C; NIST SP 1065 eq. 14),
    over the pieces between the jumps the report cut the channel at (each
    jump time the end of the last sample before it), their second differences
    pooled as the engine pools segments."""
    cuts = [0] + [int(np.searchsorted(times, t, side="right")) for t in sorted(jumps)] + [len(rate)]
    total, count = 0.0, 0
    for a, b in zip(cuts[:-1], cuts[1:]):
        piece_total, piece_count = squared_differences(rate[a:b], tau0, m, key=(id(rate), a, b, tau0))
        if piece_count > 0:
            total += piece_total
            count += piece_count
    return float(np.sqrt(total / (2.0 * (m * tau0) ** 2 * count)))


def repaired(rate, times, intervals, half_window=5):
    """The samples inside the report's OUTLIER intervals, each replaced by the
    median of its 2w+1 neighbours in the recorded series."""
    out = rate.copy()
    for start, end in intervals:
        for k in np.nonzero((times >= start - 1e-9) & (times <= end + 1e-9))[0]:
            if half_window <= k < len(rate) - half_window:
                out[k] = np.median(rate[k - half_window:k + half_window + 1])
    return out


def run(cmd):
    result = subprocess.run(cmd, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit("failed: %s\n%s%s" % (" ".join(cmd), result.stdout, result.stderr))
    return result.stdout


def main():
    insdiag, source, work = sys.argv[1:4]
    os.makedirs(work, exist_ok=True)
    imu = os.path.join(source, "data/real/rlg-static-psins.imu")
    header, counts = read_psins(imu)
    gyro, acc, dt = body_rates(header, counts)
    raw_path, bin_path = os.path.join(work, "rlg.rawimusa"), os.path.join(work, "rlg.bin")
    write_rawimusa(raw_path, counts, dt)
    write_binary(bin_path, counts, dt)
    common = ["--serial", "PSINS-RLG-2014"]
    site = ["--site", "34.246048,108.909664,380"]
    gyro_scale = "%.17g*rad" % (header[2][0] * ARCSEC_RAD)
    acc_scale = "%.17g*m/s" % (header[2][3] * 1e-6 * header[1][5])
    imports = {
        "psins-imu": [imu, "--preset", "psins-imu"],
        "novatel-rawimusa": [raw_path, "--preset", "novatel-rawimusa", *site,
                             "--units", "gyro=%s,acc=%s" % (gyro_scale, acc_scale)],
        "binary": [bin_path, "--binary", "i32", "--set", "header_bytes=32", *site,
                   "--columns", "t:f64,gyro_y,gyro_x,-gyro_z,acc_y,acc_x,-acc_z",
                   "--units", "gyro=%s,acc=%s" % (gyro_scale, acc_scale)],
    }
    failures = 0
    for name, args in imports.items():
        out = os.path.join(work, name + ".csv")
        run([insdiag, "import", *args, *common, "-o", out])
        samples = read_run(out)
        gyro_err = np.max(np.abs(samples[:, 1:4] - gyro)) / np.max(np.abs(gyro))
        acc_err = np.max(np.abs(samples[:, 4:7] - acc)) / np.max(np.abs(acc))
        # Relative to the largest value: the RAWIMUSA times of 2.6e5 s hold
        # 5.8e-11 s, a few 1e-9 of an interval.
        ok = len(samples) == len(gyro) and gyro_err < 1e-8 and acc_err < 1e-8
        failures += not ok
        print("%-17s %d samples, max |imported - numpy| / max |numpy|: gyro %.2g, acc %.2g: %s"
              % (name, len(samples), gyro_err, acc_err, "ok" if ok else "FAILED"))
        if name == "binary":
            continue
        curves = os.path.join(work, name + "-allan.csv")
        report = json.loads(run([insdiag, "analyze", out, "--allan", curves, "--json"]))
        report = report.get("report", report)
        spikes = {}
        for f in report.get("faultIntervals", []):
            if f["kind"] == "OUTLIER" and f["channel"] in CHANNELS:
                spikes.setdefault(f["channel"], []).append((f["startS"], f["endS"]))
        times = samples[:, 0]
        # Where the analysis cut a channel's static segment at a jump of its mean.
        jumps = {c["channel"]: c.get("jumpTimesS", []) for c in report.get("allan", [])}
        series = {c: (gyro if i < 3 else acc)[:, i % 3] for i, c in enumerate(CHANNELS)}
        fixed = {c: repaired(series[c], times, spikes.get(c, [])) for c in CHANNELS}
        worst, worst_raw = {}, {}
        with open(curves, encoding="utf-8") as f:
            next(f)
            for line in f:
                channel, tau, engine_adev = line.split(",")[:3]
                m = int(round(float(tau) / dt))
                for table, values in ((worst, fixed[channel]), (worst_raw, series[channel])):
                    numpy_adev = adev(values, dt, m, times, jumps.get(channel, []))
                    rel = abs(float(engine_adev) - numpy_adev) / numpy_adev
                    table[channel] = max(table.get(channel, 0.0), rel)
        _THETA.clear()
        for channel, rel in worst.items():
            ok = rel < 1e-8
            failures += not ok
            cut = ("cut at %s s" % ", ".join("%.2f" % t for t in jumps[channel])) if jumps.get(channel) else "not cut"
            print("%-17s Allan deviation of %s (%d spikes repaired, %s): worst relative difference to numpy "
                  "%.2g over every tau (%.2g without the repair): %s"
                  % (name, channel, len(spikes.get(channel, [])), cut, rel, worst_raw[channel],
                     "ok" if ok else "FAILED"))
    failures += check_receiver_record(insdiag, source, work)
    sys.exit(1 if failures else 0)


# The HG1700-AG58's counts (NovAtel's raw IMU scale factors): 2^-33 rad and
# 2^-27 ft/s, at 100 Hz. They give this record a specific force of 9.79 m/s²:
# gravity, so they are its IMU's.
AG58_GYRO_RAD = 2.0 ** -33
AG58_ACC_MPS = 0.3048 * 2.0 ** -27
AG58_RATE_HZ = 100.0


def check_receiver_record(insdiag, source, work):
    """The real RAWIMUSXA record against numpy's reading of its fields."""
    path = os.path.join(source, "data/real/novatel-rawimusxa-edie.asc")
    with open(path, encoding="ascii") as f:
        line = f.read().strip()
    body, crc = line[1:].split("*")
    crc_ok = (zlib.crc32(body.encode(), 0xFFFFFFFF) ^ 0xFFFFFFFF) & 0xFFFFFFFF == int(crc, 16)
    fields = body.split(";")[1].split(",")
    z_acc, minus_y_acc, x_acc, z_gyro, minus_y_gyro, x_gyro = (int(v) for v in fields[5:11])
    dt = 1.0 / AG58_RATE_HZ
    # Sensor X-right, Y-forward, Z-up to body x-forward, y-right, z-down.
    acc = np.array([-minus_y_acc, x_acc, -z_acc]) * AG58_ACC_MPS / dt
    gyro = np.array([-minus_y_gyro, x_gyro, -z_gyro]) * AG58_GYRO_RAD / dt
    out = os.path.join(work, "receiver-record.csv")
    run([insdiag, "import", path, "--preset", "novatel-rawimusxa", "--serial", "EDIE-RAWIMUSXA",
         "--site", "51.0762,-114.1363,1100", "--rate-hz", "%g" % AG58_RATE_HZ,
         "--units", "gyro=%.17g*rad,acc=%.17g*m/s" % (AG58_GYRO_RAD, AG58_ACC_MPS), "-o", out])
    sample = read_run(out)
    # As for the re-encoded RAWIMUSA: the interval is the difference of two
    # 4.8e5-s times, which hold 5.8e-11 s.
    acc_err = np.max(np.abs(sample[0, 4:7] - acc)) / np.max(np.abs(acc))
    gyro_err = np.max(np.abs(sample[0, 1:4] - gyro)) / np.max(np.abs(gyro))
    ok = (crc_ok and len(sample) == 1 and acc_err < 1e-8 and gyro_err < 1e-8
          and abs(np.linalg.norm(acc) - 9.8) < 0.05 and acc[2] < -9.7)
    print("novatel-rawimusxa NovAtel's EDIE record: CRC %s; numpy acc %s m/s^2 (|f| %.4f), gyro %s rad/s; "
          "|imported - numpy| / max |numpy|: gyro %.2g, acc %.2g: %s"
          % ("ok" if crc_ok else "BAD", np.array2string(acc, precision=5), np.linalg.norm(acc),
             np.array2string(gyro, precision=6), gyro_err, acc_err, "ok" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    main()
