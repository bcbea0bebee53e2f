#!/usr/bin/python3
"""Speed baseline only: the machine-tool model of `fvm verify --order 3 --basis legendre` (XFYZ, 21 error functions
and the tracker pose) fitted with scipy.optimize.least_squares(method="lm") and a numeric (forward-difference)
Jacobian, so that the whole `fvm verify` process can be timed against a plain Python fit of the same model on the
same readings. Not a second implementation to trust: no rank analysis, no uncertainties, no validation.

Model ([Aguado 2016] eq. 1, last term X; the convention of stage/axis_chain.h, small angles R = I + [e]x):
    X_LT = R_LT^T ( R_X^-1 ( R_Y ( R_Z T + Z ) + Y - X ) - T_LT )
    X = (-x + xTx, xTy, xTz);  Y = (yTx - y xWy, y + yTy, yTz);  Z = (zTx - z xWz, zTy - z yWz, z + zTz)
each term a Legendre series of order 3 in u = (q - mid-travel) / half-travel of its own axis, the squareness terms
constants; R_k = I + [(kRx, kRy, kRz)]x; the tracker pose (T_LT, rotation vector of R_LT) is estimated jointly,
starting from the rigid best fit [Umeyama 1991] of the readings to the ideal machine. Residuals are whitened by each
reading's covariance under the published tracker noise (range 4 um + 0.8 um/m, angles 24 urad), as fvm verify
weights them.

Free coefficients: the 39 that fvm verify keeps on a full mesh of this chain (the other 36 alias the pose or each
other and are fixed at zero), or those of an `fvm verify --json` output given with --fixed-from.

Usage: /usr/bin/python3 tests/bench/scipy_verify.py DIR/readings.csv [--fixed-from verify.json]
       (readings from `fvm simulate tracker --points mesh:100,100,100 --seed 1 --tool 0,0,100 -o DIR`;
        Debian python3-scipy: apt-get install --no-install-recommends python3-scipy)
"""
import csv, json, sys, time

import numpy as np
from scipy.optimize import least_squares

TRAVEL_MIN = np.array([0.0, 0.0, 0.0])
TRAVEL_MAX = np.array([2500.0, 1500.0, 1200.0])  # --machine 2500x1500x1200 (the span of the mesh)
TOOL = np.array([0.0, 0.0, 100.0])
ORDER = 3
AXES = "xyz"
TERMS = [a + k + c for a in AXES for k in "TR" for c in AXES]  # xTx xTy xTz xRx xRy xRz yTx ...
SQUARENESS = ["xWy", "xWz", "yWz"]
COEFS = [f"{t}{p}" for t in TERMS for p in range(ORDER + 1)] + SQUARENESS
# What fvm verify's rank treatment fixes for XFYZ, order 3, estimated pose, on a full 3D mesh: constant terms that
# the pose absorbs, first-order terms equal to squareness plus pose, rotations with no lever arm (the tool sits on
# the Z axis), and Z's pitch and roll of order >= 2, which the tool's 100 mm offset makes aliases of zTx, zTy.
FIXED = ("xTx0 xTy0 xTz0 yTx0 yTy0 yTz0 zTx0 zTy0 zTz0 xRz0 yRz0 zRz0 xRx0 xRy0 yRx0 yRy0 zRx0 zRy0 xTy1 xTz1 "
         "yTx1 yTz1 zTx1 zTy1 yRz1 zRz1 zRx1 zRy1 yRz2 zRz2 zRx2 zRy2 yRz3 zRz3 zRx3 zRy3").split()
SIGMA_RANGE_A, SIGMA_RANGE_B, SIGMA_ANGLE = 0.004, 0.8e-6, 24e-6  # mm, mm/mm, rad


def read_readings(path):
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    q = np.array([[float(r[k]) for k in "xyz"] for r in rows])
    m = np.array([[float(r[k]) for k in ("xt", "yt", "zt")] for r in rows])
    return q, m


def whitening(m):
    """L^-1 of each reading's covariance J diag(sr^2, sa^2, se^2) J^T (n x 3 x 3)."""
    r = np.linalg.norm(m, axis=1)
    az = np.arctan2(m[:, 1], m[:, 0])
    el = np.arcsin(m[:, 2] / r)
    ca, sa, ce, se = np.cos(az), np.sin(az), np.cos(el), np.sin(el)
    j = np.stack([np.stack([ce * ca, -r * ce * sa, -r * se * ca], -1),
                  np.stack([ce * sa, r * ce * ca, -r * se * sa], -1),
                  np.stack([se, np.zeros_like(r), r * ce], -1)], 1)
    var = np.stack([(SIGMA_RANGE_A + SIGMA_RANGE_B * r) ** 2, np.full_like(r, SIGMA_ANGLE ** 2),
                    np.full_like(r, SIGMA_ANGLE ** 2)], -1)
    cov = np.einsum("nij,nj,nkj->nik", j, var, j)
    return np.linalg.inv(np.linalg.cholesky(cov))


def legendre(u):
    """P0..P3 at u (n x 4)."""
    return np.stack([np.ones_like(u), u, 1.5 * u * u - 0.5, 2.5 * u ** 3 - 1.5 * u], -1)


def cross(a, b):
    return np.cross(a, b)


def rotation_matrix(v):
    theta = np.linalg.norm(v)
    if theta < 1e-300:
        return np.eye(3)
    k = v / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


class Model:
    def __init__(self, q, fixed):
        self.q = q
        u = (q - 0.5 * (TRAVEL_MIN + TRAVEL_MAX)) / (0.5 * (TRAVEL_MAX - TRAVEL_MIN))
        self.basis = [legendre(u[:, k]) for k in range(3)]  # per axis, n x 4
        self.free = [c for c in COEFS if c not in fixed]
        self.index = {c: i for i, c in enumerate(self.free)}

    def terms(self, coef):
        """Values of the 18 T/R terms (dict of n-vectors) and the 3 squareness constants."""
        values = {}
        for t in TERMS:
            axis = AXES.index(t[0])
            v = np.zeros(len(self.q))
            for p in range(ORDER + 1):
                i = self.index.get(f"{t}{p}")
                if i is not None:
                    v = v + coef[i] * self.basis[axis][:, p]
            values[t] = v
        w = {s: coef[self.index[s]] if s in self.index else 0.0 for s in SQUARENESS}
        return values, w

    def tool_points(self, coef):
        """Part (machine) frame coordinates of the tool point at every command (n x 3)."""
        e, w = self.terms(coef)
        x, y, z = self.q[:, 0], self.q[:, 1], self.q[:, 2]
        vec = lambda a, b, c: np.stack([a, b, c], -1)
        tx = vec(-x + e["xTx"], e["xTy"], e["xTz"])
        ty = vec(e["yTx"] - y * w["xWy"], y + e["yTy"], e["yTz"])
        tz = vec(e["zTx"] - z * w["xWz"], e["zTy"] - z * w["yWz"], z + e["zTz"])
        rx, ry, rz = (vec(e[a + "Rx"], e[a + "Ry"], e[a + "Rz"]) for a in AXES)
        t = np.broadcast_to(TOOL, self.q.shape)
        v = tz + t + cross(rz, t)           # Z(T) = R_Z T + Z
        v = ty + v + cross(ry, v)           # Y(.) = R_Y . + Y
        v = v - tx                          # R_X^-1 (. - X), the exact inverse of I + [rx]x
        return (v - cross(rx, v) + rx * np.sum(rx * v, 1, keepdims=True)) / (1 + np.sum(rx * rx, 1, keepdims=True))

    def in_tracker(self, coef, pose6):
        return (self.tool_points(coef) - pose6[:3]) @ rotation_matrix(pose6[3:])


def rigid_start(part, tracker):
    """Umeyama: part = R tracker + t; returns (t, rotation vector of R)."""
    mp, mt = part.mean(0), tracker.mean(0)
    u, s, vt = np.linalg.svd((part - mp).T @ (tracker - mt))
    d = np.sign(np.linalg.det(u @ vt))
    r = u @ np.diag([1, 1, d]) @ vt
    angle = np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / (2 * np.sin(angle))
    return np.concatenate([mp - r @ mt, angle * axis])


def main():
    args = sys.argv[1:]
    if not args or args[0].startswith("-"):
        sys.exit(__doc__)
    fixed = FIXED
    if "--fixed-from" in args:
        fixed = [f["name"] for f in json.loads(open(args[args.index("--fixed-from") + 1]).read())["fixed"]]
    q, measured = read_readings(args[0])
    start = time.perf_counter()
    whiten = whitening(measured)
    model = Model(q, set(fixed))
    n = len(model.free)
    # Parameters in units of their plausible size (0.5 mm, 1 mrad at the end of the travel; pose 1 mm, 1 mrad).
    scale = np.array([1e-3 if ("R" in c or "W" in c) else 0.5 for c in model.free] + [1.0] * 3 + [1e-3] * 3)
    pose0 = rigid_start(model.tool_points(np.zeros(n)), measured)

    def unpack(p):
        x = p * scale
        return x[:n], pose0 + x[n:]

    def residuals(p):
        coef, pose6 = unpack(p)
        return np.einsum("nij,nj->ni", whiten, model.in_tracker(coef, pose6) - measured).ravel()

    fit = least_squares(residuals, np.zeros(n + 6), method="lm", x_scale="jac")
    seconds = time.perf_counter() - start
    coef, pose6 = unpack(fit.x)
    initial = np.linalg.norm(model.in_tracker(np.zeros(n), pose0) - measured, axis=1) * 1e3
    final = np.linalg.norm(model.in_tracker(coef, pose6) - measured, axis=1) * 1e3
    print(f"{len(q)} points, {n} coefficients + 6 pose: volumetric error mean {initial.mean():.2f} um (ideal machine, "
          f"rigid pose) -> max {final.max():.1f} / mean {final.mean():.2f} / min {final.min():.2f} um; "
          f"cost {fit.cost:.6g}, {fit.nfev} evaluations, {seconds:.3f} s (fit only); {fit.message}")


if __name__ == "__main__":
    main()
