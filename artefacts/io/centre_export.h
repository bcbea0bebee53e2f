#pragma once
// Calotte-centre exports (CSV), the contract between imaging and stage calibration (docs/formats.md):
// '#' comment lines, then a header naming at least id,x,y,z; optional t (s since the measurement started),
// radius, form_rms; other columns ignored. Units mm. One file is one measurement of one artefact placement.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fvm::artefacts {

struct CentreRecord {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
  std::optional<double> t_s;
  std::optional<double> radius_mm;
  std::optional<double> form_rms_mm;
  // Whether the fit that made the centre reached its minimum (written as a `converged` column of 1 / 0; readers
  // that do not know the column ignore it, as the contract allows).
  std::optional<bool> converged;
  int line = 0;  // line of the source file it was read from (for messages); 0 when it was not read from a file
};

struct CentreExport {
  std::string source;                 // where it came from, for messages
  std::vector<std::string> comments;  // the '#' lines, without the '#'
  std::vector<CentreRecord> centres;  // file order

  const CentreRecord* Find(int id) const;  // nullptr when absent
};

// Throws InputError "FILE:LINE: problem; what to do" on a missing file, a header without id,x,y,z, a short or
// non-numeric row, NaN or infinite values, a duplicated id, no rows at all, or coordinates that look like
// micrometres (any |x|, |y|, |z| above 1000 mm: no FVM stage is a metre long).
CentreExport ReadCentreExport(const std::filesystem::path& path);

// Whether a file is a centre export rather than an XYZ/CSV point cloud: a .csv whose header (its first line that is
// neither blank nor a # comment) names an id column.
bool IsCentreExportFile(const std::filesystem::path& path);

// Writes id,x,y,z[,t][,radius][,form_rms][,converged] with 6 decimals of mm (1 nm), comments first; atomically.
void WriteCentreExport(const std::filesystem::path& path, const CentreExport& data);

}  // namespace fvm::artefacts
