// The plugin libfvm_report.so: the report writers (fvm_report, with PLplot) behind their table (report_plugin.h).

#include "report/plugin.h"

namespace fvm::report {
namespace {

constexpr ReportWriters kReportWriters{&WriteReport, &WriteMachineReport, &WriteUncertaintyReport,
                                          &WriteStitchReport};

}  // namespace
}  // namespace fvm::report

extern "C" __attribute__((visibility("default"))) const void* fvm_report_v1() { return &fvm::report::kReportWriters; }
