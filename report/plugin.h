#pragma once
// The HTML reports, seen through one table of their entry points, so that the fvm executable loads PLplot (with
// freetype, png, brotli, qhull and its own helpers: a dozen shared objects, about a sixth of the start-up of a light
// command, issue 47) only when a command writes a report.
//
// How it is built (report/CMakeLists.txt): fvm_report stays a static library for the tests; the plugin
// libfvm_report.so (plugin.cc) holds it and returns this table; the executable links on_demand.cc
// instead, the same functions forwarded through the table of the plugin, loaded on the first call
// (imaging/io/plugin_loader.h). The members take their types from the declarations.

#include <string_view>

#include "report/machine_report.h"
#include "report/stage_report.h"
#include "report/stitch_report.h"
#include "report/uncertainty_report.h"

namespace fvm::report {

// The plugin's function table (entry point "fvm_report_v1").
struct ReportWriters {
  decltype(&WriteReport) write_report;
  decltype(&WriteMachineReport) write_machine_report;
  decltype(&WriteUncertaintyReport) write_uncertainty_report;
  decltype(&WriteStitchReport) write_stitch_report;
};

// The table, loading the plugin on first use; when it cannot be loaded, throws InputError "<action> needs PLplot:
// libfvm_report.so could not be loaded (...); install the Debian package ...".
const ReportWriters& LoadReportWriters(std::string_view action);

}  // namespace fvm::report
