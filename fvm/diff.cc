// fvm diff: how far a test export of an artefact is from a reference export of it, calotte by calotte and as
// distances between calottes (the measure of the published stitching-strategy study, [Pérez 2019] Tables 1-2).

#include <fmt/core.h>
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "artefacts/io/centre_export.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "fvm/commands.h"

namespace fvm::cli {
namespace {

using artefacts::CentreExport;

struct DiffOptions {
  std::string ref;
  std::string test;
  std::string pairs;
  bool json = false;
  bool xy = false;
};

struct CalotteDiff {
  int id = 0;
  Eigen::Vector3d d_um;
};

struct PairDiff {
  int a = 0, b = 0;
  double ref_mm = 0.0, test_mm = 0.0;
  double diff_um() const { return (test_mm - ref_mm) * 1000.0; }
};

std::string Trimmed(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") - begin + 1);
}

std::optional<int> ParseId(const std::string& s) {
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9) return std::nullopt;
  return static_cast<int>(*ParseInt(s));  // digits only, at most nine: always an int
}

std::vector<std::pair<int, int>> ParsePairs(const std::string& text) {
  const auto bad = [&](const std::string& item) {
    return InputError(fmt::format("--pairs '{}': '{}' is not a pair of calotte ids; write a:b[,a:b...], e.g. "
                                  "--pairs 1:6,1:31",
                                  text, item));
  };
  std::vector<std::pair<int, int>> pairs;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(',', start);
    const std::string item = Trimmed(text.substr(start, end == std::string::npos ? end : end - start));
    const size_t colon = item.find(':');
    if (colon == std::string::npos) throw bad(item);
    const std::optional<int> a = ParseId(Trimmed(item.substr(0, colon)));
    const std::optional<int> b = ParseId(Trimmed(item.substr(colon + 1)));
    if (!a || !b) throw bad(item);
    if (*a == *b) {
      throw InputError(fmt::format("--pairs '{}': '{}' pairs calotte {} with itself, a distance of nothing; pair two "
                                   "different calottes",
                                   text, item, *a));
    }
    pairs.emplace_back(*a, *b);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return pairs;
}


// Fixed decimals without "-0.0": a difference that rounds to nothing has no sign.
std::string Fixed(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

void PrintTable(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = header[c].size();
    for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
  }
  const auto print = [&](const std::vector<std::string>& row) {
    std::string line;
    for (size_t c = 0; c < row.size(); ++c) line += fmt::format("{}{:>{}}", c == 0 ? "" : "  ", row[c], width[c]);
    fmt::print("{}\n", line);
  };
  print(header);
  for (const auto& row : rows) print(row);
}

void RunDiff(const DiffOptions& options) {
  const CentreExport ref = artefacts::ReadCentreExport(options.ref);
  const CentreExport test = artefacts::ReadCentreExport(options.test);

  std::vector<int> common, only_ref, only_test;
  for (const auto& c : ref.centres) (test.Find(c.id) ? common : only_ref).push_back(c.id);
  for (const auto& c : test.centres) {
    if (!ref.Find(c.id)) only_test.push_back(c.id);
  }
  if (!only_ref.empty()) {
    fmt::print(stderr, "fvm diff: warning: calotte {} only in {}; left out\n", fmt::join(only_ref, ", "), options.ref);
  }
  if (!only_test.empty()) {
    fmt::print(stderr, "fvm diff: warning: calotte {} only in {}; left out\n", fmt::join(only_test, ", "), options.test);
  }
  if (common.empty()) {
    throw InputError(fmt::format("{} and {} have no calotte id in common; compare two exports of the same artefact",
                                 options.ref, options.test));
  }

  std::vector<std::pair<int, int>> pairs;
  if (!options.pairs.empty()) {
    pairs = ParsePairs(options.pairs);
  } else {
    for (size_t i = 1; i < common.size(); ++i) pairs.emplace_back(common.front(), common[i]);
  }
  // The published tables measure in the XY plane (their distances match the XY distance of their coordinates
  // to the last digit, the 3-D distance for the Y direction by 0.4 um only); --xy reproduces them.
  const auto distance = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return options.xy ? (p - q).head<2>().norm() : (p - q).norm();
  };
  std::vector<PairDiff> pair_diffs;
  for (const auto& [a, b] : pairs) {
    for (const int id : {a, b}) {
      if (!ref.Find(id) || !test.Find(id)) {
        const std::string where = !ref.Find(id) && !test.Find(id) ? options.ref + " nor in " + options.test
                                  : ref.Find(id)                   ? options.test
                                                                   : options.ref;
        throw InputError(fmt::format("--pairs {}:{}: calotte {} is not in {}; pair calottes present in both files "
                                     "(common ids: {})",
                                     a, b, id, where, fmt::join(common, ", ")));
      }
    }
    pair_diffs.push_back({a, b, distance(ref.Find(a)->position, ref.Find(b)->position),
                          distance(test.Find(a)->position, test.Find(b)->position)});
  }
  std::vector<CalotteDiff> calotte_diffs;
  for (const int id : common) calotte_diffs.push_back({id, (test.Find(id)->position - ref.Find(id)->position) * 1e3});

  if (options.json) {
    nlohmann::ordered_json out;  // keys in the order a reader expects, not sorted
    out["ref"] = options.ref;
    out["test"] = options.test;
    out["distance"] = options.xy ? "xy" : "3d";
    out["only_in_ref"] = only_ref;
    out["only_in_test"] = only_test;
    out["calottes"] = nlohmann::ordered_json::array();
    for (const auto& c : calotte_diffs) {
      out["calottes"].push_back({{"id", c.id},
                                 {"dx_um", RoundTo(c.d_um.x(), 1e4)},
                                 {"dy_um", RoundTo(c.d_um.y(), 1e4)},
                                 {"dz_um", RoundTo(c.d_um.z(), 1e4)},
                                 {"d_um", RoundTo(c.d_um.norm(), 1e4)}});
    }
    out["pairs"] = nlohmann::ordered_json::array();
    for (const auto& p : pair_diffs) {
      out["pairs"].push_back({{"a", p.a},
                              {"b", p.b},
                              {"ref_mm", RoundTo(p.ref_mm, 1e7)},
                              {"test_mm", RoundTo(p.test_mm, 1e7)},
                              {"diff_um", RoundTo(p.diff_um(), 1e4)}});
    }
    fmt::print("{}\n", out.dump(2));
    return;
  }

  fmt::print("REF   {}\nTEST  {}\n\n", options.ref, options.test);
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : calotte_diffs) {
    rows.push_back({std::to_string(c.id), Fixed(c.d_um.x(), 1), Fixed(c.d_um.y(), 1), Fixed(c.d_um.z(), 1),
                    Fixed(c.d_um.norm(), 1)});
  }
  PrintTable({"calotte", "dx [um]", "dy [um]", "dz [um]", "|d| [um]"}, rows);
  if (pair_diffs.empty()) return;
  rows.clear();
  for (const auto& p : pair_diffs) {
    rows.push_back({fmt::format("{}:{}", p.a, p.b), Fixed(p.ref_mm, 4), Fixed(p.test_mm, 4), Fixed(p.diff_um(), 1)});
  }
  fmt::print("\n{}\n", options.xy ? "distances in the XY plane (--xy)" : "distances in 3-D");
  PrintTable({"pair", "REF [mm]", "TEST [mm]", "TEST-REF [um]"}, rows);
}

}  // namespace

void RegisterDiff(CLI::App& app) {
  auto options = std::make_shared<DiffOptions>();
  CLI::App* sub = app.add_subcommand("diff", "per-calotte and distance differences between two exports");
  AddDetails(sub,
      "Per-calotte differences TEST - REF (dx, dy, dz, |d| in um) for the calottes in both centre exports, and for "
      "each pair of calottes their distance in REF and in TEST (mm) and its change (um). Calottes in only one file "
      "are left out with a warning.");
  sub->add_option("REF", options->ref, "reference centre export (CSV id,x,y,z in mm), e.g. the stitched one")
      ->required();
  sub->add_option("TEST", options->test, "centre export to compare with it")->required();
  sub->add_option("--pairs", options->pairs,
                  "calotte pairs a:b whose distances to compare, e.g. 1:6,1:31 (default: the first common calotte "
                  "with every other one)");
  sub->add_flag("--xy", options->xy, "distances in the XY plane, z ignored (as the stitching tables of [Pérez 2019])");
  sub->add_flag("--json", options->json,
                "print one JSON document {\"calottes\": [{\"id\", \"dx_um\", \"dy_um\", \"dz_um\", \"d_um\"}], "
                "\"pairs\": [{\"a\", \"b\", \"ref_mm\", \"test_mm\", \"diff_um\"}]}");
  sub->footer(
      "Example: fvm diff samples/stitching-strategies/x/a.csv samples/stitching-strategies/x/b.csv --pairs 1:6 --xy");
  sub->callback([options] { RunDiff(*options); });
}

}  // namespace fvm::cli
