#pragma once
// fvm multilaterate as a job: points located from the ranges (and angles) of several tracker stations, the stations
// known or calibrated with the points (stage/multilateration.h), each point with its covariance; the points as
// tracker readings for a verification, and their error against known true positions. Refusals name the files
// (and the options as the command line spells them).

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/point_list.h"
#include "artefacts/io/tracker_readings.h"
#include "stage/multilateration.h"
#include "stage/residual_summary.h"

namespace fvm::workflows {

struct MultilaterateOptions {
  std::string readings;               // id,station,range (mm) [,azimuth,elevation (rad)] [,x,y,z]
  std::string stations;               // stations JSON; empty: none (a self-calibration then starts from the angles)
  bool self_calibrate = false;        // estimate the stations with the points (at least 4 stations)
  bool angles = false;                // use azimuth and elevation too (bundle adjustment)
  std::string tracker = "published";  // noise preset for the weights
  std::string nominal;                // nominal machine coordinates id,x,y,z; empty: the readings' x,y,z columns
  std::string truth;                  // true positions id,x,y,z in the same frame: each point's error; empty: none
  // Refuses an unknown tracker preset (--tracker) and no readings file.
  void Check() const;
};

struct Multilateration {
  artefacts::MultilaterationReadings data;
  stage::MultilaterationProblem problem;  // points in file order, stations in the stations file's (or first seen)
  stage::MultilaterationOptions options;
  stage::MultilaterationResult result;
  // "bundle adjustment: ranges and angles" or "ranges only".
  std::string Mode() const;
  // Each point with its standard uncertainties (the covariance's diagonal), in the problem's order.
  std::vector<artefacts::MultilateratedPoint> Points() const;
  double u_mean_mm = 0, u_max_mm = 0;  // of the points' 3-D standard uncertainty |u|
};

// Reads, checks (stations without readings, readings of stations not in the file, a self-calibration with fewer
// than 4 stations: what stays unobservable) and solves. A result that did not converge is returned as it is.
Multilateration Multilaterate(const MultilaterateOptions& options);

// The points' nominal machine coordinates: from `nominal_file` (id,x,y,z[,approach]) when given, else the readings'
// x,y,z columns; empty when neither has them.
std::map<std::string, artefacts::ListedPoint, std::less<>> NominalCoordinates(const Multilateration& m,
                                                                              const std::string& nominal_file);

// The multilaterated points as tracker readings (nominal x,y,z; xt,yt,zt the point in the stations' frame) for a
// machine verification, to be written to `target` (named in refusals as --verify-readings). Throws InputError when
// `nominal` is empty or misses a point.
artefacts::TrackerReadings VerifyReadings(const Multilateration& m, const MultilaterateOptions& options,
                                          const std::map<std::string, artefacts::ListedPoint, std::less<>>& nominal,
                                          const std::string& nominal_file, const std::string& target);

// Distances between the multilaterated points and their true positions (mm).
// `truth_file`: id,x,y,z in the same frame (simulations: true_points.csv); a point missing there is an InputError.
stage::ResidualSummary ErrorAgainstTruth(const Multilateration& m, const std::string& truth_file);

}  // namespace fvm::workflows
