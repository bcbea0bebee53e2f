#include "fvm/summary_output.h"

#include <fmt/core.h>

namespace fvm::cli {

nlohmann::ordered_json WithPaths(const nlohmann::ordered_json& document, const std::vector<PathKey>& paths) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  std::vector<bool> placed(paths.size(), false);
  for (const auto& item : document.items()) {
    for (std::size_t i = 0; i < paths.size(); ++i) {
      if (!placed[i] && paths[i].before == item.key()) out[paths[i].key] = paths[i].path, placed[i] = true;
    }
    out[item.key()] = item.value();
  }
  for (std::size_t i = 0; i < paths.size(); ++i) {
    if (!placed[i]) out[paths[i].key] = paths[i].path;
  }
  return out;
}

void AddSortedPath(nlohmann::ordered_json& document, const std::string& key, const std::string& path) {
  nlohmann::json sorted = document;
  sorted[key] = path;
  document = sorted;
}

void PrintSummary(const workflows::Summary& summary, bool json, const std::vector<PathKey>& paths) {
  if (json) {
    fmt::print("{}\n", WithPaths(summary.json, paths).dump(2));
  } else {
    fmt::print("{}", summary.text);
  }
}

}  // namespace fvm::cli
