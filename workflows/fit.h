#pragma once
// `fvm fit FILE`: the calottes of a height map or cloud found and fitted with spheres (workflows/find_calottes.h),
// or, with a shape, one sphere or plane fitted to every point of the file (imaging/shape_fit.h); the summary the
// command prints and the centre export it writes.

#include <optional>
#include <string>

#include "artefacts/io/centre_export.h"
#include "imaging/io/surface_file.h"
#include "imaging/shape_fit.h"
#include "workflows/find_calottes.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// The options as `fvm fit` spells them (--artefact, --radius-mm, ...).
struct FitOptions {
  std::string artefact;  // grid6x6, bar17, ...: number the calottes as it does; empty: no numbering
  double radius_mm = 0.0;
  std::optional<double> rotation_deg;
  double min_diameter_mm = 0.0, max_diameter_mm = 0.0, min_depth_mm = 0.0;
  std::string residual = "height";  // or "orthogonal"
  std::string shape;                // "sphere" or "plane": one shape to every point instead of the calotte search
  bool robust = false;              // with a shape: least median of squares among stray points

  // Throws InputError naming the options that do not go together (`writes_output`: a centre export, -o, is asked).
  void Check(bool writes_output = false) const;
  FindCalottesOptions CalotteSearch() const;  // throws InputError for an unknown artefact
};

struct FitResult {
  std::string file;                     // what was fitted (its name in the text)
  FitOptions options;
  std::optional<FoundCalottes> found;   // the calotte search
  std::optional<imaging::ShapeFit> shape;  // or the one shape
};

// Reads `file` and fits; refusals name the file.
FitResult FitFile(const std::string& file, const imaging::SurfaceReadOptions& read, const FitOptions& options);

// The centre export the calotte search writes (fvm fit -o), `output` its path.
artefacts::CentreExport FitCentreExport(const FitResult& result, const std::string& output);

// The --json document and the printed text. Calottes: {"calottes": [...], "method", "artefact", "face", "layout",
// "rejected"} (the command adds "file" before "method" and "output" last); a shape: {"shape", "points", ...,
// "outliers", "robust", "method"} ("file" before "robust").
Summary Summarize(const FitResult& result);

}  // namespace fvm::workflows
