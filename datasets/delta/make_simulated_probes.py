#!/usr/bin/python3
"""Writes probes_simulated.csv: G30 S-1 probe heights of a simulated linear delta whose real
geometry (TRUTH) differs from the geometry its firmware runs (NOMINAL), plus Gaussian probe
noise. Written independently of tunekit's C++ model: for each probe point it solves the three
rod equations for the true nozzle position on the bed (z = 0) and the commanded height, by
Newton's method. Conventions as RepRapFirmware's linear delta (towers at 210, 330, 90 deg;
carriage homed at H + sqrt(L^2 - R^2) + e)."""
import math
import numpy as np

NOMINAL = dict(R=105.0, L=[215.0] * 3, ang=[210.0, 330.0, 90.0], e=[0.0] * 3, H=250.0)
TRUTH = dict(R=104.2, L=[215.0] * 3, ang=[210.4, 329.7, 90.0], e=[0.35, -0.20, 0.10], H=250.0)
NOISE_MM = 0.01
SEED = 2013


def towers(g):
    return [(g["R"] * math.cos(math.radians(a)), g["R"] * math.sin(math.radians(a))) for a in g["ang"]]


def homed(g):
    return [g["H"] + math.sqrt(L * L - g["R"] ** 2) + e for L, e in zip(g["L"], g["e"])]


def equations(u, x, y):
    X, Y, zc = u
    tn, tt = towers(NOMINAL), towers(TRUTH)
    hn, ht = homed(NOMINAL), homed(TRUTH)
    out = []
    for i in range(3):
        cmd = zc + math.sqrt(NOMINAL["L"][i] ** 2 - (x - tn[i][0]) ** 2 - (y - tn[i][1]) ** 2)
        real = ht[i] - (hn[i] - cmd)
        out.append(real - math.sqrt(TRUTH["L"][i] ** 2 - (X - tt[i][0]) ** 2 - (Y - tt[i][1]) ** 2))
    return np.array(out)


def probe(x, y):
    u = np.array([x, y, 0.0])
    for _ in range(50):
        f = equations(u, x, y)
        J = np.zeros((3, 3))
        for j in range(3):
            d = np.zeros(3)
            d[j] = 1e-6
            J[:, j] = (equations(u + d, x, y) - equations(u - d, x, y)) / 2e-6
        step = np.linalg.solve(J, f)
        u = u - step
        if np.max(np.abs(step)) < 1e-13:
            break
    return u[2]


def main():
    rng = np.random.default_rng(SEED)
    pts = [(0.0, 0.0)]
    for k in (1, 2):
        r = 85.0 * k / 2
        pts += [(r * math.cos(math.pi / 2 + 2 * math.pi * j / 8), r * math.sin(math.pi / 2 + 2 * math.pi * j / 8))
                for j in range(8)]
    with open("probes_simulated.csv", "w") as f:
        f.write("x_mm,y_mm,z_mm,z_exact_mm\n")
        for x, y in pts:
            z = probe(x, y)
            f.write("%.3f,%.3f,%.4f,%.9f\n" % (x, y, z + rng.normal(0.0, NOISE_MM), z))


if __name__ == "__main__":
    main()
