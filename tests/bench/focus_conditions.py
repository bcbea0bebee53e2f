#!/usr/bin/python3
"""`fvm focus` against ../shared/bench/focusgen.py over the optics and textures of issue 47.

Renders focusgen.py's scene (a tilted textured face with a 35 um calotte, walls to 24 deg, 1 um pixels and steps) for
each seed and condition (NA, diffraction floor sigma0, texture correlation), reconstructs it with `fvm focus
--uncertainty`, and scores each region as ../shared/bench/check does (flat beyond the rim + 3 px, wall from half the
footprint radius to the rim - 3 px, bottom inside half the radius, 5 px border left out): rms error in z-steps, the
95 % coverage of 1.96 u_z, and the rms of error / u_z. Prints a markdown table, one row per seed and condition.

Usage: /usr/bin/python3 tests/bench/focus_conditions.py [FVM] [SEEDS] [CONDITIONS]
       FVM defaults to build/fvm/fvm, SEEDS to 11,12, CONDITIONS to the 13 of the table on the focus page
       ("NA:SIGMA0_UM:TEXTURE_PX;..."). Needs ../shared/bench and Debian's python3-numpy, python3-tifffile. About
       15 s a stack on 2 cores.
"""
import itertools
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import tifffile

BENCH = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/bench"))
sys.path.insert(0, BENCH)
from fvmtiff import read_float_tiff  # noqa: E402  (reads float TIFFs with the floating-point predictor)

CORNERS = list(itertools.product([0.3, 0.9], [0.3, 0.8], [0.7, 2.0]))
DEFAULT = CORNERS + [(0.4, 0.6, 1.0), (0.6, 0.45, 1.5), (0.4, 0.6, 2.0), (0.9, 0.6, 1.0), (0.6, 0.8, 1.5)]


def run(fvm, work, seed, na, sigma0, texture):
    d = os.path.join(work, f"s{seed}_{na}_{sigma0}_{texture}")
    subprocess.run([sys.executable, os.path.join(BENCH, "focusgen.py"), d, "--seed", str(seed), "--na", str(na),
                    "--sigma0-um", str(sigma0), "--texture-px", str(texture)], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([fvm, "focus", f"{d}/stack.csv", "-o", f"{d}/h.tif", "--uncertainty", f"{d}/u.tif",
                    "--pixel-mm", "0.001"], check=True, stdout=subprocess.DEVNULL)
    truth = json.load(open(f"{d}/truth.json"))
    z_true = tifffile.imread(f"{d}/truth.tif")
    step = truth["step_mm"]
    info = truth["surface_info"]
    (cx, cy), a = info["centre_px"], info["footprint_radius_px"]
    r = np.hypot(np.arange(z_true.shape[1]) - cx, (np.arange(z_true.shape[0]) - cy)[:, None])
    e = read_float_tiff(f"{d}/h.tif").astype(float) - z_true
    u = read_float_tiff(f"{d}/u.tif").astype(float)
    inner = np.zeros(z_true.shape, bool)
    inner[5:-5, 5:-5] = True
    valid = inner & np.isfinite(e)
    regions = [valid & (r > a + 3), valid & (r > a / 2) & (r < a - 3), valid & (r < a / 2)]
    figures = [(np.sqrt(np.mean(e[s] ** 2)) / step, np.mean(np.abs(e[s]) <= 1.96 * u[s]),
                np.sqrt(np.mean((e[s] / u[s]) ** 2))) for s in regions]
    return figures, valid.sum() / inner.sum()


def main():
    fvm = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build/fvm/fvm")
    seeds = [int(s) for s in (sys.argv[2] if len(sys.argv) > 2 else "11,12").split(",")]
    conditions = ([tuple(float(x) for x in c.split(":")) for c in sys.argv[3].split(";")] if len(sys.argv) > 3
                  else DEFAULT)
    jobs = [(s, *c) for s in seeds for c in conditions]
    with tempfile.TemporaryDirectory() as work, ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda j: run(fvm, work, *j), jobs))
    print("| seed | NA | sigma0 um | texture px | flat: rms step, coverage, error/u_z | wall | bottom | valid |")
    print("|---|---|---|---|---|---|---|---|")
    for (seed, na, sigma0, texture), (figures, valid) in zip(jobs, results):
        cells = " | ".join(f"{rms:.3f} · {100 * cov:.1f} % · {z:.2f}" for rms, cov, z in figures)
        print(f"| {seed} | {na} | {sigma0} | {texture} | {cells} | {valid:.3f} |")
    coverage = [f[1] for figures, _ in results for f in figures]
    standardised = [f[2] for figures, _ in results for f in figures]
    print(f"\ncoverage {100 * min(coverage):.1f}-{100 * max(coverage):.1f} %, error / u_z rms "
          f"{min(standardised):.2f}-{max(standardised):.2f}")


if __name__ == "__main__":
    main()
