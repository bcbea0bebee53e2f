// fvm correct --calibration CAL.json IN -o OUT: compensate a stitching-free export (a microscope stage model from
// `fvm calibrate`), or turn a list of nominal points into a compensation table (a machine model from `fvm verify`).

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/csv.h"
#include "core/file_io.h"
#include "core/number_text.h"
#include "artefacts/io/centre_export.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "stage/io/calibration_file.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "fvm/scan_correction_run.h"
#include "workflows/correct.h"
#include "fvm/surface_read_args.h"
#include "stage/axis_chain.h"

namespace fvm::cli {
namespace {

struct CorrectArgs {
  std::string calibration;
  std::string input;
  std::string output;
  std::string frame = "stage";             // stage | first-tile
  std::string stitched_frame = "rotated";  // first-tile: rotated | translated
  std::string layout;                      // scans: tile layout, one rigid shift per tile
  std::string origin;                      // scans: X,Y,Z stage position of the file's origin
  double resample_mm = 0.0;                // scans: a height map on this grid again
  bool extrapolate = false;                // scans: correct points outside the calibrated travel too
  bool json = false;
  SurfaceReadArgs read;                    // scans: how to read images and clouds (as fvm info)
};

// A machine model is what `fvm verify -o` writes: it names the tracker pose (instrument_pose) or a tool offset. A
// stage model of `fvm calibrate` has neither and compensates centre exports.
bool IsMachineModel(const std::string& path) {
  nlohmann::json doc;
  try {
    doc = ReadJsonFile(path);
  } catch (const InputError&) {
    return false;  // ReadCalibration says what is wrong with it
  }
  return doc.is_object() && (doc.contains("instrument_pose") || doc.contains("tool_offset_mm"));
}

// The compensation table: per nominal point the command that puts the tool point where the error-free machine
// would (stage::CompensateCommand) and the correction command - nominal. Commands are written to 1 nm (6 decimals),
// corrections to 1 nm in um (3 decimals); no "-0".
void RunMachine(const CorrectArgs& args, const stage::Calibration& cal) {
  const std::vector<artefacts::ListedPoint> points = artefacts::ReadPointList(args.input);
  std::string csv = fmt::format(
      "# compensation table by fvm {} with {} (model {}, tool offset {}, {}, {} mm): command xc,yc,zc puts the tool "
      "point where the error-free machine puts it for x,y,z; d = command - nominal\n",
      FVM_VERSION, args.calibration, cal.model, FormatShortest(cal.layout.chain().tool_offset.x()),
      FormatShortest(cal.layout.chain().tool_offset.y()), FormatShortest(cal.layout.chain().tool_offset.z()));
  csv += "id,x,y,z,xc,yc,zc,dx_um,dy_um,dz_um\n";
  nlohmann::json doc;
  double largest = 0.0;
  for (const workflows::CompensatedPoint& c : workflows::CompensationTable(cal, points, args.input)) {
    const artefacts::ListedPoint& p = *c.nominal;
    const Eigen::Vector3d d_um = c.correction_mm * 1e3;
    largest = std::max(largest, d_um.norm());
    std::vector<std::string> fields{p.id};
    for (int k = 0; k < 3; ++k) fields.push_back(FormatShortest(p.position[k]));
    const auto fixed = [](double v, int decimals) {
      const double scale = std::pow(10.0, decimals);
      return FormatFixed(std::round(v * scale) / scale + 0.0, decimals);  // + 0.0: -0 becomes 0
    };
    for (int k = 0; k < 3; ++k) fields.push_back(fixed(c.command[k], 6));
    for (int k = 0; k < 3; ++k) fields.push_back(fixed(d_um[k], 3));
    csv += CsvLine(fields);
    doc["points"].push_back({{"id", p.id}, {"command", {c.command.x(), c.command.y(), c.command.z()}},
                             {"correction_um", {d_um.x(), d_um.y(), d_um.z()}}});
  }
  WriteFileAtomically(args.output, csv);
  if (args.json) {
    doc["output"] = args.output;
    doc["largest_correction_um"] = largest;
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("compensated {} points of {} with machine model {}; largest correction {:.1f} um; written to {}\n",
             points.size(), args.input, cal.model, largest, args.output);
}

// The frame a corrected export is in, as its header comment, --help and the JSON say it.
std::string FrameText(const CorrectArgs& args, const std::optional<Eigen::Vector3d>& first_tile) {
  if (!first_tile) return "stage (the model's part frame: stage coordinates compensated)";
  const Eigen::Vector3d& a = *first_tile;
  return fmt::format("first-tile (as a stitched measurement started at the first tile ({:.4f}, {:.4f}, {:.4f}) mm puts "
                     "it, {})", a.x(), a.y(), a.z(), args.stitched_frame);
}

nlohmann::json FrameJson(const CorrectArgs& args, const std::optional<Eigen::Vector3d>& first_tile) {
  nlohmann::json frame = {{"frame", args.frame}};
  if (first_tile) {
    const Eigen::Vector3d& a = *first_tile;
    frame["stitched_frame"] = args.stitched_frame;
    frame["first_tile_mm"] = {a.x(), a.y(), a.z()};
  }
  return frame;
}

void RunCentres(const CorrectArgs& args, const stage::Calibration& cal) {
  const artefacts::CentreExport input = artefacts::ReadCentreExport(args.input);
  // The stage frame: the model's part frame. The first tile's: where a stitched measurement of the same centres
  // would put them, started at the first tile of this export (its encoder reading) and turned with the stage there.
  std::optional<stage::StitchedFrame> first_tile_frame;
  if (args.frame == "first-tile") first_tile_frame = stage::ParseStitchedFrame(args.stitched_frame);
  const workflows::CentreCorrection corrected = workflows::CorrectCentres(cal, input, first_tile_frame, args.input);
  const std::optional<Eigen::Vector3d>& frame = corrected.first_tile_mm;
  // Same rows, compensated; u_x, u_y, u_z are the standard uncertainties the model's covariance gives each point.
  std::string csv = fmt::format("# corrected by fvm {} with {} (model {})\n", FVM_VERSION, args.calibration, cal.model);
  csv += "# frame: " + FrameText(args, frame) + "\n";
  for (const std::string& c : input.comments) csv += "#" + c + "\n";
  csv += "id,x,y,z,u_x,u_y,u_z";
  // t is optional cell by cell: a row whose t is empty is written with an empty t, never a made-up number.
  const bool has_t = std::any_of(input.centres.begin(), input.centres.end(),
                                 [](const artefacts::CentreRecord& c) { return c.t_s.has_value(); });
  if (has_t) csv += ",t";
  csv += "\n";
  nlohmann::json doc = FrameJson(args, frame);
  for (const workflows::CorrectedCentre& c : corrected.centres) {
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
  WriteFileAtomically(args.output, csv);
  if (args.json) {
    doc["output"] = args.output;
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("corrected {} centres of {} with model {} in the {} frame; largest shift {:.1f} um; written to {}\n",
             input.centres.size(), args.input, cal.model, args.frame, corrected.largest_shift_mm * 1e3, args.output);
}

// A .csv file is a centre export when its header names an id column; otherwise it is an XYZ/CSV point cloud.
bool IsCentreExport(const std::string& path) {
  if (AsciiLower(std::filesystem::path(path).extension().string()) != ".csv") return false;
  const std::string head = ReadFileHead(path, 1 << 16);
  std::size_t start = 0;
  while (start < head.size()) {
    const std::size_t end = std::min(head.find('\n', start), head.size());
    const std::string_view line = TrimBlanks(std::string_view(head).substr(start, end - start));
    start = end + 1;
    if (line.empty() || line.front() == '#') continue;
    std::size_t field_start = 0;
    while (field_start <= line.size()) {
      const std::size_t field_end = std::min(line.find_first_of(",;\t", field_start), line.size());
      if (AsciiLower(TrimBlanks(line.substr(field_start, field_end - field_start))) == "id") return true;
      field_start = field_end + 1;
    }
    return false;
  }
  return false;
}

void Run(const CorrectArgs& args) {
  if (IsMachineModel(args.calibration)) {
    if (!IsCentreExport(args.input) && std::filesystem::path(args.input).extension() != ".csv") {
      throw InputError(fmt::format("{}: a machine model (fvm verify) makes compensation tables from point lists, it "
                                   "does not correct scans; use the stage model of 'fvm calibrate'",
                                   args.calibration));
    }
    RunMachine(args, stage::ReadCalibration(args.calibration));
    return;
  }
  const stage::Calibration cal = stage::ReadCalibration(args.calibration);
  if (IsCentreExport(args.input) && args.layout.empty()) {
    RunCentres(args, cal);
    return;
  }
  if (cal.layout.chain().code != stage::AxisChain::FvmStage().code) {
    throw InputError(fmt::format("{}: a calibration of the {} chain; scans of a focus-variation microscope are "
                                 "corrected with its {} stage model (fvm calibrate)",
                                 args.calibration, cal.layout.chain().code, stage::AxisChain::FvmStage().code));
  }
  stage::ScanCorrectionOptions options;
  if (!args.origin.empty()) options.origin_mm = ParseVector3(args.origin, "--origin", "--origin 12.5,-30,0");
  if (args.frame == "first-tile") options.first_tile_frame = stage::ParseStitchedFrame(args.stitched_frame);
  const ScanCorrectionArgs scan{args.calibration, args.input,       args.output, args.layout,          args.resample_mm,
                                args.extrapolate, args.json,        ThreadCount(), args.read.ToOptions(), options};
  RunScanCorrection(scan, cal);
}

}  // namespace

void RegisterCorrect(CLI::App& app) {
  auto args = std::make_shared<CorrectArgs>();
  CLI::App* sub = app.add_subcommand("correct", "compensate a stitching-free export or scan, or make a machine's compensation table");
  AddDetails(sub,
             "With a stage model ('fvm calibrate -o'), IN is a stitching-free centre export (CSV with an id column) "
             "or a scan: a point cloud (XYZ/CSV text, PLY ascii or binary, PCD) or a height map (X3P, AL3D, TIFF). "
             "Every valid point is moved by the model at its own stage coordinates, exactly as a centre at the same "
             "coordinates (the result equals the centre-CSV correction to 1 nm); NaN and infinite points are skipped "
             "and counted. A cloud stays a cloud (the format of -o: .ply, .pcd, .xyz), with the standard "
             "uncertainties u_x, u_y, u_z (mm) as extra PLY/PCD properties or XYZ columns; a height map becomes an "
             "organised cloud, or with --resample PIXEL_MM a height map on a regular grid again (-o .x3p with float64 "
             "heights, .al3d, .tif; invalid where no point lands), its uncertainties in OUT.uncertainty.csv. "
             "Coordinates are mm in and out."
             "Frame (stated in the output's header comment, the summary and the JSON): the default --frame stage gives "
             "the model's part frame, which is not the frame of a stitched export: a stitched measurement starts at "
             "the encoder reading of its first tile and so differs from stage coordinates by the stage's error there "
             "(tens of um). --frame first-tile gives the result as a stitched measurement of the same scan started at "
             "its first tile (lowest x, highest y) puts it, directly comparable with a stitched export and with the "
             "first-tile validation figure of 'fvm calibrate'."
             "A file whose coordinates are not stage coordinates (an origin at the dataset's corner) needs --origin "
             "X,Y,Z, the stage position of that origin; the output keeps the file's origin. Points outside the "
             "calibrated travel are refused, named, unless --extrapolate."
             "--layout L.csv (file,row,col,x,y: tiles and their stage positions) corrects each tile by one rigid "
             "shift, the model at the tile's position, and writes the tiles into the directory -o with shifts.csv. "
             "Within a tile the camera, not the stage, measured the points, so per-tile is right for data measured "
             "tile by tile and per-point for coordinates that each come from the encoders. They differ by the "
             "model's change across one field of view, at the tile's corners: on the sample's model 27 "
             "(samples/bar17, 125 um mean stage error) up to 6.2 um at 2.5x (5.63 mm), 3.1 um at 5x (2.82 mm), "
             "1.8 um at 10x, 0.9 um at 20x and 0.35 um at 50x; the run prints the figure for its own tiles."
             "With a machine model ('fvm verify -o': the file names instrument_pose or tool_offset_mm), IN is a list "
             "of nominal points id,x,y,z (mm; points.csv of 'fvm simulate tracker' is one) and OUT the compensation "
             "table id,x,y,z,xc,yc,zc,dx_um,dy_um,dz_um: the command xc,yc,zc puts the tool point where the "
             "error-free machine puts it for x,y,z (the model's inverse), d = command - nominal. The model's errors "
             "are known up to the tracker pose, so the table is zero at the axes' origin (travel minimum).");
  sub->add_option("--calibration", args->calibration, "model file written by 'fvm calibrate -o' or 'fvm verify -o'")->required();
  sub->add_option("IN", args->input, "stitching-free centre export, scan (cloud or height map), or nominal machine points");
  sub->add_option("-o,--output", args->output,
                  "corrected export (id,x,y,z,u_x,u_y,u_z), corrected scan (format by extension), tile directory "
                  "(--layout) or compensation table")
      ->required();
  sub->add_option("--frame", args->frame,
                  "stage model: 'stage' (default: the model's part frame) or 'first-tile' (where a stitched measurement "
                  "started at this export's first tile puts the points: comparable with its stitched export)")
      ->check(CLI::IsMember({"stage", "first-tile"}))
      ->capture_default_str();
  sub->add_option("--stitched-frame", args->stitched_frame,
                  "--frame first-tile: 'rotated' (turned with the stage at the first tile, by the model's rotation terms) "
                  "or 'translated'")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  sub->add_option("--layout", args->layout, "scans: tile layout file,row,col,x,y (stage mm): one rigid shift per tile");
  sub->add_option("--origin", args->origin, "scans: X,Y,Z, the stage position (mm) of the file's coordinate origin")
      ->check(NumbersCheck(3, "--origin", "--origin 12.5,-30,0"));
  sub->add_option("--resample", args->resample_mm,
                  "scans: PIXEL_MM, a height map on a regular grid of this pixel again (else a cloud)")
      ->check(Within(kPixelMm));
  sub->add_flag("--extrapolate", args->extrapolate, "scans: correct points outside the calibrated travel too");
  args->read.AddOptions(*sub);
  sub->add_flag("--json", args->json, "print the result (frame, points, shifts, uncertainties) as JSON");
  sub->footer("Example:\n  fvm calibrate samples/bar17 --model 27 -o stage.json && fvm correct --calibration stage.json "
              "samples/bar17/val-01.free.csv -o val-01.corrected.csv\n"
              "  fvm correct --calibration stage.json scan.x3p -o scan.ply                # a cloud with u_x, u_y, u_z\n"
              "  fvm correct --calibration stage.json scan.x3p -o fixed.x3p --resample 0.01 --frame first-tile\n"
              "  fvm correct --calibration stage.json --layout tiles/layout.csv -o corrected-tiles/\n"
              "  fvm verify plan/readings.csv --tool 0,0,100 -o machine.json && fvm correct --calibration machine.json "
              "plan/points.csv -o compensation.csv");
  sub->callback([args] {
    if (args->input.empty() && args->layout.empty()) throw CLI::RequiredError("IN (or --layout)");
    Run(*args);
  });
}

}  // namespace fvm::cli
