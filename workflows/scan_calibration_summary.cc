// The summary of `fvm calibrate --scan` (calibration_summary.h): what the scans registered, what no scan can tell,
// the predicted uncertainty of the xy stage error, and the held-out placements of --validate.

#include <fmt/core.h>

#include "stage/io/calibration_file.h"
#include "workflows/calibration_summary.h"

namespace fvm::workflows {
namespace {

// Each scan's tiles and pairs, and the pairs not used with why.
nlohmann::json ScansJson(const std::vector<artefacts::RegisteredScan>& scans) {
  nlohmann::json all;
  for (const auto& scan : scans) {
    nlohmann::json j = {{"name", scan.name}, {"tiles", scan.encoder_mm.size()}, {"pairs", scan.registration.pairs.size()},
                        {"searched_again", scan.registration.pairs_searched_again}};
    int ok = 0;
    for (const auto& pair : scan.registration.pairs) {
      if (pair.accepted) {
        ++ok;
      } else {
        j["rejected"].push_back({{"tiles", {pair.a + 1, pair.b + 1}}, {"reason", pair.rejection}});
      }
    }
    j["registered"] = ok;
    all.push_back(j);
  }
  return all;
}

nlohmann::json PredictedJson(const ScanCalibrationResult& r) {
  return {{"pair_weights", r.predicted_xy_um},
          {"pair_weights_without_pixel_size", r.predicted_without_pixel_um},
          {"independent_positions", r.predicted_independent_um},
          {"model_misfit_along_scans", r.fitted.split.misfit_mm * 1e3},
          {"model_misfit_at_point_um", {r.fitted.split.misfit_at_point_mm.x() * 1e3, r.fitted.split.misfit_at_point_mm.y() * 1e3}},
          {"combined", r.predicted_xy_with_misfit_um},
          {"white_residual_ratio", r.fitted.split.white_ratio},
          {"what", "standard uncertainty of the xy stage error, rms over the box the scans cover, "
                   "less the offset and the turn about z no registered image can tell: from the "
                   "coefficients' covariance (pair weights, the white part of the residuals, the "
                   "registrations' sub-pixel bias, the misfit the coefficients took up), and what "
                   "the model leaves along the scans (misfit), combined"}};
}

nlohmann::json ScanJson(const ScanCalibrationRun& run) {
  const CalibrateJobOptions& options = run.options;
  nlohmann::json doc = stage::CalibrationToJson(run.calibration.fitted.result);
  doc["stitched_frame"] = options.settings.stitched_frame;
  doc["pixel_mm"] = options.pixel_mm;
  doc["pixel_u_mm"] = options.pixel_u_mm;
  if (run.field) {
    doc["distortion"] = DistortionJson(run.field->fit, run.field->identified, options.pixel_mm);
  }
  doc["scans"] = ScansJson(run.scans);
  // What no image of a scan can tell, whatever the rank analysis finds on these data (it takes the pixel size as
  // given): the scale of the pixels, and the camera's turn against the stage axes.
  doc["cannot_tell"] = {
      {{"what", "the pixel size"}, {"aliases", {"xTx1", "yTy1"}},
       {"fixed_by", "--pixel-mm (its uncertainty --pixel-u-mm propagates), or one known length"}},
      {{"what", "the camera's rotation against the stage axes"}, {"aliases", {"xRz0", "yRz0", "xWy0"}},
       {"fixed_by", "the first tile's frame: the result is in it (stitched_frame.h), as an artefact calibration's is"}}};
  doc["predicted_xy_u_um"] = PredictedJson(run.calibration);
  if (run.calibration.judged) {
    doc["validation"] = ValidationJson(*run.calibration.judged, options.settings.Frame());
    doc["validation"]["batch"] = options.validate;
    doc["validation"]["note"] = "grey tiles show no heights: z terms stay at 0; the 3-D figures keep the stage's z errors, the distances hardly see them";
    doc["validation"]["placements"] = run.calibration.validation_placements;
  }
  return doc;
}

// The registrations: a line per scan (and per pair not used), then the totals and the frame.
std::string RegistrationsText(const ScanCalibrationRun& run) {
  std::string text;
  int tiles = 0, pairs = 0, registered = 0;
  for (const auto& scan : run.scans) {
    int ok = 0;
    std::string rejected;
    for (const auto& pair : scan.registration.pairs) {
      if (pair.accepted) {
        ++ok;
      } else {
        rejected += fmt::format("    tiles {}-{} not used: {}\n", pair.a + 1, pair.b + 1, pair.rejection);
      }
    }
    text += fmt::format("  {}: {} tiles, {} of {} neighbour pairs registered\n", scan.name, scan.encoder_mm.size(), ok,
                        scan.registration.pairs.size()) + rejected;
    tiles += static_cast<int>(scan.encoder_mm.size());
    pairs += static_cast<int>(scan.registration.pairs.size());
    registered += ok;
  }
  text += fmt::format("  {} tiles, {} of {} pairs registered; pixel {:.6g} mm (u {:.2g} mm); frame: the first tile of {}, {}\n",
                      tiles, registered, pairs, run.options.pixel_mm, run.options.pixel_u_mm, run.scans.front().name,
                      run.options.settings.stitched_frame);
  return text;
}

// What the fit left, and the uncertainty it predicts.
std::string ScanFitText(const ScanCalibrationRun& run) {
  const ScanCalibrationResult& r = run.calibration;
  const stage::IdentificationResult& result = r.fitted.result;
  std::string text =
      "\n  no scan can tell the pixel size from xTx1, yTy1 (taken from --pixel-mm), nor the camera's turn against\n"
      "  the stage axes from the constant yaw and squareness xRz0, yRz0, xWy0 (the result is in the first tile's frame)\n";
  text += fmt::format("\n  registered displacements after the fit: rms {:.3f} um (weighted rms {:.2f}: 1 = as the registrations' own "
                      "covariances say)\n", result.residual_summary.rms_um(), result.weighted_rms);
  text += fmt::format("  the residuals' white part is {:.2f} x the registrations' covariance; chained along the scans they leave "
                      "{:.3f} um rms that the model cannot take at a point (x {:.3f}, y {:.3f}: each axis' along the scans "
                      "that move it)\n", r.fitted.split.white_ratio, r.fitted.split.misfit_mm * 1e3,
                      r.fitted.split.misfit_at_point_mm.x() * 1e3, r.fitted.split.misfit_at_point_mm.y() * 1e3);
  text += fmt::format("  predicted xy stage-error uncertainty over the scanned box, less its offset and turn about z (k=1): {:.3f} um rms "
                      "from the coefficients", r.predicted_xy_um);
  if (run.options.pixel_u_mm > 0.0) text += fmt::format(" ({:.3f} um without the pixel size's)", r.predicted_without_pixel_um);
  text += fmt::format(", {:.3f} um with the misfit\n", r.predicted_xy_with_misfit_um);
  text += fmt::format("  the same positions as independent points of equal weight: {:.3f} um (the chain's correlation ignored)\n",
                      r.predicted_independent_um);
  return text;
}

std::string ScanSource(const ScanCalibrationRun& run) {
  return fmt::format("{} scans ({})", run.scans.size(), JoinNames(run.layouts));
}

std::string ScanText(const ScanCalibrationRun& run) {
  const stage::IdentificationResult& result = run.calibration.fitted.result;
  const stage::Calibration& cal = result.calibration;
  std::string text = fmt::format("fvm calibrate: model {} ({} chain, eq. 1) on {}\n", cal.model, cal.layout.chain().code,
                                 ScanSource(run));
  text += RegistrationsText(run);
  if (run.field) {
    text += DistortionText(run.field->fit, run.field->identified, run.options.pixel_mm);
    if (run.field->identified) {
      text += fmt::format("    its u widened {:.2f} times: the overlaps' quarters scatter that much more than their points "
                          "(no loop of the chains checks them)\n", run.field->fit.block_scatter_factor);
    }
  }
  text += fmt::format("  solver: {} in {} iterations; condition number {:.3g}\n",
                      result.converged ? "converged" : "NOT converged", result.iterations, result.condition_number);
  text += ParameterTable(result) + ScanFitText(run);
  if (run.calibration.validation) {
    text += ValidationText(*run.calibration.judged, run.options.settings.Frame());
    text += "  grey tiles show no heights: the scans leave the z terms at 0, so the 3-D figures above keep the stage's\n"
            "  z errors; the distances, which z hardly changes on a flat artefact, judge the scan calibration\n";
  }
  return text;
}

}  // namespace

Summary Summarize(const ScanCalibrationRun& run) {
  Summary summary{ScanJson(run), ScanText(run), std::nullopt};
  const ScanCalibrationResult& r = run.calibration;
  if (r.judged) {
    summary.report = CalibrationReport(ScanSource(run), r.fitted.result, *r.validation,
                                       "validation placements of " + run.options.validate, *r.judged,
                                       run.options.settings.Frame());
  }
  return summary;
}

}  // namespace fvm::workflows
