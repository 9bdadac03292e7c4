#!/usr/bin/env python3
"""Writes the synthetic liquefier data sets with known truth (pure Python, fixed seeds).

synthetic_steps.csv: feed-rate steps through a first-order-plus-dead-time liquefier,
  force = F0 + K * u(t - theta) filtered by 1/(tau s + 1), plus white noise.
synthetic_chirp.csv: a linear chirp of the feed rate through a second-order system
  K wn^2 / (s^2 + 2 zeta wn s + wn^2), plus white output noise.
"""
import math, random

# --- steps ---
K, TAU, THETA, F0, SIGMA = 12.0, 0.6, 0.15, 3.0, 0.15
levels = [(0.0, 1.0), (10.0, 3.0), (30.0, 1.0), (50.0, 2.0), (65.0, 0.0)]
fs, T = 100.0, 80.0
rng = random.Random(1)
with open('synthetic_steps.csv', 'w') as f:
    f.write(f'# synthetic: FOPDT K={K} N/(mm/s), tau={TAU} s, theta={THETA} s, offset {F0} N, noise sd {SIGMA} N, seed 1\n')
    f.write('time (s),feed (mm/s),force (N)\n')
    for i in range(int(T * fs) + 1):
        t = i / fs
        u = [lv for (t0, lv) in levels if t >= t0][-1]
        y = F0 + K * levels[0][1]
        for j in range(1, len(levels)):
            du = levels[j][1] - levels[j - 1][1]
            s = t - levels[j][0] - THETA
            if s > 0:
                y += K * du * (1 - math.exp(-s / TAU))
        y += rng.gauss(0, SIGMA)
        f.write(f'{t:.2f},{u:g},{y:.5f}\n')

# --- chirp through a second-order system ---
K2, FN, ZETA, SIG2 = 2.0, 12.0, 0.2, 0.02
fs2, T2, F_LO, F_HI = 250.0, 40.0, 0.2, 50.0
wn = 2 * math.pi * FN
rng = random.Random(2)
def u_of(t):
    k = (F_HI - F_LO) / T2
    return math.sin(2 * math.pi * (F_LO * t + 0.5 * k * t * t))
def deriv(t, x):
    return (x[1], K2 * wn * wn * u_of(t) - 2 * ZETA * wn * x[1] - wn * wn * x[0])
x = (0.0, 0.0)
sub = 20
h = 1 / (fs2 * sub)
with open('synthetic_chirp.csv', 'w') as f:
    f.write(f'# synthetic: linear chirp {F_LO}-{F_HI} Hz over {T2} s through K={K2}, fn={FN} Hz, zeta={ZETA}; output noise sd {SIG2}, seed 2\n')
    f.write('time (s),feed (mm/s),force (N)\n')
    n = int(T2 * fs2)
    for i in range(n):
        t = i / fs2
        f.write(f'{t:.4f},{u_of(t):.6f},{x[0] + rng.gauss(0, SIG2):.6f}\n')
        for _ in range(sub):  # RK4
            tt = t + _ * h
            k1 = deriv(tt, x)
            k2 = deriv(tt + h / 2, (x[0] + h / 2 * k1[0], x[1] + h / 2 * k1[1]))
            k3 = deriv(tt + h / 2, (x[0] + h / 2 * k2[0], x[1] + h / 2 * k2[1]))
            k4 = deriv(tt + h, (x[0] + h * k3[0], x[1] + h * k3[1]))
            x = (x[0] + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]), x[1] + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))
