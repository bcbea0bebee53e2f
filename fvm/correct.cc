// fvm correct --calibration CAL.json IN -o OUT: compensate a stitching-free export (a microscope stage model from
// `fvm calibrate`), or turn a list of nominal points into a compensation table (a machine model from `fvm verify`).

#include <fmt/core.h>

#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "fvm/surface_read_args.h"
#include "workflows/correct_files.h"

namespace fvm::cli {
namespace {

struct CorrectArgs {
  std::string origin;  // scans: X,Y,Z, parsed into options.origin_mm
  bool json = false;
  SurfaceReadArgs read;  // scans: how to read images and clouds (as fvm info)
  workflows::CorrectOptions options;
};

void Run(const CorrectArgs& args) {
  workflows::CorrectOptions options = args.options;
  if (!args.origin.empty()) options.origin_mm = ParseVector3(args.origin, "--origin", "--origin 12.5,-30,0");
  options.read = args.read.ToOptions();
  options.threads = ThreadCount();
  options.version = FVM_VERSION;
  workflows::CorrectedFiles corrected = workflows::CorrectFiles(options);
  if (!args.json) {
    fmt::print("{}", corrected.summary.text);
    return;
  }
  for (const auto& [key, path] : corrected.paths) AddSortedPath(corrected.summary.json, key, path);
  fmt::print("{}\n", corrected.summary.json.dump(2));
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
  sub->add_option("--calibration", args->options.calibration, "model file written by 'fvm calibrate -o' or 'fvm verify -o'")->required();
  sub->add_option("IN", args->options.input, "stitching-free centre export, scan (cloud or height map), or nominal machine points");
  sub->add_option("-o,--output", args->options.output,
                  "corrected export (id,x,y,z,u_x,u_y,u_z), corrected scan (format by extension), tile directory "
                  "(--layout) or compensation table")
      ->required();
  sub->add_option("--frame", args->options.frame,
                  "stage model: 'stage' (default: the model's part frame) or 'first-tile' (where a stitched measurement "
                  "started at this export's first tile puts the points: comparable with its stitched export)")
      ->check(CLI::IsMember({"stage", "first-tile"}))
      ->capture_default_str();
  sub->add_option("--stitched-frame", args->options.stitched_frame,
                  "--frame first-tile: 'rotated' (turned with the stage at the first tile, by the model's rotation terms) "
                  "or 'translated'")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  sub->add_option("--layout", args->options.layout, "scans: tile layout file,row,col,x,y (stage mm): one rigid shift per tile");
  sub->add_option("--origin", args->origin, "scans: X,Y,Z, the stage position (mm) of the file's coordinate origin")
      ->check(NumbersCheck(3, "--origin", "--origin 12.5,-30,0"));
  sub->add_option("--resample", args->options.resample_mm,
                  "scans: PIXEL_MM, a height map on a regular grid of this pixel again (else a cloud)")
      ->check(Within(kPixelMm));
  sub->add_flag("--extrapolate", args->options.extrapolate, "scans: correct points outside the calibrated travel too");
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
    if (args->options.input.empty() && args->options.layout.empty()) throw CLI::RequiredError("IN (or --layout)");
    Run(*args);
  });
}

}  // namespace fvm::cli
