#!/usr/bin/python3
"""`fvm calibrate --scan`'s predicted u against ../shared/bench/scangen.py's truth at its 200 validation positions.

For each seed (and field distortion D, px) renders scangen's three scans (402 tiles of 512 px) into a temporary
directory, calibrates with model 27 (`--distortion` when D != 0), corrects validation.free.csv with `fvm correct`
(stage frame) and compares it with validation.truth.csv after the best rigid 2-D transform (linearised: offset and
turn about the points' centroid, the turns are 1e-4 rad). Each point's predicted u is judged as its error is seen:
the coefficients' share propagated jointly to the 200 points (a perturbation of the calibration along each
eigenvector of its covariance, by one standard deviation) with the same rigid motion projected out, plus the part
`fvm correct` adds beyond the coefficients (the model's unmodelled part). Prints a markdown table: rms / max
error, predicted u (rms), the printed `predicted_xy_u_um.combined`, error / combined, the rms of error / u per
coordinate, and the share within 1.96 u. With a field (D != 0), also the field's own-axis cubic terms against
scangen's radial field (k1 = D, every other term 0): x^3 in d_x (k1 + dx_x3) and y^3 in d_y (k1), miss / stated u.

Usage: /usr/bin/python3 tests/bench/scan_prediction_scangen.py [FVM] [SEED:D,...]
       FVM defaults to build/fvm/fvm, the runs to 2:0,5:0,7:0. About 1-2 min a run on 2 cores.
       FVM_SCANGEN_CACHE=DIR reads scans rendered before from DIR/s{SEED}_d{D}/ (scangen.py's output, only read)
       where they exist instead of rendering them again.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCANGEN = os.path.join(HERE, "..", "..", "..", "shared", "bench", "scangen.py")


def read_csv(path):
    rows = [line.strip().split(",") for line in open(path) if line.strip() and not line.startswith("#")]
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


def correct(fvm, cal, free):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "c.csv")
        subprocess.run([fvm, "correct", "--calibration", cal, free, "-o", out], capture_output=True, check=True)
        return read_csv(out)


def judge(fvm, d, distortion, work):
    cal = os.path.join(work, "cal.json")
    cmd = [fvm, "calibrate", "--scan", f"{d}/row.csv", "--scan", f"{d}/col.csv", "--scan", f"{d}/row2.csv",
           "--pixel-mm", "0.00275", "--model", "27", "-o", cal] + (["--distortion"] if distortion else [])
    subprocess.run(cmd, capture_output=True, check=True)
    doc = json.load(open(cal))
    free = f"{d}/validation.free.csv"
    head, base = correct(fvm, cal, free)
    ix, iy = head.index("x"), head.index("y")
    p = base[:, [ix, iy]]
    u = base[:, [head.index("u_x"), head.index("u_y")]]
    truth = read_csv(f"{d}/validation.truth.csv")[1][:, 1:3]
    n = len(p)
    names, cov = doc["free"], np.array(doc["covariance"])
    w, v = np.linalg.eigh(cov)
    columns = []
    for k in np.flatnonzero(w > 0):
        moved = json.loads(json.dumps(doc))
        for c in moved["parameters"]:
            if c["name"] in names:
                c["value"] += v[names.index(c["name"]), k] * np.sqrt(w[k])
        path = os.path.join(work, "moved.json")
        json.dump(moved, open(path, "w"))
        columns.append((correct(fvm, path, free)[1][:, [ix, iy]] - p).reshape(-1))
    jac = np.array(columns).T  # 2n x k: one standard deviation along each eigenvector
    centre = p.mean(axis=0)
    rigid = np.zeros((2 * n, 3))
    rigid[0::2, 0], rigid[1::2, 1] = 1, 1
    rigid[0::2, 2], rigid[1::2, 2] = -(p[:, 1] - centre[1]), p[:, 0] - centre[0]
    q = np.linalg.qr(rigid)[0]
    project = np.eye(2 * n) - q @ q.T
    e = project @ (p - truth).reshape(-1)
    seen = project @ jac
    coefficients2 = np.sum(seen ** 2, axis=1)
    unmodelled2 = np.maximum(u.reshape(-1) ** 2 - np.sum(jac ** 2, axis=1), 0.0)
    var = coefficients2 + unmodelled2
    z = e / np.sqrt(var)
    norm = np.linalg.norm(e.reshape(n, 2), axis=1)
    rms = np.sqrt(np.mean(norm ** 2)) * 1e3
    combined = doc["predicted_xy_u_um"]["combined"]
    cubic = {}
    if distortion:
        field = doc["distortion"]
        names = [t["name"] for t in field["terms"]]
        c, v = np.array([t["value_px"] for t in field["terms"]]), np.array(field["covariance_px2"])
        for key, terms in (("x3", ("k1", "dx_x3")), ("y3", ("k1",))):
            g = np.zeros(len(names))
            g[[names.index(t) for t in terms]] = 1.0
            cubic[key] = f"{g @ c - distortion:+.4f} / {np.sqrt(g @ v @ g):.4f}"
    return {**cubic, "rms_um": rms, "max_um": norm.max() * 1e3, "u_um": np.sqrt(2 * np.mean(var)) * 1e3, "combined_um": combined,
            "ratio": rms / combined, "z_rms": np.sqrt(np.mean(z ** 2)), "coverage": np.mean(np.abs(z) < 1.959964)}


def main():
    fvm = sys.argv[1] if len(sys.argv) > 1 else "build/fvm/fvm"
    runs = [r.split(":") for r in (sys.argv[2] if len(sys.argv) > 2 else "2:0,5:0,7:0").split(",")]
    print("| seed | D (px) | rms / max error (um) | predicted u, rms (um) | printed combined (um) | error / combined | "
          "standardised rms | 95 % coverage | x^3 in d_x: miss / u (px) | y^3 in d_y: miss / u (px) |\n"
          "|---|---|---|---|---|---|---|---|---|---|")
    cache = os.environ.get("FVM_SCANGEN_CACHE")
    z2, cover = [], []
    for seed, d_px in runs:
        with tempfile.TemporaryDirectory() as work:
            d = os.path.join(cache, f"s{seed}_d{d_px}") if cache else work
            if d == work or not os.path.isfile(os.path.join(d, "validation.truth.csv")):
                d = work
                subprocess.run([sys.executable, SCANGEN, d, "--seed", seed, "--distortion-px", d_px],
                               capture_output=True, check=True)
            r = judge(fvm, d, float(d_px), work)
        z2.append(r["z_rms"] ** 2), cover.append(r["coverage"])
        print(f"| {seed} | {d_px} | {r['rms_um']:.3f} / {r['max_um']:.2f} | {r['u_um']:.3f} | {r['combined_um']:.3f} | "
              f"{r['ratio']:.2f} | {r['z_rms']:.2f} | {100 * r['coverage']:.1f} % | {r.get('x3', '')} | {r.get('y3', '')} |",
              flush=True)
    print(f"| pooled | | | | | | {np.sqrt(np.mean(z2)):.2f} | {100 * np.mean(cover):.1f} % | | |")


if __name__ == "__main__":
    main()
