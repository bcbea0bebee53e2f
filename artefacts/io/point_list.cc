#include "artefacts/io/point_list.h"

#include <fmt/core.h>

#include <array>
#include <cmath>
#include <set>

#include "core/csv.h"
#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::artefacts {

std::vector<ListedPoint> ReadPointList(const std::filesystem::path& path) {
  CsvOptions options;
  options.expected_header = "id,x,y,z";
  const CsvTable table = ReadCsv(path, options);
  const int id_column = table.Require("id");
  const std::array<int, 3> columns = {table.Require("x"), table.Require("y"), table.Require("z")};
  const int approach_column = table.Optional("approach");
  std::vector<ListedPoint> points;
  std::set<std::string, std::less<>> seen;
  for (const CsvRow& row : table.rows()) {
    const std::string id(TrimBlanks(table.Text(row, id_column)));
    if (id.empty()) table.Fail(row, "the point has no id; give every point a text id such as P0001");
    if (!seen.insert(id).second) table.Fail(row, fmt::format("point {}: the id appears twice; ids must be unique", id));
    ListedPoint p{id, Eigen::Vector3d::Zero(), ""};
    for (int k = 0; k < 3; ++k) {
      p.position[k] = table.Double(row, columns[static_cast<size_t>(k)], "point " + id);
      if (std::abs(p.position[k]) > 1e5) {
        table.Fail(row, fmt::format("point {}: {} = {} mm lies beyond 100 m; the list must be in mm", id, "xyz"[k],
                                    FormatShortest(p.position[k])));
      }
    }
    if (approach_column >= 0) p.approach = std::string(TrimBlanks(table.Text(row, approach_column)));
    points.push_back(std::move(p));
  }
  if (points.empty()) throw InputError(fmt::format("{}: no points; write a header id,x,y,z and one row per point", table.name()));
  return points;
}

std::map<std::string, ListedPoint, std::less<>> PointsById(std::vector<ListedPoint> points) {
  std::map<std::string, ListedPoint, std::less<>> by_id;
  for (ListedPoint& p : points) {
    std::string id = p.id;
    by_id.emplace(std::move(id), std::move(p));
  }
  return by_id;
}

}  // namespace fvm::artefacts
