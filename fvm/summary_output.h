#pragma once
// What every command does with its job's summary (workflows/summary.h): print its text, or its --json document
// with the paths of the user's files added where the document has always named them.

#include <string>
#include <vector>

#include "workflows/summary.h"

namespace fvm::cli {

// One path of the user's files in the --json document: its key, the path, and the key it comes before ("" or a
// key the document lacks: at the end).
struct PathKey {
  std::string key;
  std::string path;
  std::string before;
};

// The summary's document with the paths added.
nlohmann::ordered_json WithPaths(const nlohmann::ordered_json& document, const std::vector<PathKey>& paths);

// Adds the path of one of the user's files to a document the job built with sorted keys (nlohmann::json), in its
// sorted place, as the command has always printed it.
void AddSortedPath(nlohmann::ordered_json& document, const std::string& key, const std::string& path);

// Prints the summary's document (with the paths, indented by 2) when `json`, else its text.
void PrintSummary(const workflows::Summary& summary, bool json, const std::vector<PathKey>& paths = {});

}  // namespace fvm::cli
