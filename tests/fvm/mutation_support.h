#pragma once
// Seeded, structured mutations of the files and options a command reads, for the property tests that run the fvm
// executable on them (issues 34 and 44), and the checks of what comes out: no nan or inf written or printed.

#include <algorithm>
#include <filesystem>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/test_support.h"

namespace fvm::testing {

namespace fs = std::filesystem;

inline const std::vector<std::string> kAbsurd = {"0", "-1", "1e-300", "1e308", "nan", "inf", "-inf", "1e3", "2.5", "", "abc", "1,2", "1e-300x1e-300x1e-300"};

inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

inline std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (size_t k = 0; k < parts.size(); ++k) out += (k ? separator : "") + parts[k];
  return out;
}

// Where a CSV's header and data lines are ('#' comments and empty lines skipped); header = lines.size() when none.
struct CsvLines {
  size_t header = 0;
  std::vector<size_t> rows;
};
inline CsvLines FindCsvLines(const std::vector<std::string>& lines) {
  CsvLines found{lines.size(), {}};
  for (size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].empty() || lines[k][0] == '#') continue;
    if (found.header == lines.size()) {
      found.header = k;
    } else {
      found.rows.push_back(k);
    }
  }
  return found;
}

// One structured mutation of a CSV file (header first, '#' comments kept).
inline std::string MutateCsv(const std::string& text, std::mt19937_64& random) {
  std::vector<std::string> lines = Lines(text);
  const auto [header, rows] = FindCsvLines(lines);
  if (rows.empty()) return text;
  const auto pick = [&](size_t n) { return static_cast<size_t>(random() % n); };
  const size_t row = rows[pick(rows.size())];
  switch (pick(7)) {
    case 0: {  // a cell becomes absurd
      std::vector<std::string> cells = Cells(lines[row]);
      cells[pick(cells.size())] = kAbsurd[pick(kAbsurd.size())];
      lines[row] = Join(cells, ",");
      break;
    }
    case 1:  // a row twice
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(row), lines[row]);
      break;
    case 2:  // a row gone
      lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(row));
      break;
    case 3: {  // two columns of the header swapped
      std::vector<std::string> cells = Cells(lines[header]);
      std::swap(cells[pick(cells.size())], cells[pick(cells.size())]);
      lines[header] = Join(cells, ",");
      break;
    }
    case 4:  // every reading the same
      for (const size_t r : rows) lines[r] = lines[rows.front()];
      break;
    case 5: {  // a column scaled by a factor of 1e300 or mirrored
      std::vector<std::string> head = Cells(lines[header]);
      const size_t column = pick(head.size());
      const double factor = random() % 2 ? -1.0 : 1e300;
      for (const size_t r : rows) {
        std::vector<std::string> cells = Cells(lines[r]);
        if (column >= cells.size()) continue;
        try {
          cells[column] = std::to_string(std::stod(cells[column]) * factor);
        } catch (const std::exception&) {
        }
        lines[r] = Join(cells, ",");
      }
      break;
    }
    default: {  // cut short in the middle of a line
      const std::string joined = Join(lines, "\n");
      return joined.substr(0, joined.size() / 2 + pick(joined.size() / 2));
    }
  }
  return Join(lines, "\n") + "\n";
}

// The values black-box fuzzing found faults with (issue 44): subnormal, huge, NaN spelled as text, empty fields.
inline const std::vector<std::string> kNumberTraps = {"1e-310", "4.9e-324", "-2e-320", "1e308", "1.7e308", "-1e300",
                                                      "nan",    "NaN",      "-nan",    "NAN",   "inf",     "-Infinity",
                                                      "",       " "};

// One mutation aimed at the numbers of a CSV: a cell turned into a trap, a whole column of one (an export written
// by a broken converter: every x 1e-310), a gross outlier (one value off by up to a bar's length, as a hand-edited
// export carries), or an empty field.
inline std::string MutateNumbers(const std::string& text, std::mt19937_64& random) {
  std::vector<std::string> lines = Lines(text);
  const auto [header, rows] = FindCsvLines(lines);
  if (rows.empty()) return text;
  const auto pick = [&](size_t n) { return static_cast<size_t>(random() % n); };
  const size_t row = rows[pick(rows.size())];
  std::vector<std::string> cells = Cells(lines[row]);
  const size_t column = pick(cells.size());
  switch (pick(4)) {
    case 0:
      cells[column] = kNumberTraps[pick(kNumberTraps.size())];
      lines[row] = Join(cells, ",");
      break;
    case 1: {
      const std::string trap = kNumberTraps[pick(kNumberTraps.size())];
      for (const size_t r : rows) {
        std::vector<std::string> c = Cells(lines[r]);
        if (column < c.size()) c[column] = trap;
        lines[r] = Join(c, ",");
      }
      break;
    }
    case 2:
      try {
        const double off = (random() % 2 ? 1.0 : -1.0) * static_cast<double>(1 + pick(200));
        std::ostringstream value;
        value.precision(6);
        value << std::fixed << std::stod(cells[column]) + off;
        cells[column] = value.str();
      } catch (const std::exception&) {
        cells[column] = "1e-310";
      }
      lines[row] = Join(cells, ",");
      break;
    default:
      cells[column].clear();
      lines[row] = Join(cells, ",");
      break;
  }
  return Join(lines, "\n") + "\n";
}

inline bool HoldsNonFinite(const std::string& text) {
  static const std::regex non_finite(R"((^|[^A-Za-z_])(-?nan|-?inf|NaN|-?Inf|infinity)([^A-Za-z_]|$))", std::regex::icase);
  return std::regex_search(text, non_finite);
}

inline std::string FilesText(const fs::path& path) {
  if (!fs::exists(path)) return {};
  if (!fs::is_directory(path)) return ReadText(path);
  std::string all;
  for (const auto& entry : fs::recursive_directory_iterator(path)) {
    if (entry.is_regular_file() && entry.path().extension() != ".svg") all += ReadText(entry.path());
  }
  return all;
}

}  // namespace fvm::testing
