#pragma once
// The discrepancy workflow on tiles (`fvm diagnose --layout L.csv` / `--scan L.csv ...`): does a rigid, undistorted
// image of every tile explain the overlaps? Dense correspondences in every registered overlap
// (imaging/overlap_correspondences.h) are fitted twice on the same points: the rigid model (tile positions only)
// and the field model (positions and the objective's field distortion, imaging/field_distortion_fit.h, as `fvm
// stitch --distortion` and `fvm calibrate --scan --distortion` identify it). The field's free coefficients are the
// extra parameters of an F test. Its noise is the correspondences' own scatter widened by how much more they scatter
// over a quarter of an overlap (and, on a grid, round its loops) than single points allow: the points of one overlap
// share the texture's errors, and counted as independent they would make any field significant. When the test says
// so, the effect is named `field_distortion`, with its size (largest displacement) and the overlap residuals before
// and after. As the batch's discrepancy workflow (stage/discrepancy_effects.cc) does, it is named only when the
// Bayesian information criterion agrees: a field of a few hundredths of a pixel that every overlap shares (the
// texture's rendering, the correspondences' own bias) passes an F test on ten thousand points, yet explains a
// percent of their scatter.

#include <optional>
#include <string>
#include <vector>

#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"
#include "imaging/overlap_correspondences.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct TileDiagnoseOptions {
  std::string layout;              // --layout: one grid of tiles, as fvm stitch takes it
  std::vector<std::string> scans;  // --scan: calibration scans, as fvm calibrate --scan takes them
  double overlap = 0.0;            // --overlap (a layout's nominal overlap, fraction); scans take the encoders'
  double pixel_mm = 0.0;           // --pixel-mm: sizes in um (scans need it)
  int order = 3;                   // --order: the field model's polynomial order (2..6)
  double alpha = 0.01;             // --alpha: false-alarm probability of the F test
  int threads = 0;
  imaging::CorrespondenceOptions matching;
  // Throws InputError naming the option (--layout, --scan, --overlap, --pixel-mm, --order, --alpha).
  void Check() const;
};

// The overlap residuals of one model over the points both fits share: |r| per point (2-D), in px.
struct OverlapResiduals {
  int points = 0;
  double rms_px = 0.0, mean_px = 0.0;
};

struct TileDiagnosis {
  std::string source;  // "layout" or "scan"
  int tiles = 0, pairs = 0, pairs_used = 0;
  int width_px = 0, height_px = 0;
  imaging::FieldDistortionFit field;  // the field model's fit (field, positions, scatter)
  OverlapResiduals rigid, with_field;
  int extra_parameters = 0;          // the field's free coefficients (held terms excluded)
  double point_sigma_px = 0.0;       // the field fit's scatter of one correspondence (per axis)
  // The larger of the field fit's block and loop (pair) scatter factors; the blocks' degrees of freedom
  // (field.block_dof) are the F test's denominator's.
  double noise_factor = 1.0;
  double f_statistic = 0.0, p_value = 1.0;
  // The Bayesian information criterion's change on the points counted as independent observations (2 a point over
  // noise_factor^2): negative when the field earns its coefficients.
  double delta_bic = 0.0;
  bool significant = false;  // p_value < alpha and delta_bic < 0, the batch's discrepancy workflow's rule
  double largest_px = 0.0;           // the field's largest displacement over the tile
};

TileDiagnosis DiagnoseTiles(const TileDiagnoseOptions& options);

// The --json document, the printed text (no report: the field's plots belong to `fvm stitch --report`).
Summary Summarize(const TileDiagnosis& diagnosis, const TileDiagnoseOptions& options);

}  // namespace fvm::workflows
