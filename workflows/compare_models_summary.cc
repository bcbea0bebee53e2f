// What `fvm compare` prints and its --json document, from the comparison itself.

#include <fmt/core.h>

#include "workflows/compare_models.h"

namespace fvm::workflows {
namespace {

nlohmann::json FrameFreeJson(const stage::FrameFreeStats& s) {
  return {{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
          {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
}

nlohmann::json ScoreJson(const ModelScore& s) {
  const stage::IdentificationResult& id = s.identification;
  return {{"model", s.model},
          {"n_params", s.nominal},
          {"n_identified", id.calibration.layout.NumFree()},
          {"fixed", id.fixed.size()},
          {"identification",
           {{"mean_um", id.residual_summary.mean_um()}, {"rms_um", id.residual_summary.rms_um()}, {"max_um", id.residual_summary.max_um()}}},
          {"validation",
           {{"centres", s.validation.count},
            {"mean_um", s.validation.mean_mm * 1e3},
            {"rms_um", s.validation.rms_mm * 1e3},
            {"max_um", s.validation.max_mm * 1e3},
            {"predicted_rms_um", s.validation.predicted_rms_mm * 1e3},
            {"rigid", FrameFreeJson(s.rigid)},
            {"distances", FrameFreeJson(s.distances)}}},
          {"distance_error_um", {{"rms", s.distance_error_rms_mm * 1e3}}},
          {"aic", s.aic},
          {"bic", s.bic},
          {"condition", id.condition_number},
          {"converged", id.converged}};
}

const char* ValidationBy(const ModelComparison& c) {
  return c.validation_placements ? "batch.json validate placements" : "leave-one-placement-out";
}

// Frame-free figures first: the rigid fit per placement and the distances over all pairs, then the first tile's.
std::string Table(const ModelComparison& c, const CompareOptions& options, const std::string& batch_name) {
  std::string text = fmt::format("fvm compare: {} (validation: {})\n\n", batch_name, ValidationBy(c));
  text += fmt::format("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "model",
                      "params", "fixed", "id rms", "rigid", "predicted", "dist", "predicted", "1st-tile", "max", "predicted", "AIC",
                      "BIC", "cond");
  text += fmt::format("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "", "", "",
                      "um", "rms um", "rms um", "rms um", "rms um", "rms um", "um", "rms um", "", "", "");
  for (const ModelScore& s : c.scores) {
    const stage::IdentificationResult& id = s.identification;
    text += fmt::format("  {:>5} {:>6} {:>6} | {:>8.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>8.2f} {:>9.2f} | {:>9.1f} "
                        "{:>9.1f} {:>8.3g}\n",
                        s.model, s.nominal, id.fixed.size(), id.residual_summary.rms_um(), s.rigid.rms_mm * 1e3,
                        s.rigid.predicted_rms_mm * 1e3, s.distances.rms_mm * 1e3, s.distances.predicted_rms_mm * 1e3,
                        s.validation.rms_mm * 1e3, s.validation.max_mm * 1e3, s.validation.predicted_rms_mm * 1e3, s.aic, s.bic,
                        id.condition_number);
  }
  text += fmt::format("  (first tile: each placement in its first tile's {} frame)\n", options.settings.stitched_frame);
  text += fmt::format("\n  {}\n", c.recommendation);
  return text;
}

}  // namespace

Summary Summarize(const ModelComparison& comparison, const CompareOptions& options, const std::string& batch_name) {
  Summary summary;
  nlohmann::json doc;  // sorted keys, as the command has always printed them
  doc["validation_by"] = ValidationBy(comparison);
  doc["stitched_frame"] = options.settings.stitched_frame;
  for (const ModelScore& s : comparison.scores) doc["models"].push_back(ScoreJson(s));
  doc["recommendation"] = comparison.recommendation;
  summary.text = Table(comparison, options, batch_name);
  summary.json = doc;
  return summary;
}

}  // namespace fvm::workflows
