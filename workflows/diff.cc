#include "workflows/diff.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::workflows {
namespace {

using artefacts::CentreExport;

std::string TrimmedBlanks(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") - begin + 1);
}

std::optional<int> ParseCalotteId(const std::string& s) {
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9) return std::nullopt;
  return static_cast<int>(*ParseInt(s));  // digits only, at most nine: always an int
}

// Fixed decimals without "-0.0": a difference that rounds to nothing has no sign.
std::string FixedUnsignedZero(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// Right-aligned columns two spaces apart, each as wide as its widest cell.
std::string Table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = header[c].size();
    for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
  }
  std::string text;
  const auto line = [&](const std::vector<std::string>& row) {
    for (size_t c = 0; c < row.size(); ++c) text += fmt::format("{}{:>{}}", c == 0 ? "" : "  ", row[c], width[c]);
    text += "\n";
  };
  line(header);
  for (const auto& row : rows) line(row);
  return text;
}

// The ids of both exports: in both (REF's order), in REF only, in TEST only.
struct IdMatch {
  std::vector<int> common, only_ref, only_test;
};

IdMatch MatchIds(const CentreExport& ref, const CentreExport& test) {
  IdMatch m;
  for (const auto& c : ref.centres) (test.Find(c.id) ? m.common : m.only_ref).push_back(c.id);
  for (const auto& c : test.centres) {
    if (!ref.Find(c.id)) m.only_test.push_back(c.id);
  }
  return m;
}

void RequireInBoth(int a, int b, const CentreExport& ref, const CentreExport& test, const std::string& ref_name,
                   const std::string& test_name, const std::vector<int>& common) {
  for (const int id : {a, b}) {
    if (ref.Find(id) && test.Find(id)) continue;
    const std::string where = !ref.Find(id) && !test.Find(id) ? ref_name + " nor in " + test_name
                              : ref.Find(id)                   ? test_name
                                                               : ref_name;
    throw InputError(fmt::format("--pairs {}:{}: calotte {} is not in {}; pair calottes present in both files "
                                 "(common ids: {})",
                                 a, b, id, where, fmt::join(common, ", ")));
  }
}

}  // namespace

std::vector<std::pair<int, int>> DiffOptions::Pairs() const {
  const auto bad = [&](const std::string& item) {
    return InputError(fmt::format("--pairs '{}': '{}' is not a pair of calotte ids; write a:b[,a:b...], e.g. "
                                  "--pairs 1:6,1:31",
                                  pairs, item));
  };
  std::vector<std::pair<int, int>> out;
  if (pairs.empty()) return out;
  size_t start = 0;
  while (true) {
    const size_t end = pairs.find(',', start);
    const std::string item = TrimmedBlanks(pairs.substr(start, end == std::string::npos ? end : end - start));
    const size_t colon = item.find(':');
    if (colon == std::string::npos) throw bad(item);
    const std::optional<int> a = ParseCalotteId(TrimmedBlanks(item.substr(0, colon)));
    const std::optional<int> b = ParseCalotteId(TrimmedBlanks(item.substr(colon + 1)));
    if (!a || !b) throw bad(item);
    if (*a == *b) {
      throw InputError(fmt::format("--pairs '{}': '{}' pairs calotte {} with itself, a distance of nothing; pair two "
                                   "different calottes",
                                   pairs, item, *a));
    }
    out.emplace_back(*a, *b);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

void DiffOptions::Check() const { Pairs(); }

DiffResult DiffExports(const CentreExport& ref, const CentreExport& test, const DiffOptions& options,
                       const std::string& ref_name, const std::string& test_name,
                       const std::function<void(const std::string&)>& warn) {
  DiffResult r{ref_name, test_name, options.xy, {}, {}, {}, {}};
  const IdMatch ids = MatchIds(ref, test);
  r.only_ref = ids.only_ref;
  r.only_test = ids.only_test;
  if (warn && !r.only_ref.empty()) warn(fmt::format("calotte {} only in {}; left out", fmt::join(r.only_ref, ", "), ref_name));
  if (warn && !r.only_test.empty()) warn(fmt::format("calotte {} only in {}; left out", fmt::join(r.only_test, ", "), test_name));
  if (ids.common.empty()) {
    throw InputError(fmt::format("{} and {} have no calotte id in common; compare two exports of the same artefact",
                                 ref_name, test_name));
  }
  std::vector<std::pair<int, int>> pairs = options.Pairs();
  if (options.pairs.empty()) {
    for (size_t i = 1; i < ids.common.size(); ++i) pairs.emplace_back(ids.common.front(), ids.common[i]);
  }
  // The published tables measure in the XY plane (their distances match the XY distance of their coordinates
  // to the last digit, the 3-D distance for the Y direction by 0.4 um only); --xy reproduces them.
  const auto distance = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return options.xy ? (p - q).head<2>().norm() : (p - q).norm();
  };
  for (const auto& [a, b] : pairs) {
    RequireInBoth(a, b, ref, test, ref_name, test_name, ids.common);
    r.pairs.push_back({a, b, distance(ref.Find(a)->position, ref.Find(b)->position),
                       distance(test.Find(a)->position, test.Find(b)->position)});
  }
  for (const int id : ids.common) r.calottes.push_back({id, (test.Find(id)->position - ref.Find(id)->position) * 1e3});
  return r;
}

DiffResult DiffFiles(const std::string& ref, const std::string& test, const DiffOptions& options,
                     const std::function<void(const std::string&)>& warn) {
  return DiffExports(artefacts::ReadCentreExport(ref), artefacts::ReadCentreExport(test), options, ref, test, warn);
}

Summary Summarize(const DiffResult& r) {
  Summary s;
  nlohmann::ordered_json& out = s.json;  // keys in the order a reader expects, not sorted
  out["distance"] = r.xy ? "xy" : "3d";
  out["only_in_ref"] = r.only_ref;
  out["only_in_test"] = r.only_test;
  out["calottes"] = nlohmann::ordered_json::array();
  for (const auto& c : r.calottes) {
    out["calottes"].push_back({{"id", c.id},
                               {"dx_um", RoundTo(c.d_um.x(), 1e4)},
                               {"dy_um", RoundTo(c.d_um.y(), 1e4)},
                               {"dz_um", RoundTo(c.d_um.z(), 1e4)},
                               {"d_um", RoundTo(c.d_um.norm(), 1e4)}});
  }
  out["pairs"] = nlohmann::ordered_json::array();
  for (const auto& p : r.pairs) {
    out["pairs"].push_back({{"a", p.a},
                            {"b", p.b},
                            {"ref_mm", RoundTo(p.ref_mm, 1e7)},
                            {"test_mm", RoundTo(p.test_mm, 1e7)},
                            {"diff_um", RoundTo(p.diff_um(), 1e4)}});
  }

  s.text = fmt::format("REF   {}\nTEST  {}\n\n", r.ref, r.test);
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : r.calottes) {
    rows.push_back({std::to_string(c.id), FixedUnsignedZero(c.d_um.x(), 1), FixedUnsignedZero(c.d_um.y(), 1),
                    FixedUnsignedZero(c.d_um.z(), 1), FixedUnsignedZero(c.d_um.norm(), 1)});
  }
  s.text += Table({"calotte", "dx [um]", "dy [um]", "dz [um]", "|d| [um]"}, rows);
  if (r.pairs.empty()) return s;
  rows.clear();
  for (const auto& p : r.pairs) {
    rows.push_back({fmt::format("{}:{}", p.a, p.b), FixedUnsignedZero(p.ref_mm, 4), FixedUnsignedZero(p.test_mm, 4),
                    FixedUnsignedZero(p.diff_um(), 1)});
  }
  s.text += fmt::format("\n{}\n", r.xy ? "distances in the XY plane (--xy)" : "distances in 3-D");
  s.text += Table({"pair", "REF [mm]", "TEST [mm]", "TEST-REF [um]"}, rows);
  return s;
}

}  // namespace fvm::workflows
