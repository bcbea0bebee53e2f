#pragma once
// What fvm multilaterate tells its user (workflows/summary.h): the --json document (points, stations, range rms,
// the network's geometry) and the printed lines, and the comment lines of the points file it writes.

#include <optional>
#include <string>
#include <vector>

#include "workflows/multilaterate.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// `truth_error`: the points against true positions read from `truth_file` (ErrorAgainstTruth), when given;
// `written`: what the front end writes ("points.csv and ml.csv (for fvm verify)"), empty when nothing.
Summary Summarize(const Multilateration& m, const MultilaterateOptions& options,
                  const std::optional<stage::ResidualSummary>& truth_error = std::nullopt,
                  const std::string& truth_file = "", const std::string& written = "");

// The header comments of the points file (-o): where the points came from, their frame and uncertainties.
std::vector<std::string> PointsFileComments(const Multilateration& m, const MultilaterateOptions& options);

}  // namespace fvm::workflows
