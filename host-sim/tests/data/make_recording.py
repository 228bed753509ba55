#!/usr/bin/env python3
"""An independent recording for `host-sim replay` (host-sim/tests/replay_independent.rs): the
Table 1 specimen (m1 29.5 kg, m2 1.75 kg, 7 Hz, 5 %, mu = mu_s = 0.2) on a harmonic table
(2 m/s², 0.143 s) after a 0.3 s rest, simulated here by a different method than host-sim's
exact truth: absolute coordinates x1, x2, fixed-step RK4 (dt = 1e-5 s) with Coulomb friction,
each phase change located by bisection of the step. Written as another lab's logger would:
1 kHz, its own column names, accelerations in g, the slip in mm, accelerometer offsets, seeded
noise, a few empty cells, and the true top acceleration in a column replay is not told about.

Run: python3 make_recording.py > recording-independent.csv (standard library only)."""

import math
import random
import sys

M1, M2, F, XI, MU, G = 29.5, 1.75, 7.0, 0.05, 0.2, 9.80665
P = 2 * math.pi * F
K, C = M1 * P * P, 2 * M1 * P * XI
N = MU * (M1 + M2) * G
A, T, REST = 2.0, 0.143, 0.3
DT, RATE, DURATION = 1e-5, 1000.0, 2.5
STEPS = int(round(1.0 / (RATE * DT)))
OFFSET_G = (0.002, -0.003, 0.001)  # table, base, top
NOISE = 0.005  # m/s²


def table(t):
    """Table acceleration, velocity, displacement (at rest until REST)."""
    if t <= REST:
        return 0.0, 0.0, 0.0
    w, s = 2 * math.pi / T, t - REST
    return A * math.sin(w * s), A / w * (1 - math.cos(w * s)), A / w * (s - math.sin(w * s) / w)


def accel(t, y, phase):
    """(ẍ1, ẍ2) for y = (x1, v1, x2, v2) in phase 0 (stuck: the base moves with the table) or
    ±1 (sliding: friction −phase·N on the base)."""
    x1, v1, x2, v2 = y
    spring = K * (x1 - x2) + C * (v1 - v2)
    a1 = -spring / M1
    if phase == 0:
        a2 = table(t)[0]
    else:
        a2 = (spring - phase * N) / M2
    return a1, a2


def rk4(t, y, h, phase):
    def f(tt, yy):
        a1, a2 = accel(tt, yy, phase)
        return (yy[1], a1, yy[3], a2)

    k1 = f(t, y)
    k2 = f(t + h / 2, [y[i] + h / 2 * k1[i] for i in range(4)])
    k3 = f(t + h / 2, [y[i] + h / 2 * k2[i] for i in range(4)])
    k4 = f(t + h, [y[i] + h * k3[i] for i in range(4)])
    return [y[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]) for i in range(4)]


def needed(t, y):
    """The friction force that keeps the base stuck."""
    x1, v1, x2, v2 = y
    return M2 * table(t)[0] - (K * (x1 - x2) + C * (v1 - v2))


def switch(t, y, phase):
    """The phase change condition's value (a sign change marks the event), or None."""
    if phase == 0:
        return abs(needed(t, y)) - N  # > 0: slips
    return (y[3] - table(t)[1]) * phase  # slip velocity in the sliding direction: < 0 at its zero


def step(t, y, h, phase):
    """One step of length h, cut at a phase change located by bisection; returns (t, y, phase)."""
    y1 = rk4(t, y, h, phase)
    s0, s1 = switch(t, y, phase), switch(t + h, y1, phase)
    crossed = (s0 <= 0 < s1) if phase == 0 else (s0 > 0 >= s1)
    if not crossed:
        return t + h, y1, phase
    lo, hi = 0.0, h
    for _ in range(60):
        mid = (lo + hi) / 2
        ym = rk4(t, y, mid, phase)
        sm = switch(t + mid, ym, phase)
        if (sm <= 0) if phase == 0 else (sm > 0):
            lo = mid
        else:
            hi = mid
    te = t + hi
    ye = rk4(t, y, hi, phase)
    if phase == 0:
        new = -1 if needed(te, ye) > 0 else 1  # the base lags behind the friction it needed
    else:
        ye[3] = table(te)[1]  # zero slip velocity
        new = 0 if abs(needed(te, ye)) <= N else -phase
    # The rest of the step in the new phase.
    rest = h - hi
    if rest > 0:
        ye = rk4(te, ye, rest, new)
    return t + h, ye, new


def main():
    rnd = random.Random(7)
    y, phase, t = [0.0, 0.0, 0.0, 0.0], 0, 0.0
    out = sys.stdout
    out.write("Time (s),A table (g),A base (g),A top (g),LVDT (mm),A top true (g)\n")
    n = int(round(DURATION * RATE))
    blanks = {137: 2, 901: 1, 1544: 3, 2011: 4}
    for k in range(n):
        a1, a2 = accel(t, y, phase)
        ag = table(t)[0]
        slip_mm = 1e3 * (y[2] - table(t)[2])
        cells = [
            f"{t:.3f}",
            f"{(ag + rnd.gauss(0, NOISE)) / G + OFFSET_G[0]:.8f}",
            f"{(a2 + rnd.gauss(0, NOISE)) / G + OFFSET_G[1]:.8f}",
            f"{(a1 + rnd.gauss(0, NOISE)) / G + OFFSET_G[2]:.8f}",
            f"{slip_mm:.6f}",
            f"{a1 / G:.10f}",
        ]
        if k in blanks:
            cells[blanks[k]] = ""
        out.write(",".join(cells) + "\n")
        for _ in range(STEPS):
            t, y, phase = step(t, y, DT, phase)
        t = (k + 1) / RATE


if __name__ == "__main__":
    main()
