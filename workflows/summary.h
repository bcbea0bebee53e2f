#pragma once
// What a job tells its user, owned by the job's result (the pattern of Ceres' Solver::Summary): the JSON document
// scripts read (`--json`, and Python's result), the text the command prints for people, and the report's data.
// Every front end shows the same summary: the command line writes and prints it, the Python module returns its JSON
// as a dict and writes its report with fvm.write_report, so the two cannot drift apart. Paths of the user's files
// are the front end's to add (Python's results have none).

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

#include "report/report.h"

namespace fvm::workflows {

struct Summary {
  nlohmann::ordered_json json;           // the --json document, keys in the order the command prints them
  std::string text;                      // what the command prints, newline-terminated lines
  std::optional<report::Report> report;  // what --report DIR draws; empty for a job without a report
};

}  // namespace fvm::workflows
