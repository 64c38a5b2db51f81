"""Rotary-table kinematics for the independent bench-run simulator.

A two-axis table: the outer axis turns the platform in yaw ψ about the local
down axis, the inner axis rolls the unit by φ about its own x axis, so the
body attitude is C_b^n = Rz(ψ) · Rx(φ) (shared/spec/bench-run-format.md:
C_b^n = Rz(yaw)·Ry(pitch)·Rx(roll) with pitch 0). Each table angle is a
piecewise-quadratic function of time: holds, constant rates, and constant
angular accelerations for ramped rate changes; a rate step is a breakpoint
where the rate changes within zero time.

Body rate w.r.t. the navigation frame (Titterton & Weston, Strapdown Inertial
Navigation Technology, 2nd ed., §3.6, Euler-angle rates):
    ω_nb^b = [φ̇, 0, 0] + Rx(φ)ᵀ [0, 0, ψ̇] = [φ̇, ψ̇ sin φ, ψ̇ cos φ].
The body sits at the table centre, at rest on the Earth, so (Groves,
Principles of GNSS, Inertial and Multisensor Integrated Navigation Systems,
2nd ed., eq. 5.42 with zero velocity)
    ω_ib^b = ω_nb^b + C_b^nᵀ ω_ie^n,   ω_ie^n = Ω [cos L, 0, −sin L]
    f^b    = C_b^nᵀ (−g^n),            g^n = [0, 0, g(L, h)]  (normal gravity: its
             centripetal part is in g, so a body at rest senses exactly −g^n).
"""
import math

import numpy as np

EARTH_RATE_RAD_S = 7.292115e-5  # WGS-84
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_GM = 3.986004418e14


def normal_gravity_mps2(latitude_rad, height_m):
    """WGS-84 normal gravity: Somigliana's formula and its second-order height
    correction (NIMA TR8350.2, 3rd ed., eq. 4-1 and 4-3)."""
    s2 = math.sin(latitude_rad) ** 2
    gamma_e, k, e2 = 9.7803253359, 0.00193185265241, 0.00669437999013
    g0 = gamma_e * (1.0 + k * s2) / math.sqrt(1.0 - e2 * s2)
    m = EARTH_RATE_RAD_S ** 2 * WGS84_A_M ** 2 * (WGS84_A_M * (1 - WGS84_F)) / WGS84_GM
    return g0 * (1.0 - 2.0 / WGS84_A_M * (1.0 + WGS84_F + m - 2.0 * WGS84_F * s2) * height_m
                 + 3.0 * height_m ** 2 / WGS84_A_M ** 2)


class AxisMotion:
    """One table axis: a piecewise-quadratic angle. Piece i starts at t[i] with
    angle a[i], rate w[i] and a constant acceleration e[i] until t[i+1]."""

    def __init__(self, start_angle_rad=0.0):
        self.t = [0.0]
        self.a = [start_angle_rad]
        self.w = [0.0]
        self.e = [0.0]

    def _end_state(self, t_end):
        dt = t_end - self.t[-1]
        angle = self.a[-1] + self.w[-1] * dt + 0.5 * self.e[-1] * dt * dt
        rate = self.w[-1] + self.e[-1] * dt
        return angle, rate

    def add_piece(self, start_s, rate_rad_s, accel_rad_s2, keep_rate=False):
        """A new piece at `start_s`: its rate jumps to `rate_rad_s` (a rate step)
        unless `keep_rate`, and it accelerates at `accel_rad_s2`."""
        angle, rate = self._end_state(start_s)
        self.t.append(start_s)
        self.a.append(angle)
        self.w.append(rate if keep_rate else rate_rad_s)
        self.e.append(accel_rad_s2)

    def evaluate(self, times_s):
        """Angle and rate at `times_s` (array)."""
        t = np.asarray(times_s, dtype=float)
        knots = np.asarray(self.t)
        i = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, len(knots) - 1)
        dt = t - knots[i]
        a, w, e = np.asarray(self.a)[i], np.asarray(self.w)[i], np.asarray(self.e)[i]
        return a + w * dt + 0.5 * e * dt * dt, w + e * dt

    def breakpoints(self):
        return list(self.t[1:])


def body_attitude(yaw_rad, roll_rad):
    """C_b^n = Rz(ψ) Rx(φ) for arrays of angles: shape (n, 3, 3)."""
    cy, sy, cr, sr = np.cos(yaw_rad), np.sin(yaw_rad), np.cos(roll_rad), np.sin(roll_rad)
    C = np.zeros(np.shape(yaw_rad) + (3, 3))
    C[..., 0, 0], C[..., 0, 1], C[..., 0, 2] = cy, -sy * cr, sy * sr
    C[..., 1, 0], C[..., 1, 1], C[..., 1, 2] = sy, cy * cr, -cy * sr
    C[..., 2, 0], C[..., 2, 1], C[..., 2, 2] = 0.0, sr, cr
    return C


def true_rates_and_forces(times_s, yaw, roll, latitude_rad, gravity_mps2):
    """ω_ib^b [rad/s] and f^b [m/s²] at `times_s` for the yaw and roll axes (AxisMotion)."""
    psi, psi_dot = yaw.evaluate(times_s)
    phi, phi_dot = roll.evaluate(times_s)
    C = body_attitude(psi, phi)
    w_nb = np.stack([phi_dot, psi_dot * np.sin(phi), psi_dot * np.cos(phi)], axis=-1)
    w_ie_n = EARTH_RATE_RAD_S * np.array([math.cos(latitude_rad), 0.0, -math.sin(latitude_rad)])
    w_ib = w_nb + np.einsum("kji,j->ki", C, w_ie_n)
    f_b = np.einsum("kji,j->ki", C, np.array([0.0, 0.0, -gravity_mps2]))
    return w_ib, f_b, psi


# Gauss–Legendre nodes and weights on [0, 1] (6 points: exact for polynomials
# of degree 11; the integrands here are smooth within each piece).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(6)
GL_NODES = 0.5 * (_GL_X + 1.0)
GL_WEIGHTS = 0.5 * _GL_W


def interval_means(sample_times_s, breakpoints_s, integrand):
    """Mean of integrand(t) (an (n, d) array function) over each sample interval
    (t[k−1], t[k]], by Gauss–Legendre quadrature on every piece between the
    sample edges and the motion's breakpoints. Returns (n − 1, d)."""
    t = np.asarray(sample_times_s, dtype=float)
    inner = [b for b in breakpoints_s if t[0] < b < t[-1]]
    edges = np.union1d(t, np.asarray(inner, dtype=float))
    lengths = np.diff(edges)
    nodes = edges[:-1, None] + lengths[:, None] * GL_NODES[None, :]
    values = integrand(nodes.ravel())
    values = values.reshape(nodes.shape + (values.shape[-1],))
    piece_integrals = np.einsum("pqd,q->pd", values, GL_WEIGHTS) * lengths[:, None]
    starts = np.searchsorted(edges, t[:-1])
    sums = np.add.reduceat(piece_integrals, starts, axis=0)
    return sums / np.diff(t)[:, None]


def euler_zyx(C):
    """Roll, pitch, yaw of C = Rz(yaw) Ry(pitch) Rx(roll), yaw in (−π, π]."""
    roll = np.arctan2(C[..., 2, 1], C[..., 2, 2])
    pitch = -np.arcsin(np.clip(C[..., 2, 0], -1.0, 1.0))
    yaw = np.arctan2(C[..., 1, 0], C[..., 0, 0])
    return roll, pitch, yaw
