#pragma once
// One CSV reader and writer for every table the tools exchange (centre exports, tile layouts, focus-stack lists,
// tracker and multilateration data): the same dialect everywhere and the same error messages, naming the file,
// the line and the column.
//
// The dialect: a header row naming the columns (matched without regard to case), `#` comment lines and blank
// lines anywhere outside a quoted field, the separator `,` `;` or tab (taken from the header unless given),
// RFC 4180 quoting (a quoted field may hold the separator, a line break and doubled quotes "" for one quote),
// CRLF or LF line ends, an optional UTF-8 byte order mark, blanks around a field ignored. Numbers are read with
// core/number_text.h: '.' is the decimal mark whatever the locale.
//
// Why our own reader and not libcsv: libcsv is a streaming C parser that calls back per field and per record.
// It knows nothing of comment lines (a `#` line with a comma becomes a record), of header names, or of the line a
// record started on, so every message "FILE:LINE: column 'x'" would need a layer of our own on top that tracks
// lines through its callbacks; the quote handling, the part it would save, is some forty lines here. One small
// reader that keeps positions is simpler to use, to test and to ship (no extra system package).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fvm {

struct CsvOptions {
  char separator = 0;  // 0: the one of ',' ';' tab that occurs most often in the header (',' on a tie)
  // What the header should name, for the messages on a file without one, e.g. "id,x,y,z".
  std::string expected_header;
  // Bounds checked while reading, before anything grows: a damaged or mistaken file fails with a message instead
  // of filling the memory.
  std::size_t max_bytes = std::size_t{1} << 30;
  std::size_t max_rows = 10'000'000;
  std::size_t max_columns = 1000;
};

struct CsvRow {
  int line = 0;                     // the line the row starts on (1-based, as an editor counts)
  std::vector<std::string> fields;  // as many as the header has (the reader refuses other counts)
};

class CsvTable {
 public:
  const std::string& name() const { return name_; }  // the file, as messages name it
  char separator() const { return separator_; }
  int header_line() const { return header_line_; }
  const std::vector<std::string>& header() const { return header_; }  // names as written, blanks trimmed
  const std::vector<CsvRow>& rows() const { return rows_; }
  // Text of the `#` comment lines in file order, without the '#' and one space after it.
  const std::vector<std::string>& comments() const { return comments_; }

  // The index of the column with this name (case-insensitive), or -1.
  int Optional(std::string_view column) const;
  // The same, throwing InputError "FILE:LINE: the header has no column 'z'; ..." (LINE of the header) when absent.
  int Require(std::string_view column) const;

  // "FILE:LINE" of a row, for messages of the caller's own.
  std::string Where(const CsvRow& row) const;
  // Throws InputError "FILE:LINE: problem".
  [[noreturn]] void Fail(const CsvRow& row, std::string_view problem) const;

  // Cells. `column` is an index from Require/Optional (Optional's -1 reads as an empty cell). `context` (e.g.
  // "calotte 7") goes into messages after FILE:LINE. Messages read
  //   "FILE:LINE: context: column 'x' (field 3): 'abc' is not a number; write plain numbers with '.' ..."
  std::string_view Text(const CsvRow& row, int column) const;
  // Empty cell: nullopt. Otherwise the number, nan and inf included (the caller knows what they mean); a subnormal
  // number (nonzero, below 2.2e-308 in size) throws.
  std::optional<double> OptionalDouble(const CsvRow& row, int column, std::string_view context = {}) const;
  // A finite number; an empty cell, nan or inf throws.
  double Double(const CsvRow& row, int column, std::string_view context = {}) const;
  // A whole number in [min, max]; anything else (empty, 1.5, out of range) throws naming the range.
  std::int64_t Int(const CsvRow& row, int column, std::int64_t min, std::int64_t max,
                   std::string_view context = {}) const;

 private:
  friend CsvTable ParseCsv(std::string_view text, std::string name, const CsvOptions& options);
  std::string Column(int column) const;
  [[noreturn]] void FailCell(const CsvRow& row, int column, std::string_view context, std::string_view problem) const;

  std::string name_;
  std::string expected_header_;
  char separator_ = ',';
  int header_line_ = 0;
  std::vector<std::string> header_;
  std::vector<std::string> lower_header_;
  std::vector<CsvRow> rows_;
  std::vector<std::string> comments_;
};

// Reads and parses a file; `name` in messages is the path as given. Throws InputError on a missing or unreadable
// file, no header, a duplicate column name, a row with another number of fields than the header, an unclosed
// quote, text after a closing quote, or a bound of the options exceeded.
CsvTable ReadCsv(const std::filesystem::path& path, const CsvOptions& options = {});
// The same for text already in memory; `name` stands for the file in messages.
CsvTable ParseCsv(std::string_view text, std::string name, const CsvOptions& options = {});

// Writing: the field as it must appear in a CSV line, quoted (with inner quotes doubled) only when it holds a
// separator of the dialect, a quote, a line break, '#' first, or blanks at either end that a reader would trim.
std::string CsvField(std::string_view text);
// The fields joined by `separator`, each through CsvField, and a '\n'.
std::string CsvLine(const std::vector<std::string>& fields, char separator = ',');
// Comment lines "# text", one per line of each comment: a line break inside a comment must not start a row.
std::string CsvComments(const std::vector<std::string>& comments);

}  // namespace fvm
