#!/usr/bin/env python3
"""Writes data/normative_gait.csv: the OpenSim subject01 walk (subject01_walk1_ik.mot, CC BY 3.0, Delp et al.)
as 101 samples of knee flexion, hip flexion and ankle dorsiflexion over one gait cycle starting at heel strike.

Usage: scripts/normative_gait_table.py ../shared/data/opensim_gait/subject01_walk1_ik.mot > data/normative_gait.csv

The trial holds 1.2 s at 60 Hz, a little over one cycle but no whole cycle of either leg from heel strike to heel
strike, so the cycle is assembled from both legs: the right leg from its heel strike to the end of the trial, then
the left leg half a cycle earlier (the two legs are taken as symmetric). Heel strike is where the knee is most
extended in terminal swing (the OpenSim knee_angle maximum before loading response); the cycle time is twice the
interval from the right to the left heel strike. Rejected: a cycle of one leg by matching the curve with itself
shifted, which needs more than one cycle of data to find the period.
Signs: knee flexion = -knee_angle (OpenSim flexion is negative), hip flexion = hip_flexion, dorsiflexion =
ankle_angle.
"""
import sys


def load(path):
    text = open(path).read().split("endheader", 1)[1].strip().splitlines()
    names = text[0].split("\t")
    rows = [[float(x) for x in line.split()] for line in text[1:] if line.strip()]
    return {n: [r[i] for r in rows] for i, n in enumerate(names)}


def interp(ts, ys, t):
    if t <= ts[0]:
        return ys[0]
    for i in range(1, len(ts)):
        if t <= ts[i]:
            u = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
            return ys[i - 1] + u * (ys[i] - ys[i - 1])
    return ys[-1]


def strike(ts, knee, lo, hi):
    best = None
    for t, k in zip(ts, knee):
        if lo <= t <= hi and (best is None or k > best[1]):
            best = (t, k)
    return best[0]


def main():
    d = load(sys.argv[1])
    ts = d["time"]
    t_r = strike(ts, d["knee_angle_r"], 0.45, 0.8)
    t_l = strike(ts, d["knee_angle_l"], t_r + 0.3, ts[-1])
    cycle = 2.0 * (t_l - t_r)
    print("# Normative walk: OpenSim subject01_walk1_ik.mot (opensim-org/opensim-models @ 20a888b9,")
    print("# Pipelines/Gait2354_Simbody/OutputReference), CC BY 3.0 as the models' credits state (the .mot")
    print("# carries no own statement; the same terms are assumed). Credit: Delp, Loan, Hoy, Zajac, Topp, Rosen,")
    print("# Thelen, Anderson, Seth (Delp et al., IEEE TBME 1990). Derived by scripts/normative_gait_table.py:")
    print("# right leg from heel strike at t = %.4f s, left leg half a cycle earlier past the trial's end;" % t_r)
    print("# cycle %.4f s. Degrees; flexion and dorsiflexion positive." % cycle)
    print("phase_pct,knee_flexion_deg,hip_flexion_deg,ankle_dorsiflexion_deg")
    for i in range(101):
        t = t_r + cycle * i / 100.0
        if t <= ts[-1]:
            side, at = "r", t
        else:
            side, at = "l", t - 0.5 * cycle
        knee = -interp(ts, d["knee_angle_" + side], at)
        hip = interp(ts, d["hip_flexion_" + side], at)
        ankle = interp(ts, d["ankle_angle_" + side], at)
        print("%d,%.2f,%.2f,%.2f" % (i, knee, hip, ankle))


main()
