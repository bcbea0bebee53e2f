#pragma once
// Compensation with an identified model (`fvm correct`): a stitching-free centre export corrected point by point
// with the standard uncertainties the model's covariance gives, and a machine's compensation table (the commands
// that put the tool where the error-free machine would).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/centre_export.h"
#include "artefacts/io/point_list.h"
#include "stage/calibration.h"
#include "stage/stitched_frame.h"

namespace fvm::workflows {

struct CorrectedCentre {
  const artefacts::CentreRecord* input = nullptr;  // the export's row
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
  Eigen::Vector3d u = Eigen::Vector3d::Zero();         // standard uncertainties, mm
  double shift_mm = 0.0;                               // |corrected - measured|
};

struct CentreCorrection {
  std::vector<CorrectedCentre> centres;  // the export's order
  // --frame first-tile: the first tile's encoder reading the result is referred to; none in the stage frame.
  std::optional<Eigen::Vector3d> first_tile_mm;
  double largest_shift_mm = 0.0;
};

// In the stage frame (the model's part frame) without `first_tile_frame`; with it, where a stitched measurement of
// the same centres started at the export's first tile and turned with the stage there (that frame) puts them.
// Throws InputError (naming `name`) for an export without centres in the first-tile frame.
CentreCorrection CorrectCentres(const stage::Calibration& calibration, const artefacts::CentreExport& centres,
                                std::optional<stage::StitchedFrame> first_tile_frame, const std::string& name);

struct CompensatedPoint {
  const artefacts::ListedPoint* nominal = nullptr;  // the list's point
  Eigen::Vector3d command = Eigen::Vector3d::Zero();  // puts the tool point where the error-free machine puts it
  Eigen::Vector3d correction_mm = Eigen::Vector3d::Zero();  // command - nominal
};

// Throws InputError naming `name` and the point where the model's inverse does not converge.
std::vector<CompensatedPoint> CompensationTable(const stage::Calibration& machine,
                                                const std::vector<artefacts::ListedPoint>& points,
                                                const std::string& name);

}  // namespace fvm::workflows
