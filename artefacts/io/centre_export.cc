#include "artefacts/io/centre_export.h"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <string_view>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm::artefacts {
namespace {

// No FVM stage travels a metre: larger coordinates are micrometres written where mm belong.
constexpr double kMaxCoordinateMm = 1000.0;

std::string_view Trim(std::string_view s) {
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return s;
}

// Spreadsheets quote fields; a quoted number is still a number.
std::string_view Unquote(std::string_view s) {
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') return Trim(s.substr(1, s.size() - 2));
  return s;
}

std::string Lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

std::vector<std::string_view> Split(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t end = line.find(separator, start);
    fields.push_back(Unquote(Trim(line.substr(start, end == std::string_view::npos ? end : end - start))));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return fields;
}

// Comma is the contract; European spreadsheets write ';' and some tools tab-separate. The header decides.
char DetectSeparator(std::string_view header) {
  char best = ',';
  long best_count = std::count(header.begin(), header.end(), ',');
  for (const char candidate : {';', '\t'}) {
    const long count = std::count(header.begin(), header.end(), candidate);
    if (count > best_count) {
      best = candidate;
      best_count = count;
    }
  }
  return best;
}

std::string SeparatorName(char separator) {
  return separator == '\t' ? std::string("tab") : fmt::format("'{}'", separator);
}

// Leading '+' is legal in CSV written by hand; from_chars does not accept it.
std::optional<double> ParseDouble(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || error != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

std::optional<int> ParseInt(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  int value = 0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || error != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

struct Columns {
  int id = -1, x = -1, y = -1, z = -1, t = -1, radius = -1, form_rms = -1;
};

class Reader {
 public:
  explicit Reader(const std::filesystem::path& path) : path_(path), name_(path.string()) {}

  CentreExport Read() {
    std::ifstream in(path_);
    if (!in) {
      throw InputError(fmt::format("{}: cannot open the centre export ({}); check the path", name_,
                                   std::strerror(errno)));
    }
    CentreExport data;
    data.source = name_;
    std::map<int, int> first_line_of_id;
    std::string raw;
    int number = 0;
    while (std::getline(in, raw)) {
      ++number;
      std::string_view line = raw;
      if (number == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // spreadsheet BOM
      line = Trim(line);  // also drops the '\r' of files written on Windows
      if (line.empty()) continue;
      if (line.front() == '#') {
        line.remove_prefix(1);
        if (!line.empty() && line.front() == ' ') line.remove_prefix(1);
        data.comments.emplace_back(line);
        continue;
      }
      if (header_line_ == 0) {
        ReadHeader(line, number);
        continue;
      }
      CentreRecord record = ReadRow(line, number);
      const auto [it, inserted] = first_line_of_id.emplace(record.id, number);
      if (!inserted) {
        throw InputError(fmt::format("{}:{}: calotte {} appears again (first at line {}); an export holds each "
                                     "calotte once: remove or renumber one of them",
                                     name_, number, record.id, it->second));
      }
      data.centres.push_back(std::move(record));
    }
    if (in.bad()) {
      throw InputError(fmt::format("{}:{}: read error ({}); check the file", name_, number, std::strerror(errno)));
    }
    if (header_line_ == 0) {
      if (number == 0) {
        throw InputError(fmt::format("{}: the file is empty, no header line; write a header id,x,y,z and one row per "
                                     "calotte",
                                     name_));
      }
      throw InputError(fmt::format("{}: no header line (only comments or blank lines); the first line that is not a "
                                   "'#' comment must name the columns, at least id,x,y,z",
                                   Where(number)));
    }
    if (data.centres.empty()) {
      throw InputError(fmt::format("{}:{}: no calotte rows after the header; export the fitted centres, one row "
                                   "per calotte",
                                   name_, header_line_));
    }
    return data;
  }

 private:
  std::string Where(int line) const { return fmt::format("{}:{}", name_, line); }

  void ReadHeader(std::string_view line, int number) {
    separator_ = DetectSeparator(line);
    const std::vector<std::string_view> fields = Split(line, separator_);
    n_fields_ = fields.size();
    std::map<std::string, int> index;
    for (size_t i = 0; i < fields.size(); ++i) {
      const std::string name = Lower(fields[i]);
      if (name.empty()) continue;  // a trailing separator: an unnamed column, ignored like any other extra
      if (!index.emplace(name, static_cast<int>(i)).second) {
        throw InputError(fmt::format("{}: column '{}' appears twice in the header; keep one of them", Where(number),
                                     name));
      }
    }
    const auto find = [&](const char* name) {
      const auto it = index.find(name);
      return it == index.end() ? -1 : it->second;
    };
    columns_ = {find("id"), find("x"), find("y"), find("z"), find("t"), find("radius"), find("form_rms")};
    std::string missing;
    for (const auto& [name, column] : {std::pair{"id", columns_.id}, {"x", columns_.x}, {"y", columns_.y},
                                       {"z", columns_.z}}) {
      if (column < 0) missing += missing.empty() ? name : std::string(", ") + name;
    }
    if (!missing.empty()) {
      const bool looks_like_data = !fields.empty() && ParseDouble(fields[0]).has_value();
      throw InputError(fmt::format(
          "{}: the header '{}' has no column {}; {}", Where(number), line, missing,
          looks_like_data ? "this line looks like data: add a header line id,x,y,z above the rows"
                          : "name the columns at least id,x,y,z (mm), separated by commas"));
    }
    header_line_ = number;
  }

  CentreRecord ReadRow(std::string_view line, int number) {
    const std::vector<std::string_view> fields = Split(line, separator_);
    if (fields.size() != n_fields_) {
      const bool decimal_comma = separator_ == ',' && fields.size() > n_fields_;
      throw InputError(fmt::format("{}: {} fields where the header (line {}) has {}; {}", Where(number),
                                   fields.size(), header_line_, n_fields_,
                                   decimal_comma ? "write numbers with '.' as the decimal mark, not ','"
                                                 : "give every row one value per header column, separated by " +
                                                       SeparatorName(separator_)));
    }
    CentreRecord record;
    record.line = number;
    const std::string_view id_text = fields[static_cast<size_t>(columns_.id)];
    const std::optional<int> id = ParseInt(id_text);
    if (!id) {
      throw InputError(fmt::format("{}: id '{}' is not a whole number; calotte ids are integers (1, 2, ...)",
                                   Where(number), id_text));
    }
    record.id = *id;
    const auto value = [&](int column, const char* name, bool required) -> std::optional<double> {
      if (column < 0) return std::nullopt;
      const std::string_view text = fields[static_cast<size_t>(column)];
      if (text.empty()) {
        if (!required) return std::nullopt;  // an optional value this calotte lacks
        throw InputError(fmt::format("{}: calotte {}: {} is empty; every calotte needs x, y and z in mm",
                                     Where(number), record.id, name));
      }
      const std::optional<double> parsed = ParseDouble(text);
      if (!parsed) {
        throw InputError(fmt::format("{}: calotte {}: {} '{}' is not a number; write plain numbers with '.' as the "
                                     "decimal mark",
                                     Where(number), record.id, name, text));
      }
      if (!std::isfinite(*parsed)) {
        throw InputError(fmt::format("{}: calotte {}: {} is {}; a calotte whose sphere fit failed has no centre: "
                                     "refit it or delete its row",
                                     Where(number), record.id, name, text));
      }
      return parsed;
    };
    const char* axis_names[] = {"x", "y", "z"};
    const int axis_columns[] = {columns_.x, columns_.y, columns_.z};
    for (int axis = 0; axis < 3; ++axis) {
      const double v = *value(axis_columns[axis], axis_names[axis], true);
      if (std::abs(v) > kMaxCoordinateMm) {
        throw InputError(fmt::format("{}: calotte {}: {} = {} is beyond {} mm and no FVM stage is a metre long; the "
                                     "export looks like micrometres: divide by 1000 (units are mm)",
                                     Where(number), record.id, axis_names[axis], v, kMaxCoordinateMm));
      }
      record.position[axis] = v;
    }
    record.t_s = value(columns_.t, "t", false);
    record.radius_mm = value(columns_.radius, "radius", false);
    record.form_rms_mm = value(columns_.form_rms, "form_rms", false);
    return record;
  }

  std::filesystem::path path_;
  std::string name_;
  int header_line_ = 0;
  char separator_ = ',';
  size_t n_fields_ = 0;
  Columns columns_;
};

}  // namespace

const CentreRecord* CentreExport::Find(int id) const {
  const auto it = std::find_if(centres.begin(), centres.end(), [id](const CentreRecord& c) { return c.id == id; });
  return it == centres.end() ? nullptr : &*it;
}

CentreExport ReadCentreExport(const std::filesystem::path& path) { return Reader(path).Read(); }

void WriteCentreExport(const std::filesystem::path& path, const CentreExport& data) {
  const auto any = [&](auto member) {
    return std::any_of(data.centres.begin(), data.centres.end(),
                       [&](const CentreRecord& c) { return (c.*member).has_value(); });
  };
  const bool with_t = any(&CentreRecord::t_s);
  const bool with_radius = any(&CentreRecord::radius_mm);
  const bool with_form = any(&CentreRecord::form_rms_mm);
  const bool with_converged = any(&CentreRecord::converged);

  std::string out;
  for (const std::string& comment : data.comments) {
    // A comment holding a line break would end the comment and start a bogus row.
    size_t start = 0;
    while (true) {
      const size_t end = comment.find('\n', start);
      const std::string_view part = std::string_view(comment).substr(start, end - start);
      out += part.empty() ? "#\n" : fmt::format("# {}\n", part);
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  out += "id,x,y,z";
  if (with_t) out += ",t";
  if (with_radius) out += ",radius";
  if (with_form) out += ",form_rms";
  if (with_converged) out += ",converged";
  out += '\n';
  const auto optional = [](const std::optional<double>& v) { return v ? fmt::format(",{:.6f}", *v) : ","; };
  for (const CentreRecord& c : data.centres) {
    // Refuse what ReadCentreExport would refuse: an output we cannot read back is worse than none.
    const bool finite = c.position.allFinite() && (!c.t_s || std::isfinite(*c.t_s)) &&
                        (!c.radius_mm || std::isfinite(*c.radius_mm)) &&
                        (!c.form_rms_mm || std::isfinite(*c.form_rms_mm));
    if (!finite) {
      throw InputError(fmt::format("{}: calotte {} has a value that is not finite; nothing was written: drop or "
                                   "refit that calotte",
                                   path.string(), c.id));
    }
    out += fmt::format("{},{:.6f},{:.6f},{:.6f}", c.id, c.position.x(), c.position.y(), c.position.z());
    if (with_t) out += optional(c.t_s);
    if (with_radius) out += optional(c.radius_mm);
    if (with_form) out += optional(c.form_rms_mm);
    if (with_converged) out += c.converged ? (*c.converged ? ",1" : ",0") : ",";
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace fvm::artefacts
