#include "artefacts/io/centre_export.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::artefacts {
namespace {

// No FVM stage travels a metre: larger coordinates are micrometres written where mm belong.
constexpr double kMaxCentreMm = 1000.0;

// A value the row may leave empty (nullopt) or must give; nan and inf are a failed sphere fit, refused with that
// explanation rather than the generic one.
std::optional<double> Value(const CsvTable& table, const CsvRow& row, int column, const std::string& calotte,
                            bool required) {
  if (column < 0) return std::nullopt;
  const std::optional<double> value = table.OptionalDouble(row, column, calotte);
  const std::string& name = table.header()[static_cast<size_t>(column)];
  if (!value && required) {
    table.Fail(row, fmt::format("{}: {} is empty; every calotte needs x, y and z in mm", calotte, name));
  }
  if (value && !std::isfinite(*value)) {
    table.Fail(row, fmt::format("{}: {} is {}; a calotte whose sphere fit failed has no centre: refit it or delete "
                                "its row",
                                calotte, name, table.Text(row, column)));
  }
  return value;
}

struct CentreColumns {
  explicit CentreColumns(const CsvTable& table)
      : id(table.Require("id")),
        axes{table.Require("x"), table.Require("y"), table.Require("z")},
        t(table.Optional("t")),
        radius(table.Optional("radius")),
        form_rms(table.Optional("form_rms")) {}
  int id;
  int axes[3];
  int t, radius, form_rms;  // -1 when absent
};

CentreRecord ReadCentreRow(const CsvTable& table, const CsvRow& row, const CentreColumns& columns) {
  CentreRecord record;
  record.line = row.line;
  record.id = static_cast<int>(
      table.Int(row, columns.id, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
  const std::string calotte = fmt::format("calotte {}", record.id);
  for (int axis = 0; axis < 3; ++axis) {
    const double v = *Value(table, row, columns.axes[axis], calotte, true);
    if (std::abs(v) > kMaxCentreMm) {
      table.Fail(row, fmt::format("{}: {} = {} is beyond {} mm and no FVM stage is a metre long; the export looks "
                                  "like micrometres: divide by 1000 (units are mm)",
                                  calotte, table.header()[static_cast<size_t>(columns.axes[axis])], v,
                                  kMaxCentreMm));
    }
    record.position[axis] = v;
  }
  record.t_s = Value(table, row, columns.t, calotte, false);
  record.radius_mm = Value(table, row, columns.radius, calotte, false);
  record.form_rms_mm = Value(table, row, columns.form_rms, calotte, false);
  return record;
}

}  // namespace

const CentreRecord* CentreExport::Find(int id) const {
  const auto it = std::find_if(centres.begin(), centres.end(), [id](const CentreRecord& c) { return c.id == id; });
  return it == centres.end() ? nullptr : &*it;
}

CentreExport ReadCentreExport(const std::filesystem::path& path) {
  CsvOptions options;
  options.expected_header = "id,x,y,z";
  const CsvTable table = ReadCsv(path, options);
  const CentreColumns columns(table);
  if (table.rows().empty()) {
    throw InputError(fmt::format("{}:{}: no calotte rows after the header; export the fitted centres, one row per "
                                 "calotte",
                                 table.name(), table.header_line()));
  }
  CentreExport data;
  data.source = table.name();
  data.comments = table.comments();
  std::map<int, int> first_line_of_id;
  for (const CsvRow& row : table.rows()) {
    CentreRecord record = ReadCentreRow(table, row, columns);
    const auto [it, inserted] = first_line_of_id.emplace(record.id, row.line);
    if (!inserted) {
      table.Fail(row, fmt::format("calotte {} appears again (first at line {}); an export holds each calotte once: "
                                  "remove or renumber one of them",
                                  record.id, it->second));
    }
    data.centres.push_back(std::move(record));
  }
  return data;
}

void WriteCentreExport(const std::filesystem::path& path, const CentreExport& data) {
  const auto any = [&](auto member) {
    return std::any_of(data.centres.begin(), data.centres.end(),
                       [&](const CentreRecord& c) { return (c.*member).has_value(); });
  };
  const bool with_t = any(&CentreRecord::t_s);
  const bool with_radius = any(&CentreRecord::radius_mm);
  const bool with_form = any(&CentreRecord::form_rms_mm);
  const bool with_converged = any(&CentreRecord::converged);

  std::string out = CsvComments(data.comments);
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

bool IsCentreExportFile(const std::filesystem::path& path) {
  if (AsciiLower(path.extension().string()) != ".csv") return false;
  const std::string head = ReadFileHead(path, 1 << 16);
  std::size_t start = 0;
  while (start < head.size()) {
    const std::size_t end = std::min(head.find('\n', start), head.size());
    const std::string_view line = TrimBlanks(std::string_view(head).substr(start, end - start));
    start = end + 1;
    if (line.empty() || line.front() == '#') continue;
    std::size_t field_start = 0;
    while (field_start <= line.size()) {
      const std::size_t field_end = std::min(line.find_first_of(",;\t", field_start), line.size());
      if (AsciiLower(TrimBlanks(line.substr(field_start, field_end - field_start))) == "id") return true;
      field_start = field_end + 1;
    }
    return false;
  }
  return false;
}

}  // namespace fvm::artefacts
