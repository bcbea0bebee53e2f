// The report writers as the fvm executable links them: each forwards to the plugin libfvm_report.so, loaded on the
// first report (report/plugin.h says why and how).

#include <string>

#include "report/plugin.h"
#include "imaging/io/plugin_loader.h"

namespace fvm::report {

const ReportWriters& LoadReportWriters(std::string_view action) {
  static constexpr imaging::PluginSpec kPlugin{"libfvm_report.so", "fvm_report_v1", "PLplot", "libplplot17"};
  return *static_cast<const ReportWriters*>(imaging::LoadPlugin(kPlugin, action));
}

void WriteReport(const std::filesystem::path& dir, const ReportData& data) {
  LoadReportWriters("writing the report " + dir.string()).write_report(dir, data);
}

void WriteMachineReport(const std::filesystem::path& dir, const MachineReportData& data) {
  LoadReportWriters("writing the report " + dir.string()).write_machine_report(dir, data);
}

void WriteUncertaintyReport(const std::filesystem::path& dir, const UncertaintyReportData& data) {
  LoadReportWriters("writing the report " + dir.string()).write_uncertainty_report(dir, data);
}

void WriteStitchReport(const std::filesystem::path& dir, const StitchReportData& data) {
  LoadReportWriters("writing the report " + dir.string()).write_stitch_report(dir, data);
}

}  // namespace fvm::report
