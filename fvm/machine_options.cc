#include "fvm/machine_options.h"

#include <fmt/core.h>

#include "core/number_text.h"
#include "fvm/option_parsing.h"

namespace fvm::cli {

void AddMachineOptions(CLI::App* sub, workflows::MachineProblemOptions& o) {
  sub->add_option("DATA", o.data, "tracker readings: id,x,y,z + xt,yt,zt or range,azimuth,elevation (mm, rad); fvm uncertainty also takes a batch directory")
      ->required();
  sub->add_option("--chain", o.chain, "F-notation chain: letters left of F move the part (e.g. XFYZ, FXYZ, XYFZ)")
      ->capture_default_str();
  sub->add_option("--basis", o.basis, "polynomial basis")->check(CLI::IsMember({"power", "legendre", "chebyshev"}))
      ->capture_default_str();
  AddToolOption(sub, o, "tool offset X,Y,Z in mm (give it twice for two tools: a `tool` column says which)");
  auto* fit = sub->add_flag("--fit-pose")->description("estimate the tracker pose jointly (the default)");
  sub->add_option_function<std::string>(
         "--pose", [&o](const std::string& text) { o.pose = ParsePose(text, "--pose"); },
         "hold the tracker pose: X,Y,Z (mm), A,B,C (XYZ Euler, deg)")
      ->check(PoseCheck("--pose"))
      ->excludes(fit);
  AddTravelOption(sub, o, "axis travels LXxLYxLZ[@X0,Y0,Z0] in mm (default: the span of the points)");
  sub->add_option("--tracker", o.tracker, "tracker noise model for the weights")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_flag("--unweighted", o.unweighted, "equal weights instead of the readings' covariances (their cxx..czz columns, or the tracker's noise model)");
  sub->add_option("--validate", o.validate, "other readings to judge the model on (never fitted)");
  AddMaxErrorOption(sub, o);
}

void AddToolOption(CLI::App* sub, workflows::MachineProblemOptions& o, const std::string& description) {
  std::string shown;
  for (const Eigen::Vector3d& t : o.tools) {
    if (!shown.empty()) shown += ',';
    shown += FormatShortest(t.x()) + "," + FormatShortest(t.y()) + "," + FormatShortest(t.z());
  }
  sub->add_option_function<std::vector<std::string>>(
         "--tool",
         [&o](const std::vector<std::string>& texts) {
           o.tools.clear();
           for (const std::string& t : texts) o.tools.push_back(ParseVector3(t, "--tool", "0,0,100"));
         },
         description)
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->default_str("[" + shown + "]");
}

void AddTravelOption(CLI::App* sub, workflows::MachineProblemOptions& o, const std::string& description) {
  sub->add_option_function<std::string>(
         "--machine",
         [&o](const std::string& text) {
           o.travel = ParseMachine(text);
           o.travel_name = fmt::format("--machine '{}'", text);
         },
         description)
      ->check(MachineCheck());
}

void AddMaxErrorOption(CLI::App* sub, workflows::MachineProblemOptions& o) {
  sub->add_option("--max-error-mm", o.max_error_mm,
                  "plausibility bound: refuse a result with an error term or residual beyond it, which means wrong data "
                  "(mirrored axes, units, columns), not a machine (default: 1 mm per metre of the longest travel; "
                  "e.g. --max-error-mm 5)")
      ->check(Within(1e-3, 1e5, "mm"));
}

}  // namespace fvm::cli
