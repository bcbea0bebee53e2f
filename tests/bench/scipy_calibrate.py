#!/usr/bin/python3
"""Speed baseline only: the 27-parameter stage model of `fvm calibrate --model 27` fitted with
scipy.optimize.least_squares on a batch (default samples/bar17), so that `fvm calibrate` can be timed against a
plain Python fit. Not a second implementation to trust: no alias detection, no uncertainties, no validation.

Model (stage/axis_chain.h, YXFZ, small angles, anchor none): stitched = F(free), where F runs the tool point
through the Z axis and back through the part axes Y, X; each error term is c0 + c1 * q / half-travel of its
axis (x, y travel 200 mm, z 100 mm); squareness xWy, xWz ride on X, yWz on Y.
Usage: /usr/bin/python3 tests/bench/scipy_calibrate.py [batch-dir]    (Debian python3-scipy: apt-get install --no-install-recommends python3-scipy)
"""
import csv, json, sys, time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

HALF = np.array([100.0, 100.0, 50.0])  # half-travel of x, y, z (mm)
X, Y, Z = 0, 1, 2
# Terms of model 27: (axis, kind, component) with kind T, R or W; orders 0 and 1, minus xTy1, xTz1, yTz1.
TERMS = [(a, k, c) for a in (X, Y) for k in "TR" for c in (X, Y, Z)] + [(X, "W", Y), (X, "W", Z), (Y, "W", Z)]
COEFS = [(t, order) for t in TERMS for order in (0, 1) if not (t in [(X, "T", Y), (X, "T", Z), (Y, "T", Z)] and order == 1)]
assert len(COEFS) == 27


def forward(p, q):
    """Part coordinates of the tool point commanded to q (n x 3), with coefficients p."""
    n = len(q)
    trans = {a: np.zeros((n, 3)) for a in (X, Y, Z)}
    rot = {a: np.zeros((n, 3)) for a in (X, Y, Z)}
    for value, ((axis, kind, comp), order) in zip(p, COEFS):
        carrier = axis  # squareness carriers of YXFZ at the part end are X (xWy, xWz) and Y (yWz): the term's own
        term = value * (q[:, carrier] / HALF[carrier]) ** order
        if kind == "T":
            trans[axis][:, comp] += term
        elif kind == "R":
            rot[axis][:, comp] += term
        else:
            trans[carrier][:, comp] -= q[:, carrier] * term
    w = trans[Z] + np.c_[np.zeros(n), np.zeros(n), q[:, Z]]  # tool side: +q; Z carries no error in this model
    for axis in (Y, X):  # part side, -q, inverse small-angle rotation
        t = trans[axis].copy()
        t[:, axis] -= q[:, axis]
        v, e = w - t, rot[axis]
        w = (v - np.cross(e, v) + e * np.sum(e * v, axis=1, keepdims=True)) / (1 + np.sum(e * e, axis=1, keepdims=True))
    return w


def read_centres(path):
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return {r[0]: [float(v) for v in r[1:4]] for r in rows[1:]}


def main():
    batch = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "samples/bar17")
    free, ref = [], []
    for name in json.loads((batch / "batch.json").read_text())["identify"]:
        f, s = read_centres(batch / f"{name}.free.csv"), read_centres(batch / f"{name}.stitched.csv")
        for key in f.keys() & s.keys():
            free.append(f[key]), ref.append(s[key])
    free, ref = np.array(free), np.array(ref)
    start = time.perf_counter()
    fit = least_squares(lambda p: (forward(p, free) - ref).ravel(), np.zeros(len(COEFS)), x_scale="jac")
    seconds = time.perf_counter() - start
    rms = lambda r: 1000 * np.sqrt(np.mean(np.sum(r.reshape(-1, 3) ** 2, axis=1)))
    print(f"{len(free)} centres, {len(COEFS)} coefficients: rms 3D error {rms(forward(np.zeros(27), free) - ref):.2f} "
          f"-> {rms(fit.fun):.2f} um, {fit.nfev} evaluations, {seconds * 1000:.1f} ms (fit only)")


if __name__ == "__main__":
    main()
