"""Friction points from a TU Delft seal file, for `pneumo fit friction`.

    python3 examples/python/friction_points.py SEAL_Pbar.csv points.csv

The shared files (whitespace, no header, README beside them) hold time
(ms, column 1), piston position (mm, column 5), chamber pressure (bar
gauge, column 6) and load-cell force (N, column 7) at about 100 Hz. A
point is the speed by a central difference of the position over +-2
samples (40 ms, to stay above the laser's 4 um steps), the seal's force
as load cell - p A (bore 25 mm), signed along the stroke, and the
pressure; the first 15 samples (the start-up transient) are skipped.
"""
import math
import sys

BORE = 0.025  # m
SKIP = 15


def main(src, dst):
    area = math.pi * BORE * BORE / 4
    rows = [line.split() for line in open(src) if line.strip()][SKIP:]
    t = [float(r[0]) / 1e3 for r in rows]
    s = [float(r[4]) / 1e3 for r in rows]
    p = [float(r[5]) * 1e5 for r in rows]
    F = [float(r[6]) for r in rows]
    with open(dst, "w") as out:
        out.write("v [m/s], F [N], p_A [bar_rel], p_B [bar_rel]\n")
        for i in range(2, len(rows) - 2):
            v = (s[i + 2] - s[i - 2]) / (t[i + 2] - t[i - 2])
            if v != 0:  # at a standstill the force's direction is unknown
                out.write(f"{v:.9g}, {F[i] - p[i] * area:.9g}, {p[i] / 1e5:.9g}, 0\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
