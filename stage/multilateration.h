#pragma once
// Multilateration: points measured by several laser-tracker stations, located from the ranges (and, for a
// bundle adjustment, the angles too), with the stations known or calibrated together with the points ([Aguado 2016]
// section 4).
//
// Model. Station i sits at s_i in the common frame, its own frame rotated by R_i (only with angles). A reading of
// point p from station i is q = R_i^T (p - s_i) in spherical coordinates (stage/tracker.h): range |q|, azimuth
// and elevation. Each residual is divided by its sigma from the tracker's noise model (range a + b * range,
// angles constant), so the solve minimises the weighted sum of squares of [Aguado 2016] eqs. 10-16.
//
// Solver. Levenberg-Marquardt by Ceres, one residual block per reading (stage/station_reading_cost.h, automatic
// derivatives), the points eliminated block by block (each point is a 3x3 block; the station parameters form a small
// dense system, their Schur complement). With known stations and ranges only there are no station parameters and
// every point is its own 3-unknown solve. It starts in closed form (stage/multilateration_start.h).
//
// Frame of a self-calibration ([Aguado 2016] Figure 4): station 1 at the origin, station 2 on +x, station 3 in the xy
// plane (+y side); z follows by the right-hand rule. Ranges fix the scale. The starting stations (any frame) are moved
// into that frame first; results are in it.
//
// Rank. Before solving, the station parameters are examined on the Schur complement (the part of each
// parameter's effect the points cannot absorb), scaled to unit columns: a parameter the points absorb entirely,
// or one another parameter explains (stage/linear_dependence.h), is held at its start and named. Three stations
// with ranges only leave all three of their free coordinates so (3 n equations, 3 n + 3 unknowns), whatever n.
//
// Uncertainties (a priori, from the noise model; not scaled by the residuals): known stations, ranges only:
// (J^T W J)^-1 of each point's own solve; otherwise the point's block of the bundle's covariance, which includes
// the stations' uncertainty, in the frame of the result (for a self-calibration: relative to the 3-2-1 datum, so
// a point near station 1 is more certain than one far from it).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "stage/tracker.h"

namespace fvm::stage {

struct StationReading {
  int point = 0;    // index into MultilaterationProblem::point_ids
  int station = 0;  // index into MultilaterationProblem::station_names
  double range_mm = 0.0;
  bool has_angles = false;
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
};

struct MultilaterationProblem {
  std::vector<std::string> point_ids;
  std::vector<std::string> station_names;
  // Known positions (mm, common frame) or, for a self-calibration, starting values in any frame. May be empty for
  // a self-calibration whose readings all have angles: StartStationsFromAngles then supplies them.
  std::vector<Eigen::Vector3d> stations;
  std::vector<StationReading> readings;
};

struct MultilaterationOptions {
  TrackerNoise noise;               // weights (a "none" preset weighs ranges by 1 um and angles by 1 urad)
  bool self_calibrate = false;      // estimate the stations with the points (frame: see above)
  bool use_angles = false;          // bundle adjustment: azimuth and elevation too, each station's rotation estimated
  int max_iterations = 100;
  double rank_tolerance = 1e-6;     // relative part of a scaled station column the points leave unexplained
  void Check() const;               // throws std::invalid_argument
};

// The network's geometry at the solution: how well the lines of sight cross.
struct NetworkGeometry {
  // Angles between the lines of sight from a point to two stations, folded into 0-90 deg (90 is ideal for
  // ranges, 0 means the two ranges measure the same direction): min / mean / max over all pairs at all points.
  double min_angle_deg = 0, mean_angle_deg = 0, max_angle_deg = 0;
  // Position dilution of precision of the ranges: sqrt(trace((U^T U)^-1)) with U the unit lines of sight of a
  // point, i.e. its 3D uncertainty per unit range sigma with known stations. Mean and max over the points.
  double mean_pdop = 0, max_pdop = 0;
};

struct MultilaterationResult {
  std::vector<Eigen::Vector3d> points;             // mm, common frame (self-calibration: the 3-2-1 frame)
  std::vector<Eigen::Matrix3d> point_covariance;   // mm^2
  std::vector<Eigen::Vector3d> stations;           // mm
  std::vector<Eigen::Vector3d> station_u;          // standard uncertainty per coordinate, mm (0: held)
  std::vector<Eigen::Vector3d> station_rotation;   // rotation vector of each station's frame, rad (angles only)
  std::vector<std::string> unobservable;           // "station C y: ..." held at their start, with the reason
  std::vector<double> range_residuals_mm;          // per reading: |R^T (p - s)| - range
  double range_rms_mm = 0;
  double weighted_rms = 0;                         // sqrt(chi^2 / degrees of freedom); 0 without redundancy
  double range_rms_sigmas = 0;                     // rms of the range residuals in sigmas of the noise model
  int iterations = 0;
  bool converged = false;
  NetworkGeometry geometry;
};

// The range sigma the solve weighs a range by (mm): the noise model's a + b * range, or 1 um for a noise-free one.
double RangeSigmaMm(const TrackerNoise& noise, double range_mm);

// The least number of stations a point needs: 3 with known stations, 4 for a self-calibration.
int MinStationsPerPoint(const MultilaterationOptions& options);

// Throws std::invalid_argument naming the point or station on: a station with no readings, a point seen by fewer
// than MinStationsPerPoint stations, a point read twice by one station, a reading without angles under
// use_angles, a missing start, a self-calibration with fewer than 3 stations or stations on one line, and a
// point the geometry cannot fix (its lines of sight and the stations in one plane: its block is singular). Throws
// ImplausibleFit (stage/network_plausibility.h) when the ranges do not meet (residuals of thousands of sigmas) or a
// self-calibration collapses the stations onto one spot.
MultilaterationResult Multilaterate(const MultilaterationProblem& problem, const MultilaterationOptions& options);

// The station parameters a self-calibration cannot determine from these readings (at the start values), named
// with the reason; empty when every one is determined. Same checks as Multilaterate except the per-point count
// (so it can say why three stations are not enough).
std::vector<std::string> UnobservableStationParameters(const MultilaterationProblem& problem,
                                                       const MultilaterationOptions& options);

}  // namespace fvm::stage
