#pragma once
// Volumetric verification of a three-axis machine tool with a laser tracker, simulated ([IJSIMM 2016] sections 4-5):
// the point plan (mesh, cloud of [IJSIMM 2016] eq. 18, body diagonals), the CNC program that visits it, a machine whose
// geometric errors are known but are NOT the polynomials an identification fits, and the tracker readings of that
// machine with the published noise ([IJSIMM 2016] eqs. 22-24).
//
// Randomness: every draw comes from std::mt19937_64 seeded with the caller's seed, turned into uniform doubles
// (53 bits) and normal ones (Box-Muller) by this file's own code, not by std::*_distribution, whose algorithms the
// standard leaves to each library. The same seed therefore gives the same bits with any standard library on the
// same platform; only std::sin/cos/log/sqrt could differ in the last bit on another libm.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/tracker_readings.h"
#include "artefacts/machine_truth.h"
#include "artefacts/tracker_sight.h"
#include "stage/axis_chain.h"
#include "stage/error_terms.h"
#include "stage/pose.h"
#include "stage/residual_summary.h"
#include "stage/tracker.h"

namespace fvm::artefacts {

struct PlannedPoint {
  std::string id;                                     // P0001, P0002, ... in visiting order
  Eigen::Vector3d nominal = Eigen::Vector3d::Zero();  // commanded machine coordinates, mm (rounded to 1 um)
  std::string approach;                               // "+x" or "-x": the sign of X's last motion before the point
};

// A mesh with steps `step` (mm) per axis: nodes at min + i * step and always at max (a last, shorter step when
// the travel is no multiple of it). Order: X fastest, then Y, then Z, serpentine (boustrophedon): each row of X
// runs opposite to the previous one, each layer of Y rows too, so the machine never jumps back. Approach: the
// sign of the last X motion before the point (the first point counts as +x, approached from below). 2500 x
// 1500 x 1200 with steps 500, 500, 400 gives 6 * 4 * 4 = 96 points ([IJSIMM 2016] section 5); steps of 100 give 5408.
std::vector<PlannedPoint> PlanMesh(const Workspace& ws, const Eigen::Vector3d& step);
// The mesh, each coordinate strictly inside the travel moved by a uniform random amount in [-step/2, +step/2]
// of its axis (eq. 18: x_cloud = x_mesh +- rand(interval(x)) if x_min < x < x_max), rounded to 1 um; coordinates
// on the boundary stay there. Same order and approach rule as the mesh (approach from the actual motions).
std::vector<PlannedPoint> PlanCloud(const Workspace& ws, const Eigen::Vector3d& step, std::uint64_t seed);
// The 4 body diagonals, `points_per_diagonal` (>= 2) equally spaced points each, corners included, rounded to
// 1 um: (min,min,min)->(max,max,max), (max,min,min)->(min,max,max), (min,max,min)->(max,min,max),
// (max,max,min)->(min,min,max). The centre appears on each diagonal when points_per_diagonal is odd.
std::vector<PlannedPoint> PlanDiagonals(const Workspace& ws, int points_per_diagonal);

// An [ISO 6983-1] program (plain G-code, no controller-specific cycles) that visits the points:
//   %
//   (FVM VOLUMETRIC VERIFICATION: 96 POINTS, DWELL 6 S, FEED 2000 MM/MIN)
//   G90 G21 G17 G94          absolute, mm, XY plane, feed per minute
//   G0 X0.000 Y0.000 Z0.000 (P0001 +x)    rapid to the first point
//   G4 P6                    dwell in SECONDS (LinuxCNC, Siemens, Heidenhain; a Fanuc control reads P as ms:
//                            change P to X there)
//   G1 X500.000 Y0.000 Z0.000 F2000 (P0002 +x)   linear moves at the feed to the next points, each with its dwell
//   ...
//   M30
//   %
// Coordinates with 3 decimals (the plans are rounded to 1 um, so the program and points.csv agree). Comments
// carry the point id and approach. feed_mm_min <= 0 writes G0 moves throughout. Throws std::invalid_argument on
// a negative or non-finite dwell.
std::string GCodeProgram(const std::vector<PlannedPoint>& points, double dwell_s, double feed_mm_min = 2000.0);

// A random machine for `chain` (tool offset included; its instrument pose plays no part), seeded. Per term a
// cubic with random coefficients plus a sine:
//   positioning xTx, yTy, zTz: a ball-screw-like periodic error, pitch 10-40 mm, amplitude 8 % of the term's size;
//   straightness and rotation: one long wave, wavelength 0.3-0.8 of the travel, amplitude 25 % of the size;
//   squareness: a constant.
// Neither a cubic can represent: the screw period is far below the travel, the long wave has at least 1.25
// periods. Sizes per kind (positioning 20 um/m, straightness 10 um/m, rotation 20 urad, squareness 20 urad) are
// scaled together so that the mean volumetric error (|tool point displaced by the errors|) over an 11 x 11 x 11
// mesh of the workspace is `mean_error_um` ([IJSIMM 2016] Table I: 35.3 um).
MachineTruth RandomMachineTruth(const stage::AxisChain& chain, const Workspace& ws, std::uint64_t seed,
                                double mean_error_um = 35.0);
// The same for the published machine of [IJSIMM 2016]: chain XFYZ, tool offset (0, 0, 100) mm.
MachineTruth RandomMachineTruth(const Workspace& ws, std::uint64_t seed, double mean_error_um = 35.0);

// Volumetric error (mm) of the tool point commanded to q: ChainForward(e(q), q) - ChainForward(0, q) in the
// machine frame (the chain's instrument pose is ignored), and its length.
Eigen::Vector3d VolumetricErrorVector(const stage::AxisChain& chain, const MachineTruth& truth, const Eigen::Vector3d& q);
double VolumetricErrorMm(const stage::AxisChain& chain, const MachineTruth& truth, const Eigen::Vector3d& q);
// The volumetric errors of the truth at `points`.
stage::ResidualSummary VolumetricErrorSummary(const stage::AxisChain& chain, const MachineTruth& truth,
                                    const std::vector<PlannedPoint>& points);

// The tracker readings of the machine `truth` at `points`: the tool point ChainForward(chain, e(q), q) in the
// tracker frame (chain.instrument must be set: throws std::invalid_argument otherwise), converted to spherical
// coordinates, given normal noise (range sigma a + b * range, azimuth and elevation sigmas: noise.Covariance is
// the resulting Cartesian covariance) and converted back. Reproducible bit for bit for the same seed (see the
// top of this file). `noise_free`, when given, receives the same readings without noise (the truth). The readings
// are Cartesian; ids, nominal coordinates and approach come from the points.
TrackerReadings SimulateTrackerReadings(const stage::AxisChain& chain, const MachineTruth& truth,
                                        const std::vector<PlannedPoint>& points, const stage::TrackerNoise& noise,
                                        std::uint64_t seed, TrackerReadings* noise_free = nullptr);

// Multilateration: the same points read by several tracker stations (fvm multilaterate). Each station stands
// levelled at its position in the common frame, its azimuth zero along the common +x (identity rotation: a
// bundle adjustment estimates each station's rotation anyway). A reading is the range and the two angles of
// target - station with the preset's noise (range sigma a + b * range, angle sigmas), three normal draws per
// reading in the order point by point, station by station, so the same seed gives the same bits. `targets` are
// (id, true position in the common frame, mm); `nominal`, when not empty, is written as x,y,z beside them (same
// size). Rows: point by point, stations in the given order. Throws std::invalid_argument on a station at a
// target or mismatched sizes.
MultilaterationReadings SimulateMultilaterationReadings(const std::vector<Station>& stations,
                                                        const std::vector<std::pair<std::string, Eigen::Vector3d>>& targets,
                                                        const std::vector<Eigen::Vector3d>& nominal,
                                                        const stage::TrackerNoise& noise, std::uint64_t seed);

// The tool points of the machine `truth` at `points` in the machine frame (the chain's instrument pose ignored):
// what the stations of a multilateration see, and the truth to judge it against.
std::vector<std::pair<std::string, Eigen::Vector3d>> TrueToolPoints(const stage::AxisChain& chain, const MachineTruth& truth,
                                                                    const std::vector<PlannedPoint>& points);

}  // namespace fvm::artefacts
