#include "workflows/correct_files.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "artefacts/io/centre_export.h"
#include "artefacts/io/point_list.h"
#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "stage/axis_chain.h"
#include "stage/io/calibration_file.h"
#include "workflows/correct.h"
#include "workflows/correct_scan_files.h"

namespace fvm::workflows {
namespace {

// A value rounded to `decimals` and written with exactly that many; no "-0".
std::string RoundedFixed(double v, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return FormatFixed(std::round(v * scale) / scale + 0.0, decimals);  // + 0.0: -0 becomes 0
}

// The compensation table: per nominal point the command that puts the tool point where the error-free machine
// would (stage::CompensateCommand) and the correction command - nominal. Commands are written to 1 nm (6 decimals),
// corrections to 1 nm in um (3 decimals).
CorrectedFiles CompensateMachine(const CorrectOptions& o, const stage::Calibration& cal) {
  const std::vector<artefacts::ListedPoint> points = artefacts::ReadPointList(o.input);
  const Eigen::Vector3d& tool = cal.layout.chain().tool_offset;
  std::string csv = fmt::format(
      "# compensation table by fvm {} with {} (model {}, tool offset {}, {}, {} mm): command xc,yc,zc puts the tool "
      "point where the error-free machine puts it for x,y,z; d = command - nominal\n",
      o.version, o.calibration, cal.model, FormatShortest(tool.x()), FormatShortest(tool.y()), FormatShortest(tool.z()));
  csv += "id,x,y,z,xc,yc,zc,dx_um,dy_um,dz_um\n";
  CorrectedFiles out;
  nlohmann::json doc;  // sorted keys, as the command has always printed them
  double largest = 0.0;
  for (const CompensatedPoint& c : CompensationTable(cal, points, o.input)) {
    const artefacts::ListedPoint& p = *c.nominal;
    const Eigen::Vector3d d_um = c.correction_mm * 1e3;
    largest = std::max(largest, d_um.norm());
    std::vector<std::string> fields{p.id};
    for (int k = 0; k < 3; ++k) fields.push_back(FormatShortest(p.position[k]));
    for (int k = 0; k < 3; ++k) fields.push_back(RoundedFixed(c.command[k], 6));
    for (int k = 0; k < 3; ++k) fields.push_back(RoundedFixed(d_um[k], 3));
    csv += CsvLine(fields);
    doc["points"].push_back({{"id", p.id}, {"command", {c.command.x(), c.command.y(), c.command.z()}},
                             {"correction_um", {d_um.x(), d_um.y(), d_um.z()}}});
  }
  WriteFileAtomically(o.output, csv);
  doc["largest_correction_um"] = largest;
  out.summary.text = fmt::format("compensated {} points of {} with machine model {}; largest correction {:.1f} um; written to {}\n",
                                 points.size(), o.input, cal.model, largest, o.output);
  out.paths = {{"output", o.output}};
  out.summary.json = doc;
  return out;
}

// The frame a corrected export is in, as its header comment and the text say it.
std::string FrameText(const CorrectOptions& o, const std::optional<Eigen::Vector3d>& first_tile) {
  if (!first_tile) return "stage (the model's part frame: stage coordinates compensated)";
  const Eigen::Vector3d& a = *first_tile;
  return fmt::format("first-tile (as a stitched measurement started at the first tile ({:.4f}, {:.4f}, {:.4f}) mm puts "
                     "it, {})", a.x(), a.y(), a.z(), o.stitched_frame);
}

nlohmann::json CentreFrameJson(const CorrectOptions& o, const std::optional<Eigen::Vector3d>& first_tile) {
  nlohmann::json frame = {{"frame", o.frame}};
  if (first_tile) {
    const Eigen::Vector3d& a = *first_tile;
    frame["stitched_frame"] = o.stitched_frame;
    frame["first_tile_mm"] = {a.x(), a.y(), a.z()};
  }
  return frame;
}

// The same rows, compensated, in the stage frame (the model's part frame) or where a stitched measurement of the
// same centres started at this export's first tile (its encoder reading) and turned with the stage there puts them.
// u_x, u_y, u_z are the standard uncertainties the model's covariance gives each point.
CorrectedFiles CorrectCentreFile(const CorrectOptions& o, const stage::Calibration& cal) {
  const artefacts::CentreExport input = artefacts::ReadCentreExport(o.input);
  std::optional<stage::StitchedFrame> first_tile_frame;
  if (o.frame == "first-tile") first_tile_frame = stage::ParseStitchedFrame(o.stitched_frame);
  const CentreCorrection corrected = CorrectCentres(cal, input, first_tile_frame, o.input);
  const std::optional<Eigen::Vector3d>& frame = corrected.first_tile_mm;
  std::string csv = fmt::format("# corrected by fvm {} with {} (model {})\n", o.version, o.calibration, cal.model);
  csv += "# frame: " + FrameText(o, frame) + "\n";
  for (const std::string& c : input.comments) csv += "#" + c + "\n";
  csv += "id,x,y,z,u_x,u_y,u_z";
  // t is optional cell by cell: a row whose t is empty is written with an empty t, never a made-up number.
  const bool has_t = std::any_of(input.centres.begin(), input.centres.end(),
                                 [](const artefacts::CentreRecord& c) { return c.t_s.has_value(); });
  if (has_t) csv += ",t";
  csv += "\n";
  CorrectedFiles out;
  nlohmann::json doc;  // sorted keys, as the command has always printed them
  doc = CentreFrameJson(o, frame);
  for (const CorrectedCentre& c : corrected.centres) {
    const artefacts::CentreRecord& r = *c.input;
    const Eigen::Vector3d& p = c.position;
    const Eigen::Vector3d& u = c.u;
    csv += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}", r.id, p.x(), p.y(), p.z(), u.x(), u.y(), u.z());
    if (has_t) csv += r.t_s ? fmt::format(",{:.3f}", *r.t_s) : std::string(",");
    csv += "\n";
    doc["centres"].push_back({{"id", r.id}, {"x", p.x()}, {"y", p.y()}, {"z", p.z()},
                              {"u_um", {u.x() * 1e3, u.y() * 1e3, u.z() * 1e3}},
                              {"shift_um", c.shift_mm * 1e3}});
  }
  WriteFileAtomically(o.output, csv);
  out.summary.text = fmt::format("corrected {} centres of {} with model {} in the {} frame; largest shift {:.1f} um; written to {}\n",
                                 input.centres.size(), o.input, cal.model, o.frame, corrected.largest_shift_mm * 1e3, o.output);
  out.paths = {{"output", o.output}};
  out.summary.json = doc;
  return out;
}

}  // namespace

void CorrectOptions::Check() const {
  if (calibration.empty()) throw InputError("--calibration: give the model file ('fvm calibrate -o' or 'fvm verify -o')");
  if (input.empty() && layout.empty()) throw InputError("IN: give the file to correct (or --layout)");
  if (output.empty()) throw InputError("-o: give the output file (a directory with --layout)");
  if (frame != "stage" && frame != "first-tile") throw InputError("--frame: '" + frame + "' is not one of stage, first-tile");
  if (stitched_frame != "rotated" && stitched_frame != "translated") {
    throw InputError("--stitched-frame: '" + stitched_frame + "' is not one of rotated, translated");
  }
  if (!(resample_mm >= 0.0) || !std::isfinite(resample_mm)) {
    throw InputError(fmt::format("--resample: {} mm is not a pixel size; give a positive PIXEL_MM, or 0 for a cloud", resample_mm));
  }
  if (origin_mm && !origin_mm->allFinite()) throw InputError("--origin: give three finite coordinates X,Y,Z (mm)");
  if (threads < 0) throw InputError(fmt::format("--threads: {} is negative; give 0 for all cores", threads));
  read.Check();
}

CorrectedFiles CorrectFiles(const CorrectOptions& options) {
  options.Check();
  if (stage::IsMachineModelFile(options.calibration)) {
    if (!artefacts::IsCentreExportFile(options.input) && std::filesystem::path(options.input).extension() != ".csv") {
      throw InputError(fmt::format("{}: a machine model (fvm verify) makes compensation tables from point lists, it "
                                   "does not correct scans; use the stage model of 'fvm calibrate'",
                                   options.calibration));
    }
    return CompensateMachine(options, stage::ReadCalibration(options.calibration));
  }
  const stage::Calibration cal = stage::ReadCalibration(options.calibration);
  if (artefacts::IsCentreExportFile(options.input) && options.layout.empty()) return CorrectCentreFile(options, cal);
  if (cal.layout.chain().code != stage::AxisChain::FvmStage().code) {
    throw InputError(fmt::format("{}: a calibration of the {} chain; scans of a focus-variation microscope are "
                                 "corrected with its {} stage model (fvm calibrate)",
                                 options.calibration, cal.layout.chain().code, stage::AxisChain::FvmStage().code));
  }
  return options.layout.empty() ? CorrectScanFile(options, cal) : CorrectTileFiles(options, cal);
}

}  // namespace fvm::workflows
