#!/usr/bin/python3
"""Rebuilds the PSINS toolbox's SIMU log of the real ring-laser-gyro record.

The record in shared/data/real/rlg-static-psins.csv was converted from the
PSINS toolbox's sample log data/lasergyro.imu (rates = increments / 0.01 s;
axes from X-right, Y-forward, Z-up to x-forward, y-right, z-down). This
inverts that conversion back to the toolbox's layout: the comment lines, three
header lines and one line of six integer counts per sample (gyro counts of
0.1 arcsec, accelerometer counts of 125 ug*s with g = 9.780327 m/s^2). Every
count comes back within 1e-6 of an integer, so the rebuilt log holds exactly
the recorded samples.

Usage: rebuild_psins_imu.py SHARED_CSV > rlg-static.imu
"""
import math
import sys

import numpy as np

ARCSEC = math.pi / 180 / 3600
GYRO_COUNT_RAD = 0.1 * ARCSEC
G_MPS2 = 9.780327
ACC_COUNT_MPS = 125e-6 * G_MPS2
DT_S = 0.01


def main():
    rows = []
    with open(sys.argv[1], encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or line.startswith("t,"):
                continue
            rows.append([float(v) for v in line.split(",")[:7]])
    data = np.array(rows)
    gyro_frd, acc_frd = data[:, 1:4] * DT_S, data[:, 4:7] * DT_S
    # x-forward, y-right, z-down back to X-right, Y-forward, Z-up.
    gyro = np.column_stack([gyro_frd[:, 1], gyro_frd[:, 0], -gyro_frd[:, 2]]) / GYRO_COUNT_RAD
    acc = np.column_stack([acc_frd[:, 1], acc_frd[:, 0], -acc_frd[:, 2]]) / ACC_COUNT_MPS
    counts = np.hstack([gyro, acc])
    worst = np.max(np.abs(counts - np.round(counts)))
    if worst > 1e-6:
        sys.exit(f"a count is {worst} away from an integer: not the recorded layout")
    out = sys.stdout
    out.write("% PSINS-format SIMU log file, rebuilt by insdiag's data/real/rebuild_psins_imu.py\n")
    out.write("% from the converted copy of the PSINS toolbox's sample log data/lasergyro.imu (2014).\n")
    out.write("% 1st line: [pitch0(deg), roll0(deg), yaw0(deg), VE0(m/s), VN0(m/s), VU0(m/s)].\n")
    out.write("% 2nd line: [latitude0(deg), longitude0(deg), height0(m), t0(s), sampling-interval(ms), g(m/s^2)].\n")
    out.write("% 3rd line: [gf_x, gf_y, gf_z, af_x, af_y, af_z], gyro scale in arcsec, acc scale in ug*s.\n")
    out.write("% Mounting X-Right, Y-Forward, Z-Up.\n\n")
    out.write("0.000000 0.000000 -90.600000 0.000000 0.000000 0.000000\n")
    out.write("34.24604800 108.90966400 380.000 0.00000000 10.00000000 9.780327\n")
    out.write("0.100000 0.100000 0.100000 125.000 125.000 125.000\n")
    for row in np.round(counts).astype(np.int64):
        out.write(" ".join(str(v) for v in row) + "\n")


if __name__ == "__main__":
    main()
