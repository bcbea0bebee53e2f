#include "workflows/correct.h"

#include <fmt/core.h>

#include "core/input_error.h"
#include "stage/identification.h"
#include "stage/inverse_model.h"

namespace fvm::workflows {

CentreCorrection CorrectCentres(const stage::Calibration& calibration, const artefacts::CentreExport& centres,
                                std::optional<stage::StitchedFrame> first_tile_frame, const std::string& name) {
  std::optional<stage::FirstTileCompensation> first_tile;
  CentreCorrection out;
  if (first_tile_frame) {
    std::vector<Eigen::Vector3d> positions;
    for (const artefacts::CentreRecord& r : centres.centres) positions.push_back(r.position);
    if (positions.empty()) throw InputError(name + ": no centres, so no first tile");
    first_tile.emplace(calibration, *first_tile_frame, stage::FirstTile(positions));
    out.first_tile_mm = first_tile->frame().first_tile;
  }
  for (const artefacts::CentreRecord& r : centres.centres) {
    const stage::CorrectedPoint p = first_tile ? first_tile->Correct(r.position) : stage::Correct(calibration, r.position);
    const CorrectedCentre c{&r, p.position, p.covariance.diagonal().cwiseMax(0.0).cwiseSqrt(), (p.position - r.position).norm()};
    out.largest_shift_mm = std::max(out.largest_shift_mm, c.shift_mm);
    out.centres.push_back(c);
  }
  return out;
}

std::vector<CompensatedPoint> CompensationTable(const stage::Calibration& machine,
                                                const std::vector<artefacts::ListedPoint>& points,
                                                const std::string& name) {
  std::vector<CompensatedPoint> table;
  for (const artefacts::ListedPoint& p : points) {
    const stage::Compensation c = stage::CompensateCommand(machine, p.position);
    if (!c.converged || !c.command.allFinite()) {
      throw InputError(fmt::format("{}: point {}: the model's inverse did not converge at {}, {}, {} mm; is the point "
                                   "inside the travel the model was identified on?",
                                   name, p.id, p.position.x(), p.position.y(), p.position.z()));
    }
    table.push_back({&p, c.command, c.command - p.position});
  }
  return table;
}

}  // namespace fvm::workflows
