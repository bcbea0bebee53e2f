#include "workflows/scan_distortion.h"

#include <fmt/core.h>

#include "core/input_error.h"
#include "workflows/calibration_scans.h"

namespace fvm::workflows {

std::vector<artefacts::RegisteredScan> ReadAndRegisterUndistortedScans(const std::vector<std::string>& layouts,
                                                                       double pixel_mm, int threads, bool progress,
                                                                       const ScanDistortionOptions& options,
                                                                       ScanDistortion* field) {
  if (!options.known) imaging::FieldDistortionTermNames(options.order);  // throws outside 2..6
  options.matching.Check();
  options.fit.Check();
  const imaging::FieldDistortion guess = options.known.value_or(imaging::FieldDistortion{});
  std::vector<imaging::PairCorrespondences> matched;
  std::vector<Eigen::Vector2d> initial;
  std::vector<bool> fixed;
  int width = 0, height = 0;
  std::vector<artefacts::RegisteredScan> scans = ReadAndRegisterScans(
      layouts, pixel_mm, threads, progress,
      [&](const artefacts::RegisteredScan& scan, const std::vector<imaging::TileImage>& images) {
        if (width == 0) width = static_cast<int>(images.front().cols()), height = static_cast<int>(images.front().rows());
        if (images.front().cols() != width || images.front().rows() != height) {
          throw InputError(fmt::format("--distortion: scan {} has tiles of {} x {} px, the first scan {} x {}: one "
                                       "field is one objective and one camera",
                                       scan.name, images.front().cols(), images.front().rows(), width, height));
        }
        const int base = static_cast<int>(initial.size());
        std::vector<imaging::OverlapToMatch> overlaps;
        for (const imaging::PairRegistration& pair : scan.registration.pairs) {
          if (pair.accepted) overlaps.push_back({pair.a, pair.b, pair.offset_px});
        }
        for (imaging::PairCorrespondences& p : imaging::MatchOverlaps(images, overlaps, guess, options.matching)) {
          p.a += base, p.b += base;
          matched.push_back(std::move(p));
        }
        for (size_t k = 0; k < images.size(); ++k) {
          initial.push_back(scan.registration.positions.positions_px[k]);
          fixed.push_back(k == 0 || !scan.registration.positions.registered[k]);
        }
      });
  try {
    imaging::FieldDistortionFitOptions fit_options = options.fit;
    fit_options.order = options.known ? options.known->order : options.order;
    field->fit = imaging::FitFieldDistortion(matched, initial, fixed, width, height, fit_options,
                                             options.known ? &*options.known : nullptr);
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    throw InputError(std::string("--distortion: ") + e.what());
  }
  field->identified = !options.known;
  int base = 0;
  for (artefacts::RegisteredScan& scan : scans) {
    imaging::TilePositions& positions = scan.registration.positions;
    for (size_t k = 0; k < positions.positions_px.size(); ++k) {
      const auto i = static_cast<size_t>(base) + k;
      if (!positions.registered[k] && k > 0) continue;  // at its stage position, as before
      positions.positions_px[k] = field->fit.positions_px[i];
      positions.sigma_px[k] = field->fit.position_covariance_px2[i].diagonal().cwiseSqrt();
    }
    for (imaging::PairRegistration& pair : scan.registration.pairs) {
      if (pair.accepted) {
        pair.offset_px = field->fit.positions_px[static_cast<size_t>(base + pair.b)] -
                         field->fit.positions_px[static_cast<size_t>(base + pair.a)];
      }
    }
    base += static_cast<int>(positions.positions_px.size());
  }
  return scans;
}

}  // namespace fvm::workflows
