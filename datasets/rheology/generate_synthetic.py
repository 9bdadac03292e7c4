#!/usr/bin/env python3
"""Writes the synthetic rheology data sets of this folder (standard library only, fixed seeds).

peek_cross_wlf_synthetic.csv: PEEK Cross-WLF (seed 001 Table 2.4) at 380/400/420 degC
  (+273.15), 15 log-spaced shear rates 1..1e4 1/s each, multiplicative 3 % Gaussian noise.
nozzle_pressure_synthetic.csv: Boles pressure drop (seed 001 eq. 2.6/2.7) of a power law
  K = 7988 Pa.s^n at 405 degC, n = 0.539, Arrhenius shift Ea = 150 kJ/mol, regular nozzle of
  Table 5.3 (d 0.6 mm, l 4 mm, alpha 30 deg), at 395/405/415 degC and 1.5/3/6 mm3/s (the
  load-cell experiment of sec. 5.3), multiplicative 2 % Gaussian noise.
"""
import math
import random

A1, A2, D1, D2, N, TAU = 36.041, 51.6, 2.89808e16, 403.15, 0.4266, 124139.0


def cross_wlf(gamma, T):
    eta0 = D1 * math.exp(-A1 * (T - D2) / (A2 + T - D2))
    return eta0 / (1 + (eta0 * gamma / TAU) ** (1 - N))


def boles(K, n, Q, alpha, d, l):
    s = (8 * Q * (3 * n + 1) / (math.pi * d ** 3 * n)) ** n
    f = 2 / (3 * n * math.sin(alpha)) * (3 * math.sin(alpha) / (4 * n * (1 - math.cos(alpha)) ** 2 * (1 + 2 * math.cos(alpha)))) ** n
    return K * s * (1.18 / n ** 0.7 + 4 * l / d + f)


rng = random.Random(4)
with open("peek_cross_wlf_synthetic.csv", "w") as f:
    f.write("# Synthetic: PEEK Cross-WLF (seed 001 Table 2.4), 3 % noise; see PROVENANCE.md\n")
    f.write("shear_rate (1/s),viscosity (Pa.s),temperature (degC)\n")
    for tc in (380, 400, 420):
        for i in range(15):
            g = 10 ** (i * 4 / 14)
            eta = cross_wlf(g, tc + 273.15) * math.exp(0.03 * rng.gauss(0, 1))
            f.write(f"{g:.6g},{eta:.6g},{tc}\n")

rng = random.Random(5)
R = 8.314462618
with open("nozzle_pressure_synthetic.csv", "w") as f:
    f.write("# Synthetic: Boles pressure drop, power law with Arrhenius shift, 2 % noise; see PROVENANCE.md\n")
    f.write("flow (mm3/s),pressure (MPa),temperature (degC)\n")
    for tc in (395, 405, 415):
        aT = math.exp(150e3 / R * (1 / (tc + 273.15) - 1 / (405 + 273.15)))
        for q in (1.5, 3, 6):
            dp = boles(7988 * aT, 0.539, q * 1e-9, math.pi / 6, 0.6e-3, 4e-3) * math.exp(0.02 * rng.gauss(0, 1))
            f.write(f"{q},{dp * 1e-6:.6g},{tc}\n")
