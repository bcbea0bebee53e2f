#include "stage/network_plausibility.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "stage/plausibility.h"

namespace fvm::stage {

void CheckRangesSpanANetwork(const MultilaterationProblem& problem, const MultilaterationOptions& options) {
  if (!options.self_calibrate || problem.readings.empty()) return;
  double longest = 0;
  for (const StationReading& r : problem.readings) longest = std::max(longest, r.range_mm);
  const double least = kMinStationSeparationSigmas * RangeSigmaMm(options.noise, 0.0);
  if (longest < least) {
    throw ImplausibleFit(fmt::format(
        "every range is at most {:.4g} mm, shorter than {:.0f} range sigmas ({:.3g} mm): a self-calibration would put "
        "the stations collapsed onto one spot, which is no network. It needs the tracker at distinct places with "
        "ranges of its working distance; check the range column's units (mm)",
        longest, kMinStationSeparationSigmas, least));
  }
}

void CheckNetworkPlausible(const MultilaterationProblem& problem, const MultilaterationOptions& options,
                           const MultilaterationResult& result) {
  // Residuals against the noise model.
  const size_t n = std::min(problem.readings.size(), result.range_residuals_mm.size());
  if (result.range_rms_sigmas > kMaxRangeRmsSigmas && n > 0) {
    size_t worst = 0;
    for (size_t k = 1; k < n; ++k) {
      const double a = std::abs(result.range_residuals_mm[k]) / RangeSigmaMm(options.noise, problem.readings[k].range_mm);
      const double b = std::abs(result.range_residuals_mm[worst]) / RangeSigmaMm(options.noise, problem.readings[worst].range_mm);
      if (a > b) worst = k;
    }
    const StationReading& r = problem.readings[worst];
    const double sigma = RangeSigmaMm(options.noise, r.range_mm);
    throw ImplausibleFit(fmt::format(
        "the ranges do not meet: their residuals are {:.3g} sigmas of the tracker's range noise (rms; tracker {}, "
        "{:.3g} mm at {:.4g} mm), where noise leaves about 1 and more than {:.0f} cannot be noise; worst: point {}, "
        "station {}, range {:.6g} mm, residual {:.4g} mm ({:.3g} sigmas). Check the range column's units (mm), that "
        "each reading names its station and point, and the station positions",
        result.range_rms_sigmas, options.noise.name, sigma, r.range_mm, kMaxRangeRmsSigmas,
        problem.point_ids[static_cast<size_t>(r.point)], problem.station_names[static_cast<size_t>(r.station)], r.range_mm,
        result.range_residuals_mm[worst], std::abs(result.range_residuals_mm[worst]) / sigma));
  }
  if (!options.self_calibrate) return;
  // Stations on one spot.
  const double least = kMinStationSeparationSigmas * RangeSigmaMm(options.noise, 0.0);
  for (size_t a = 0; a < result.stations.size(); ++a) {
    for (size_t b = a + 1; b < result.stations.size(); ++b) {
      const double d = (result.stations[a] - result.stations[b]).norm();
      if (d < least) {
        double shortest = std::numeric_limits<double>::infinity(), longest = 0;
        for (const StationReading& r : problem.readings) {
          shortest = std::min(shortest, r.range_mm);
          longest = std::max(longest, r.range_mm);
        }
        throw ImplausibleFit(fmt::format(
            "the self-calibration put stations {} and {} {:.3g} mm apart, closer than {:.0f} range sigmas ({:.3g} mm): "
            "the stations collapsed onto one spot, which is no network (ranges from {:.4g} to {:.4g} mm). A "
            "self-calibration needs the tracker at distinct places with ranges of its working distance; check the "
            "range column's units (mm)",
            problem.station_names[a], problem.station_names[b], d, kMinStationSeparationSigmas, least, shortest, longest));
      }
    }
  }
}

}  // namespace fvm::stage
