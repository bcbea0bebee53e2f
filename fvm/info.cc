// fvm info FILE: what a surface or point-cloud file holds (workflows/surface_info.h), so that a user can check an
// export before fitting calottes in it.

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "fvm/commands.h"
#include "fvm/summary_output.h"
#include "fvm/surface_read_args.h"
#include "workflows/surface_info.h"

namespace fvm::cli {
namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
  workflows::SurfaceReadOptions read;
};

void RunInfo(const InfoArgs& args) {
  const workflows::SurfaceInfo info =
      workflows::DescribeSurface(imaging::ReadSurface(args.file, args.read.ToOptions()), args.file);
  PrintSummary(workflows::Summarize(info, args.file), args.json, {{"file", args.file, "format"}});
}

}  // namespace

void RegisterInfo(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "what a surface or point-cloud file holds");
  AddDetails(sub,
      "Reads a measurement file and tells what it holds: its format, grid (points, pixel size, origin), how many "
      "points are valid and the range of heights. Reads X3P (ISO 25178-72), Alicona AL3D, ISO 25178-71 SDF, the "
      "exports of other instruments (Sensofar PLU and PLUx, Zygo MetroPro DAT, Wyko OPD, Digital Surf SUR, NMS, "
      "GelSight TMD), height-map images (TIFF, EXR, PNG through OpenImageIO), PCD and PLY point clouds, and XYZ/CSV "
      "text (x y z in mm per line). Checksums in X3P files are verified. What was unusual about a file and read anyway "
      "(an X3P zipped around its folder, archive clutter, empty optional elements) is listed as notes.");
  sub->add_option("FILE", args->file, "the surface or point-cloud file")->required();
  sub->add_flag("--json", args->json,
                "print one JSON document {\"size_x\", \"size_y\", \"dx_mm\", \"dy_mm\", \"valid_points\", "
                "\"z_min_mm\", \"z_max_mm\", ..., \"intensity\", \"notes\"}; values the file does not have are null");
  AddSurfaceReadOptions(*sub, args->read);
  sub->footer("Example: fvm info scan.x3p --json");
  sub->callback([args] { RunInfo(*args); });
}

}  // namespace fvm::cli
