#include "core/csv.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm {
namespace {

constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

std::string SeparatorName(char separator) {
  return separator == '\t' ? std::string("tab") : fmt::format("'{}'", separator);
}

// Blanks around a field are trimmed, except the separator itself when it is a tab.
bool IsBlank(char c, char separator) { return (c == ' ' || c == '\t' || c == '\r') && c != separator; }

// The most frequent of ',' ';' tab outside quotes in the header line; ',' (the contract) on a tie or when none.
char DetectSeparator(std::string_view line) {
  std::size_t counts[3] = {0, 0, 0};
  constexpr char kCandidates[3] = {',', ';', '\t'};
  bool quoted = false;
  for (const char c : line) {
    if (c == '"') quoted = !quoted;
    if (quoted) continue;
    for (int i = 0; i < 3; ++i) counts[i] += c == kCandidates[i];
  }
  int best = 0;
  for (int i = 1; i < 3; ++i) {
    if (counts[i] > counts[best]) best = i;
  }
  return kCandidates[best];
}

// Reads one record starting at `pos` (not on a blank or comment line): fields split at the separator outside
// quotes, quoted fields unquoted. Leaves `pos` after the record's line end and counts the line breaks it passes.
class RecordParser {
 public:
  RecordParser(std::string_view text, const std::string& name, char separator, std::size_t max_columns)
      : text_(text), name_(name), separator_(separator), max_columns_(max_columns) {}

  std::vector<std::string> Next(std::size_t& pos, int& line) const {
    std::vector<std::string> fields;
    const std::size_t n = text_.size();
    while (true) {
      if (fields.size() >= max_columns_) {
        throw InputError(fmt::format("{}:{}: more than {} fields in one row; is this a CSV table? (separator {})",
                                     name_, line, max_columns_, SeparatorName(separator_)));
      }
      while (pos < n && IsBlank(text_[pos], separator_)) ++pos;
      std::string field;
      if (pos < n && text_[pos] == '"') {
        const int opened = line;
        ++pos;
        while (true) {
          if (pos >= n) {
            throw InputError(
                fmt::format("{}:{}: field {}: the quote opened here is never closed; close the field "
                            "with \" (a quote inside a quoted field is written \"\")",
                            name_, opened, fields.size() + 1));
          }
          const char c = text_[pos++];
          if (c == '"') {
            if (pos < n && text_[pos] == '"') {
              field += '"';
              ++pos;
              continue;
            }
            break;
          }
          if (c == '\n') ++line;
          field += c;
        }
        while (pos < n && IsBlank(text_[pos], separator_)) ++pos;
        if (pos < n && text_[pos] != separator_ && text_[pos] != '\n') {
          throw InputError(
              fmt::format("{}:{}: field {}: text after the closing quote; quote the whole field and "
                          "write a quote inside it as \"\"",
                          name_, line, fields.size() + 1));
        }
      } else {
        const std::size_t start = pos;
        while (pos < n && text_[pos] != separator_ && text_[pos] != '\n') ++pos;
        field = std::string(TrimBlanks(text_.substr(start, pos - start)));
      }
      fields.push_back(std::move(field));
      if (pos >= n) return fields;
      if (text_[pos++] == '\n') {
        ++line;
        return fields;
      }
    }
  }

 private:
  std::string_view text_;
  const std::string& name_;
  char separator_;
  std::size_t max_columns_;
};

}  // namespace

CsvTable ParseCsv(std::string_view text, std::string name, const CsvOptions& options) {
  if (text.size() > options.max_bytes) {
    throw InputError(
        fmt::format("{}: {} bytes is more than the {} a CSV table may have here; is this the right "
                    "file?",
                    name, text.size(), options.max_bytes));
  }
  if (text.substr(0, kByteOrderMark.size()) == kByteOrderMark) text.remove_prefix(kByteOrderMark.size());
  CsvTable table;
  table.name_ = std::move(name);
  const std::string& file = table.name_;
  table.expected_header_ = options.expected_header;
  const std::string expected =
      options.expected_header.empty() ? std::string("naming the columns") : options.expected_header;
  int line = 1;
  std::size_t pos = 0;
  std::optional<RecordParser> parser;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view whole_line = TrimBlanks(text.substr(pos, end - pos));
    if (whole_line.empty() || whole_line.front() == '#') {
      if (!whole_line.empty()) {
        std::string_view comment = whole_line.substr(1);
        if (!comment.empty() && comment.front() == ' ') comment.remove_prefix(1);
        table.comments_.emplace_back(comment);
      }
      pos = end + 1;
      ++line;
      continue;
    }
    const int first_line = line;
    if (!parser) {
      table.separator_ = options.separator != 0 ? options.separator : DetectSeparator(whole_line);
      parser.emplace(text, file, table.separator_, options.max_columns);
      table.header_line_ = first_line;
      table.header_ = parser->Next(pos, line);
      for (std::size_t i = 0; i < table.header_.size(); ++i) {
        table.lower_header_.push_back(AsciiLower(table.header_[i]));
        const std::string& key = table.lower_header_.back();
        if (key.empty()) continue;  // a trailing separator: an unnamed column, ignored like any other extra one
        for (std::size_t j = 0; j < i; ++j) {
          if (table.lower_header_[j] == key && ParseDouble(key).has_value()) {
            // A repeated number is a data row read as the header ("1,0,0,0"): say that, not "column '0' twice".
            throw InputError(fmt::format("{}:{}: this line holds numbers, not column names: the header line is "
                                         "missing; add one naming the columns ({}) above the rows",
                                         file, first_line, expected));
          }
          if (table.lower_header_[j] == key) {
            throw InputError(
                fmt::format("{}:{}: column '{}' appears twice in the header (fields {} and {}); keep "
                            "one of them",
                            file, first_line, key, j + 1, i + 1));
          }
        }
      }
      continue;
    }
    if (table.rows_.size() >= options.max_rows) {
      throw InputError(fmt::format("{}:{}: more than {} rows; split the table or check that this is the right file",
                                   file, first_line, options.max_rows));
    }
    CsvRow row;
    row.line = first_line;
    row.fields = parser->Next(pos, line);
    const std::size_t want = table.header_.size();
    if (row.fields.size() != want) {
      const bool decimal_comma = table.separator_ == ',' && row.fields.size() > want;
      throw InputError(fmt::format("{}:{}: {} fields where the header (line {}) has {}; {}", file, first_line,
                                   row.fields.size(), table.header_line_, want,
                                   decimal_comma ? "write numbers with '.' as the decimal mark, not ','"
                                                 : "give every row one value per header column, separated by " +
                                                       SeparatorName(table.separator_)));
    }
    table.rows_.push_back(std::move(row));
  }
  if (!parser) {
    if (TrimBlanks(text).empty()) {
      throw InputError(
          fmt::format("{}: the file is empty, no header line; write a header line {} and the rows "
                      "below it",
                      file, expected));
    }
    throw InputError(
        fmt::format("{}:{}: no header line (only comments or blank lines); the first line that is not "
                    "a '#' comment must name the columns ({})",
                    file, line - 1, expected));
  }
  return table;
}

CsvTable ReadCsv(const std::filesystem::path& path, const CsvOptions& options) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw InputError(fmt::format("{}: is a directory, not a file; name the CSV table itself (a header line {} and "
                                 "one row per line)",
                                 path.string(), options.expected_header.empty() ? std::string("naming the columns")
                                                                                : options.expected_header));
  }
  return ParseCsv(ReadFileBytes(path, options.max_bytes), path.string(), options);
}

int CsvTable::Optional(std::string_view column) const {
  const std::string key = AsciiLower(column);
  const auto it = std::find(lower_header_.begin(), lower_header_.end(), key);
  return it == lower_header_.end() ? -1 : static_cast<int>(it - lower_header_.begin());
}

int CsvTable::Require(std::string_view column) const {
  const int index = Optional(column);
  if (index >= 0) return index;
  const bool looks_like_data = !header_.empty() && ParseDouble(header_.front()).has_value();
  const std::string expected = expected_header_.empty() ? std::string() : " " + expected_header_;
  throw InputError(fmt::format(
      "{}:{}: the header has no column '{}'; {}", name_, header_line_, column,
      looks_like_data ? fmt::format("this line looks like data: add a header line{} above the rows", expected)
                      : fmt::format("the first line that is not a '#' comment names the columns{}", expected)));
}

std::string CsvTable::Where(const CsvRow& row) const { return fmt::format("{}:{}", name_, row.line); }

void CsvTable::Fail(const CsvRow& row, std::string_view problem) const {
  throw InputError(fmt::format("{}: {}", Where(row), problem));
}

std::string CsvTable::Column(int column) const {
  return fmt::format("column '{}' (field {})", header_[static_cast<std::size_t>(column)], column + 1);
}

void CsvTable::FailCell(const CsvRow& row, int column, std::string_view context, std::string_view problem) const {
  Fail(row, fmt::format("{}{}{}{}", context, context.empty() ? "" : ": ", Column(column), problem));
}

std::string_view CsvTable::Text(const CsvRow& row, int column) const {
  if (column < 0 || static_cast<std::size_t>(column) >= row.fields.size()) return {};
  return row.fields[static_cast<std::size_t>(column)];
}

std::optional<double> CsvTable::OptionalDouble(const CsvRow& row, int column, std::string_view context) const {
  const std::string_view text = Text(row, column);
  if (text.empty()) return std::nullopt;
  const std::optional<double> value = ParseDouble(text);
  if (!value) {
    FailCell(row, column, context,
             fmt::format(": '{}' is not a number; write plain numbers with '.' as the decimal mark", text));
  }
  // Nonzero but below 2.2e-308 in size: no instrument writes it, and sums and squares of it underflow to 0 and
  // divide into NaN further on (fvm diagnose died on stitching-free x of 1e-310, issue 44).
  if (std::fpclassify(*value) == FP_SUBNORMAL) {
    FailCell(row, column, context,
             fmt::format(": '{}' is a subnormal number (nonzero, yet below 2.2e-308 in size), which no measurement "
                         "gives; write 0 or the value meant",
                         text));
  }
  return value;
}

double CsvTable::Double(const CsvRow& row, int column, std::string_view context) const {
  const std::optional<double> value = OptionalDouble(row, column, context);
  if (!value) FailCell(row, column, context, " is empty; every row needs a number here");
  if (!std::isfinite(*value)) {
    FailCell(row, column, context, fmt::format(" is {}; give a finite number", Text(row, column)));
  }
  return *value;
}

std::int64_t CsvTable::Int(const CsvRow& row, int column, std::int64_t min, std::int64_t max,
                           std::string_view context) const {
  const std::string_view text = Text(row, column);
  const std::string range = fmt::format("give a whole number from {} to {}", min, max);
  if (text.empty()) FailCell(row, column, context, " is empty; " + range);
  const std::optional<std::int64_t> value = ParseInt(text);
  if (!value) FailCell(row, column, context, fmt::format(": '{}' is not a whole number; {}", text, range));
  if (*value < min || *value > max)
    FailCell(row, column, context, fmt::format(": {} is out of range; {}", text, range));
  return *value;
}

std::string CsvField(std::string_view text) {
  const bool needs_quotes = text.find_first_of(",;\t\"\r\n") != std::string_view::npos ||
                            (!text.empty() && (text.front() == '#' || text.front() == ' ' || text.back() == ' '));
  if (!needs_quotes) return std::string(text);
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string CsvComments(const std::vector<std::string>& comments) {
  std::string out;
  for (const std::string& comment : comments) {
    std::size_t start = 0;
    while (true) {
      const std::size_t end = comment.find('\n', start);
      const std::string_view part = std::string_view(comment).substr(start, end - start);
      out += part.empty() ? "#\n" : "# " + std::string(part) + "\n";
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  return out;
}

std::string CsvLine(const std::vector<std::string>& fields, char separator) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) out += separator;
    out += CsvField(fields[i]);
  }
  out += '\n';
  return out;
}

}  // namespace fvm
