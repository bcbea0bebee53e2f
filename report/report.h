#pragma once
// One report of any job: what `fvm ... --report DIR` and Python's `fvm.write_report(result, DIR)` write. The
// workflows build the data from their results (workflows/summary.h); the front ends only choose the directory.

#include <filesystem>
#include <type_traits>
#include <variant>

#include "report/machine_report.h"
#include "report/stage_report.h"
#include "report/stitch_report.h"
#include "report/uncertainty_report.h"

namespace fvm::report {

// The stage page (calibrate, diagnose), the machine page (verify, testpiece), the Monte Carlo page (uncertainty) or
// the tiles page (stitch).
using Report = std::variant<ReportData, MachineReportData, UncertaintyReportData, StitchReportData>;

// Writes DIR with the writer of the report's kind (their headers say what each writes and how it fails).
inline void Write(const std::filesystem::path& dir, const Report& report) {
  std::visit(
      [&dir](const auto& data) {
        using Data = std::decay_t<decltype(data)>;
        if constexpr (std::is_same_v<Data, ReportData>) {
          WriteReport(dir, data);
        } else if constexpr (std::is_same_v<Data, MachineReportData>) {
          WriteMachineReport(dir, data);
        } else if constexpr (std::is_same_v<Data, UncertaintyReportData>) {
          WriteUncertaintyReport(dir, data);
        } else {
          WriteStitchReport(dir, data);
        }
      },
      report);
}

}  // namespace fvm::report
