#include "artefacts/geometry/machined_piece.h"

#include <fmt/core.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "core/number_text.h"

namespace fvm::artefacts {
namespace {

using nlohmann::json;

struct KindName {
  FeatureKind kind;
  const char* name;
};
constexpr KindName kKinds[] = {{FeatureKind::kSlot, "slot"},
                               {FeatureKind::kSideSlot, "side_slot"},
                               {FeatureKind::kHole, "hole"},
                               {FeatureKind::kPyramid, "pyramid"},
                               {FeatureKind::kCrenellation, "crenellation"}};

PieceFeature Box(std::string name, FeatureKind kind, Eigen::Vector3d min, Eigen::Vector3d max) {
  PieceFeature f;
  f.name = std::move(name);
  f.kind = kind;
  f.min = min;
  f.max = max;
  return f;
}

// Points every `pitch` along the perimeter of the rectangle [x0, x1] x [y0, y1] at height z, counter-clockwise from
// (x0, y0); the sides must be multiples of the pitch.
std::vector<ProbePoint> Ring(double x0, double y0, double x1, double y1, double z, double pitch) {
  std::vector<ProbePoint> out;
  const Eigen::Vector2d corners[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector2d a = corners[side], b = corners[(side + 1) % 4];
    const int steps = static_cast<int>(std::lround((b - a).norm() / pitch));
    for (int i = 0; i < steps; ++i) {
      const Eigen::Vector2d p = a + (b - a) * i / steps;
      out.push_back({Eigen::Vector3d(p.x(), p.y(), z), ""});
    }
  }
  return out;
}

std::vector<ProbePoint> Line(const Eigen::Vector3d& from, const Eigen::Vector3d& step, int count, const std::string& series) {
  std::vector<ProbePoint> out;
  for (int i = 0; i < count; ++i) out.push_back({from + step * i, series});
  return out;
}

bool Overlap(const PieceFeature& a, const PieceFeature& b) {
  for (int k = 0; k < 3; ++k) {
    if (std::min(a.max[k], b.max[k]) - std::max(a.min[k], b.min[k]) <= 1e-9) return false;
  }
  return true;
}

Eigen::Vector3d Vector(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw InputError(where + " must be an array of three numbers (mm)");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) {
    if (!j[static_cast<size_t>(k)].is_number()) throw InputError(where + " must be an array of three numbers (mm)");
    v[k] = j[static_cast<size_t>(k)].get<double>();
    if (!std::isfinite(v[k])) throw InputError(where + " is not finite");
  }
  return v;
}

}  // namespace

std::string_view FeatureKindName(FeatureKind kind) {
  for (const KindName& k : kKinds) {
    if (k.kind == kind) return k.name;
  }
  return "?";
}

bool IsCut(FeatureKind kind) { return kind == FeatureKind::kSlot || kind == FeatureKind::kSideSlot || kind == FeatureKind::kHole; }

std::vector<std::string> MachinedPieceDescription::Problems() const {
  std::vector<std::string> out;
  std::set<std::string> names;
  for (const PieceFeature& f : features) {
    const std::string what = fmt::format("{} {}", FeatureKindName(f.kind), f.name);
    if (!names.insert(f.name).second) out.push_back(fmt::format("{}: the name is used twice", what));
    for (int k = 0; k < 3; ++k) {
      if (!(f.max[k] > f.min[k])) out.push_back(fmt::format("{}: max {} {} is not above min {}", what, "xyz"[k], f.max[k], f.min[k]));
      if (f.min[k] < -1e-9 || f.max[k] > envelope[k] + 1e-9) {
        out.push_back(fmt::format("{} leaves the envelope: {} from {} to {} mm, the block spans 0 to {}", what, "xyz"[k], f.min[k],
                                  f.max[k], envelope[k]));
      }
    }
    for (const ProbePoint& p : f.points) {
      if ((p.position.array() < -1e-9).any() || (p.position.array() > envelope.array() + 1e-9).any()) {
        out.push_back(fmt::format("{}: probe point ({}, {}, {}) lies outside the envelope", what, p.position.x(), p.position.y(),
                                  p.position.z()));
      }
    }
  }
  for (size_t i = 0; i < features.size(); ++i) {
    for (size_t j = i + 1; j < features.size(); ++j) {
      const PieceFeature& a = features[i];
      const PieceFeature& b = features[j];
      if (!Overlap(a, b)) continue;
      const bool cut_a = IsCut(a.kind), cut_b = IsCut(b.kind);
      if (cut_a && cut_b && a.kind == FeatureKind::kSlot && b.kind == FeatureKind::kSlot) continue;  // crossing slots
      if (cut_a != cut_b) {
        const PieceFeature& cut = cut_a ? a : b;
        const PieceFeature& solid = cut_a ? b : a;
        if (cut.kind == FeatureKind::kHole && cut.host == solid.name) continue;  // drilled into its host
      }
      out.push_back(fmt::format("{} {} and {} {} collide: their boxes overlap", FeatureKindName(a.kind), a.name,
                                FeatureKindName(b.kind), b.name));
    }
  }
  for (const PieceFeature& f : features) {
    if (f.kind == FeatureKind::kHole && !f.host.empty() && names.count(f.host) == 0) {
      out.push_back(fmt::format("hole {}: its host {} is not a feature of the piece", f.name, f.host));
    }
  }
  return out;
}

MachinedPieceDescription PublishedMachinedPiece() {
  MachinedPieceDescription piece;
  std::vector<PieceFeature>& f = piece.features;
  constexpr double kTop = 180, kBlock = 100;
  // Crenellations: teeth 10 mm wide at 20 mm pitch on a 10 mm band along each edge, standing from the block's top
  // (z 100) to z 180. Their tops carry X1 (south), X2 (north) and Y3 (west).
  for (int k = 0; k < 15; ++k) {
    const double x = 20.0 * k;
    PieceFeature s = Box(fmt::format("C-S{:02d}", k + 1), FeatureKind::kCrenellation, {x, 0, kBlock}, {x + 10, 10, kTop});
    s.points = {{{x + 5, 5, kTop}, "X1"}};
    f.push_back(s);
    PieceFeature n = Box(fmt::format("C-N{:02d}", k + 1), FeatureKind::kCrenellation, {x, 260, kBlock}, {x + 10, 270, kTop});
    n.points = {{{x + 5, 265, kTop}, "X2"}};
    f.push_back(n);
  }
  for (int k = 1; k <= 12; ++k) {
    const double y = 20.0 * k;
    PieceFeature w = Box(fmt::format("C-W{:02d}", k), FeatureKind::kCrenellation, {0, y, kBlock}, {10, y + 10, kTop});
    w.points = {{{5, y + 5, kTop}, "Y3"}};
    f.push_back(w);
    PieceFeature e = Box(fmt::format("C-E{:02d}", k), FeatureKind::kCrenellation, {290, y, kBlock}, {300, y + 10, kTop});
    e.points = {{{295, y + 5, kTop}, ""}};
    f.push_back(e);
  }
  // Four main slots 20 mm wide, 20 deep in the block's top; the two along Y carry Y1 and Y2 ([Lorente 2021]: Y1, Y2 in
  // one XY plane below Y3, apart in X).
  PieceFeature sx1 = Box("SX1", FeatureKind::kSlot, {15, 15, 80}, {285, 35, kBlock});
  sx1.points = Line({20, 25, 80}, {10, 0, 0}, 26, "");
  PieceFeature sx2 = Box("SX2", FeatureKind::kSlot, {15, 235, 80}, {285, 255, kBlock});
  sx2.points = Line({20, 245, 80}, {10, 0, 0}, 26, "");
  PieceFeature sy1 = Box("SY1", FeatureKind::kSlot, {15, 15, 80}, {35, 255, kBlock});
  sy1.points = Line({25, 25, 80}, {0, 20, 0}, 12, "Y1");
  PieceFeature sy2 = Box("SY2", FeatureKind::kSlot, {265, 15, 80}, {285, 255, kBlock});
  sy2.points = Line({275, 25, 80}, {0, 20, 0}, 12, "Y2");
  f.insert(f.end(), {sx1, sx2, sy1, sy2});
  // Three side slots on each of the faces y = 0 and x = 0, 6 mm high and 5 deep; the lowest on y = 0 carries X3
  // ([Lorente 2021]: X3 in X1's XZ plane, apart in Z).
  for (int i = 0; i < 3; ++i) {
    const double zy = 25.0 + 30.0 * i, zx = 35.0 + 30.0 * i;
    PieceFeature a = Box(fmt::format("LY{}", i + 1), FeatureKind::kSideSlot, {0, 0, zy - 3}, {300, 5, zy + 3});
    a.points = Line({5, 5, zy}, {10, 0, 0}, 30, i == 0 ? "X3" : "");
    PieceFeature b = Box(fmt::format("LX{}", i + 1), FeatureKind::kSideSlot, {0, 0, zx - 3}, {5, 270, zx + 3});
    b.points = Line({5, 15, zx}, {0, 10, 0}, 25, "");
    f.insert(f.end(), {a, b});
  }
  // Conical holes drilled into the side faces along Z for Z1, Z2 (face y = 0, apart in X) and Z3 (face y = 270):
  // into the block below z 100, into a crenellation tooth above.
  struct ZSeries {
    const char* name;
    double x;
    bool north;
    int tooth;
  };
  for (const ZSeries& s : {ZSeries{"Z1", 65, false, 4}, ZSeries{"Z2", 245, false, 13}, ZSeries{"Z3", 65, true, 4}}) {
    for (double z : {10.0, 40.0, 70.0, 110.0, 140.0, 170.0}) {
      const double y0 = s.north ? 265 : 0;
      PieceFeature h = Box(fmt::format("{}-{:.0f}", s.name, z), FeatureKind::kHole, {s.x - 2.5, y0, z - 2.5}, {s.x + 2.5, y0 + 5, z + 2.5});
      if (z > kBlock) h.host = fmt::format("C-{}{:02d}", s.north ? 'N' : 'S', s.tooth);
      h.points = {{{s.x, s.north ? 270.0 : 0.0, z}, s.name}};
      f.push_back(h);
    }
  }
  // The pyramid: four levels 20 mm high centred on the block, each stepping in by 20 mm; conical holes on the
  // exposed ring of each level (pitch 10 mm) and on the top level's rim (pitch 20) and centre: 167 points.
  const double cx = 150, cy = 135;
  const Eigen::Vector2d sizes[4] = {{200, 180}, {160, 140}, {120, 100}, {80, 60}};
  for (int level = 0; level < 4; ++level) {
    const double hx = sizes[level].x() / 2, hy = sizes[level].y() / 2;
    const double z0 = kBlock + 20.0 * level, z1 = z0 + 20;
    PieceFeature p = Box(fmt::format("P{}", level + 1), FeatureKind::kPyramid, {cx - hx, cy - hy, z0}, {cx + hx, cy + hy, z1});
    if (level < 3) {
      p.points = Ring(cx - hx + 10, cy - hy + 10, cx + hx - 10, cy + hy - 10, z1, 10);
    } else {
      p.points = Ring(cx - hx + 10, cy - hy + 10, cx + hx - 10, cy + hy - 10, z1, 20);
      p.points.push_back({{cx, cy, z1}, ""});
    }
    f.push_back(p);
  }
  return piece;
}

MachinedPieceDescription ParseMachinedPiece(std::string_view json_text, const std::string& name) {
  const json j = ParseJsonText(json_text, name, "see fvm testpiece design --help for the format");
  if (!j.is_object()) throw InputError(name + ": the description must be a JSON object with \"envelope_mm\" and \"features\"");
  MachinedPieceDescription piece;
  piece.features.clear();
  if (!j.contains("envelope_mm")) throw InputError(name + ": no \"envelope_mm\": give the block's size [x, y, z] in mm");
  piece.envelope = Vector(j["envelope_mm"], name + ": envelope_mm");
  if ((piece.envelope.array() <= 0).any()) throw InputError(name + ": envelope_mm must be positive");
  if (j.contains("origin_mm")) piece.origin = Vector(j["origin_mm"], name + ": origin_mm");
  if (!j.contains("features") || !j["features"].is_array()) throw InputError(name + ": \"features\" must be an array");
  for (size_t i = 0; i < j["features"].size(); ++i) {
    const json& jf = j["features"][i];
    const std::string where = fmt::format("{}: feature {}", name, i + 1);
    if (!jf.is_object() || !jf.contains("name") || !jf["name"].is_string()) throw InputError(where + ": needs a \"name\" (text)");
    PieceFeature f;
    f.name = jf["name"].get<std::string>();
    const std::string fw = fmt::format("{}: feature {}", name, f.name);
    try {
      const std::string kind = jf.value("kind", std::string());
      bool known = false;
      for (const KindName& k : kKinds) {
        if (kind == k.name) {
          f.kind = k.kind;
          known = true;
        }
      }
      if (!known) throw InputError(fw + ": \"kind\" must be slot, side_slot, hole, pyramid or crenellation");
      if (!jf.contains("min_mm") || !jf.contains("max_mm")) throw InputError(fw + ": needs \"min_mm\" and \"max_mm\"");
      f.min = Vector(jf["min_mm"], fw + ": min_mm");
      f.max = Vector(jf["max_mm"], fw + ": max_mm");
      if (jf.contains("host")) {
        if (!jf["host"].is_string() || f.kind != FeatureKind::kHole) throw InputError(fw + ": \"host\" (text) belongs to holes only");
        f.host = jf["host"].get<std::string>();
      }
      if (jf.contains("points")) {
        if (!jf["points"].is_array()) throw InputError(fw + ": \"points\" must be an array of {\"x\", \"y\", \"z\"}");
        for (const json& jp : jf["points"]) {
          if (!jp.is_object() || !jp.contains("x") || !jp.contains("y") || !jp.contains("z") || !jp["x"].is_number() ||
              !jp["y"].is_number() || !jp["z"].is_number()) {
            throw InputError(fw + ": each point needs numbers \"x\", \"y\", \"z\" (mm)");
          }
          ProbePoint p{{jp["x"].get<double>(), jp["y"].get<double>(), jp["z"].get<double>()}, jp.value("series", std::string())};
          if (!p.position.allFinite()) throw InputError(fw + ": a point is not finite");
          f.points.push_back(p);
        }
      }
    } catch (const json::exception& e) {  // a value of the wrong type ("kind": 3, "series": 1)
      throw InputError(fmt::format("{}: {}; see fvm testpiece design --help for the format", fw, e.what()));
    }
    piece.features.push_back(f);
  }
  const std::vector<std::string> problems = piece.Problems();
  if (!problems.empty()) {
    std::string all;
    for (const std::string& p : problems) all += "\n  " + p;
    throw InputError(fmt::format("{}: the piece cannot be made ({} problem{}):{}", name, problems.size(), problems.size() == 1 ? "" : "s", all));
  }
  return piece;
}

MachinedPieceDescription ReadMachinedPiece(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the piece description");
  std::stringstream text;
  text << in.rdbuf();
  return ParseMachinedPiece(text.str(), path);
}

std::string MachinedPieceJson(const MachinedPieceDescription& piece) {
  const auto vec = [](const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); };
  json j{{"envelope_mm", vec(piece.envelope)}, {"origin_mm", vec(piece.origin)}, {"features", json::array()}};
  for (const PieceFeature& f : piece.features) {
    json jf{{"name", f.name}, {"kind", FeatureKindName(f.kind)}, {"min_mm", vec(f.min)}, {"max_mm", vec(f.max)}};
    if (!f.host.empty()) jf["host"] = f.host;
    jf["points"] = json::array();
    for (const ProbePoint& p : f.points) {
      json jp{{"x", p.position.x()}, {"y", p.position.y()}, {"z", p.position.z()}};
      if (!p.series.empty()) jp["series"] = p.series;
      jf["points"].push_back(jp);
    }
    j["features"].push_back(jf);
  }
  return j.dump(1) + "\n";
}

std::vector<PiecePoint> NominalPoints(const MachinedPieceDescription& piece) {
  std::vector<PiecePoint> out;
  for (const PieceFeature& f : piece.features) {
    for (const ProbePoint& p : f.points) {
      out.push_back({fmt::format("T{:04d}", out.size() + 1), piece.origin + p.position, p.series.empty() ? f.name : p.series, f.name, f.kind});
    }
  }
  return out;
}

void WriteNominalPoints(const std::string& path, const std::vector<PiecePoint>& points) {
  std::string out = "id,x,y,z,series\n";
  for (const PiecePoint& p : points) {
    out += fmt::format("{},{},{},{},{}\n", p.id, FormatShortest(p.machine.x()), FormatShortest(p.machine.y()),
                       FormatShortest(p.machine.z()), p.series);
  }
  WriteFileAtomically(path, out);
}

std::string CmmProgram(const std::vector<PiecePoint>& points) {
  std::string out = fmt::format("# fvm test piece: {} points; coordinates are the machine coordinates of the cut (mm)\n", points.size());
  out += "# POINT id X Y Z SERIES series FEATURE feature: probe the cone (or face) at that point; report id,xm,ym,zm\n";
  for (const PiecePoint& p : points) {
    out += fmt::format("POINT {} X{:.3f} Y{:.3f} Z{:.3f} SERIES {} FEATURE {}\n", p.id, p.machine.x(), p.machine.y(), p.machine.z(),
                       p.series, p.feature);
  }
  return out;
}

std::string CuttingProgram(const MachinedPieceDescription& piece, double tool_diameter_mm) {
  const double safe = piece.origin.z() + piece.envelope.z() + 10.0;
  std::string out = "%\n";
  out += fmt::format("(FVM TEST PIECE {:.0f} X {:.0f} X {:.0f} MM, TOOL D{:.1f})\nG90 G21 G17 G94\n", piece.envelope.x(), piece.envelope.y(),
                     piece.envelope.z(), tool_diameter_mm);
  out += fmt::format("G0 Z{:.3f}\n", safe);
  const double r = tool_diameter_mm / 2;
  for (const PieceFeature& f : piece.features) {
    const Eigen::Vector3d lo = piece.origin + f.min, hi = piece.origin + f.max;
    out += fmt::format("({} {})\n", FeatureKindName(f.kind), f.name);
    if (f.kind == FeatureKind::kHole) {
      const Eigen::Vector3d c = 0.5 * (lo + hi);
      out += fmt::format("G0 X{:.3f} Y{:.3f}\nG81 X{:.3f} Y{:.3f} Z{:.3f} R{:.3f} F100\nG80\nG0 Z{:.3f}\n", c.x(), c.y(), c.x(), c.y(),
                         lo.z(), hi.z() + 2, safe);
      continue;
    }
    if (IsCut(f.kind)) {  // pocket: passes along the longer side at the bottom, stepping over by the radius
      const bool along_x = (hi.x() - lo.x()) >= (hi.y() - lo.y());
      const double a0 = (along_x ? lo.y() : lo.x()) + r, a1 = (along_x ? hi.y() : hi.x()) - r;
      out += fmt::format("G0 X{:.3f} Y{:.3f}\nG1 Z{:.3f} F300\n", lo.x() + r, lo.y() + r, lo.z());
      for (double a = a0; a <= std::max(a0, a1) + 1e-9; a += r) {
        if (along_x) {
          out += fmt::format("G1 X{:.3f} Y{:.3f} F800\nG1 X{:.3f}\n", lo.x() + r, a, hi.x() - r);
        } else {
          out += fmt::format("G1 X{:.3f} Y{:.3f} F800\nG1 Y{:.3f}\n", a, lo.y() + r, hi.y() - r);
        }
      }
      out += fmt::format("G0 Z{:.3f}\n", safe);
    } else {  // a solid stands where the tool contours around it at its height range
      out += fmt::format("G0 X{:.3f} Y{:.3f}\nG1 Z{:.3f} F300\nG1 X{:.3f} F800\nG1 Y{:.3f}\nG1 X{:.3f}\nG1 Y{:.3f}\nG0 Z{:.3f}\n",
                         lo.x() - r, lo.y() - r, lo.z(), hi.x() + r, hi.y() + r, lo.x() - r, lo.y() - r, safe);
    }
  }
  out += "M30\n%\n";
  return out;
}

}  // namespace fvm::artefacts
