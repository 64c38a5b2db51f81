"""Table profiles of the independent bench-run simulator (its own, not the
project simulator's). A profile is a list of steps, repeated until the run's
duration:

| profile   | what the table does |
|-----------|---------------------|
| static    | level, still |
| turns     | 300 s still, then yaw turns at 10 °/s: +360°, −360°, +90° with holds of 60–120 s |
| positions | a multi-position drift test: 16 static positions, roll 0/90/180/270° × yaw 0/90/180/270°, 200 s each, moves at 10 °/s |
| mixed     | holds, a 15 °/s yaw turn, roll tilts to 90°, 180°, 360°, a 20 °/s yaw turn back |
| tilted    | a long drift test at oblique positions: roll 35°, 125°, 215°, 305° × yaw 45°, 165°, 285°, 600 s each, moves at 5 °/s |
| tilted-turns | a long drift test turning while tilted: at roll 30°, 150°, 240° and 330° the table turns about yaw for 1200 s at 3 °/s, then back at 3 °/s for 600 s, with 120-s holds between |

The last two are drift tests of several hours: every sensor axis sees a
changing share of gravity and of the earth's rate, none of them at the
right angles of `positions`.

Rate changes are instantaneous (the rate steps within one sample) unless a
ramp acceleration is given; with `jitter_s` every hold is lengthened by a
seeded random fraction of `jitter_s`, so that the changes fall off the
sample grid.
"""
import math

from kinematics import AxisMotion

DEG = math.pi / 180.0

PROFILES = {
    "static": [("hold", 600.0)],
    "turns": [("hold", 300.0), ("yaw", 360.0, 10.0), ("hold", 60.0), ("yaw", -360.0, 10.0), ("hold", 60.0),
              ("yaw", 90.0, 10.0), ("hold", 120.0)],
    "positions": [step for roll in (0.0, 90.0, 180.0, 270.0) for yaw in (0.0, 90.0, 180.0, 270.0)
                  for step in (("to", yaw, roll, 10.0), ("hold", 200.0))],
    "mixed": [("hold", 120.0), ("yaw", 360.0, 15.0), ("hold", 60.0), ("roll", 90.0, 10.0), ("hold", 200.0),
              ("yaw", 180.0, 10.0), ("hold", 200.0), ("roll", 90.0, 10.0), ("hold", 200.0), ("roll", 180.0, 10.0),
              ("yaw", -540.0, 20.0), ("hold", 120.0)],
    "tilted": [step for roll in (35.0, 125.0, 215.0, 305.0) for yaw in (45.0, 165.0, 285.0)
               for step in (("to", yaw, roll, 5.0), ("hold", 600.0))],
    "tilted-turns": [step for roll in (30.0, 150.0, 240.0, 330.0)
                     for step in (("to", 0.0, roll, 5.0), ("hold", 120.0), ("yaw", 3600.0, 3.0), ("hold", 120.0),
                                  ("yaw", -1800.0, 3.0), ("hold", 120.0))],
}


class Table:
    def __init__(self):
        self.yaw = AxisMotion()
        self.roll = AxisMotion()
        self.t = 0.0

    def hold(self, duration_s):
        self.t += duration_s

    def move(self, axis, angle_rad, rate_rad_s, accel_rad_s2):
        """Turns `axis` by `angle_rad` at `rate_rad_s` (sign from the angle)."""
        if angle_rad == 0.0:
            return
        motion = self.yaw if axis == "yaw" else self.roll
        sign = 1.0 if angle_rad > 0 else -1.0
        rate = abs(rate_rad_s)
        if accel_rad_s2 is None or accel_rad_s2 <= 0.0:
            cruise = abs(angle_rad) / rate
            motion.add_piece(self.t, sign * rate, 0.0)
            motion.add_piece(self.t + cruise, 0.0, 0.0)
            self.t += cruise
            return
        ramp_s = rate / accel_rad_s2
        cruise = abs(angle_rad) / rate - ramp_s
        if cruise < 0.0:  # a short move: triangular rate profile
            ramp_s = math.sqrt(abs(angle_rad) / accel_rad_s2)
            cruise = 0.0
        motion.add_piece(self.t, 0.0, sign * accel_rad_s2, keep_rate=True)
        motion.add_piece(self.t + ramp_s, 0.0, 0.0, keep_rate=True)
        motion.add_piece(self.t + ramp_s + cruise, 0.0, -sign * accel_rad_s2, keep_rate=True)
        motion.add_piece(self.t + 2 * ramp_s + cruise, 0.0, 0.0)
        self.t += 2 * ramp_s + cruise

    def angles_now(self):
        return self.yaw.evaluate([self.t])[0][0], self.roll.evaluate([self.t])[0][0]


def build(name, duration_s, rng, ramp_accel_deg_s2=None, jitter_s=1.0):
    """The yaw and roll motions of profile `name` repeated over `duration_s`."""
    if name not in PROFILES:
        raise ValueError(f"unknown profile '{name}'; profiles: {', '.join(PROFILES)}")
    table = Table()
    accel = None if ramp_accel_deg_s2 is None else ramp_accel_deg_s2 * DEG
    while table.t < duration_s:
        for step in PROFILES[name]:
            if table.t >= duration_s:
                break
            kind = step[0]
            if kind == "hold":
                table.hold(step[1] + jitter_s * rng.random())
            elif kind in ("yaw", "roll"):
                table.move(kind, step[1] * DEG, step[2] * DEG, accel)
            elif kind == "to":
                yaw_now, roll_now = table.angles_now()
                target_yaw, target_roll, rate = step[1] * DEG, step[2] * DEG, step[3] * DEG
                # The shorter way round to each target.
                d_yaw = math.remainder(target_yaw - yaw_now, 2 * math.pi)
                d_roll = math.remainder(target_roll - roll_now, 2 * math.pi)
                table.move("roll", d_roll, rate, accel)
                table.move("yaw", d_yaw, rate, accel)
        if name == "static":
            table.hold(duration_s)
    return table.yaw, table.roll
