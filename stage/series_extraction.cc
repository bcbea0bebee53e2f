#include "stage/series_extraction.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace fvm::stage {
namespace {

using Series = std::vector<SeriesPoint>;
constexpr double kSameCoordinateMm = 1e-3;

const Series* Find(const std::map<std::string, Series>& series, const std::string& name) {
  const auto it = series.find(name);
  return it == series.end() || it->second.empty() ? nullptr : &it->second;
}

// Points of a and b at the same coordinate along `axis`, in increasing order of it.
std::vector<std::pair<SeriesPoint, SeriesPoint>> Pairs(const Series& a, const Series& b, int axis) {
  std::vector<std::pair<SeriesPoint, SeriesPoint>> out;
  for (const SeriesPoint& p : a) {
    for (const SeriesPoint& o : b) {
      if (std::abs(p.command[axis] - o.command[axis]) < kSameCoordinateMm) {
        out.emplace_back(p, o);
        break;
      }
    }
  }
  std::sort(out.begin(), out.end(), [axis](const auto& l, const auto& r) { return l.first.command[axis] < r.first.command[axis]; });
  return out;
}

// The mean of two parallel series point by point (Y1 and Y2 give Ya): command and deviation averaged.
Series Mean(const Series& a, const Series& b, int axis) {
  Series out;
  for (const auto& [p, o] : Pairs(a, b, axis)) out.push_back({0.5 * (p.command + o.command), 0.5 * (p.deviation + o.deviation)});
  return out;
}

// The zero-reference step: subtract the value at the axis' origin, where the error itself is zero and what
// remains is the other errors' constant share. [Lorente 2021] takes the series point at or near the origin (0, 5 or 15
// mm); we extrapolate the two points nearest it to the origin itself, because an angle referenced 5 mm off leaves a
// constant that a formula multiplies by the coordinate (x ECX(x): 8.5 urad x 300 mm = 2.5 um).
ExtractedError ZeroReferenced(std::string name, std::vector<double> s, std::vector<double> v, double origin) {
  ExtractedError e{std::move(name), std::move(s), std::move(v)};
  if (e.value.empty()) return e;
  std::vector<size_t> order(e.value.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return e.coordinate[a] < e.coordinate[b]; });
  double reference = e.value[order[0]];
  if (order.size() > 1) {
    const size_t a = order[0], b = order[1];
    reference += (origin - e.coordinate[a]) * (e.value[b] - e.value[a]) / (e.coordinate[b] - e.coordinate[a]);
  }
  for (double& x : e.value) x -= reference;
  return e;
}

// An extracted function between its samples (linear; held constant beyond them).
double At(const ExtractedError& e, double s) {
  if (e.coordinate.empty()) return 0.0;
  if (s <= e.coordinate.front()) return e.value.front();
  for (size_t i = 1; i < e.coordinate.size(); ++i) {
    if (s <= e.coordinate[i]) {
      const double f = (s - e.coordinate[i - 1]) / (e.coordinate[i] - e.coordinate[i - 1]);
      return e.value[i - 1] + f * (e.value[i] - e.value[i - 1]);
    }
  }
  return e.value.back();
}

// One formula evaluated along a series: value(point) for each point, then zero-referenced.
ExtractedError Along(const std::string& name, const Series& series, int axis, double origin,
                     const std::function<double(const SeriesPoint&)>& value) {
  std::vector<double> s, v;
  for (const SeriesPoint& p : series) {
    s.push_back(p.command[axis]);
    v.push_back(value(p));
  }
  return ZeroReferenced(name, s, v, origin);
}

// A difference formula between two parallel series: (component of a - component of b) / lever * sign.
// `correction` (of the point's coordinate) is subtracted from the difference first: what the two series' other
// positions add along the axis.
ExtractedError Difference(const std::string& name, const Series& a, const Series& b, int axis, double origin, int component,
                          double factor, const std::function<double(double)>& correction = nullptr) {
  std::vector<double> s, v;
  for (const auto& [p, o] : Pairs(a, b, axis)) {
    s.push_back(p.command[axis]);
    const double c = correction ? correction(p.command[axis]) : 0.0;
    v.push_back(factor * (p.deviation[component] - o.deviation[component] - c));
  }
  return ZeroReferenced(name, s, v, origin);
}

}  // namespace

std::vector<ExtractedError> ExtractGeometricErrors(const std::map<std::string, std::vector<SeriesPoint>>& series, double tool_length,
                                                   const Eigen::Vector3d& origin) {
  const double L = tool_length;
  std::vector<ExtractedError> out;
  ExtractedError ecx, ebx, eax;  // needed by the Y and Z formulas
  const Series* x1 = Find(series, "X1");
  const Series* x2 = Find(series, "X2");
  const Series* x3 = Find(series, "X3");
  if (x1 != nullptr && x2 != nullptr) {
    const double dy = x1->front().command.y() - x2->front().command.y();
    ecx = Difference("ECX", *x1, *x2, 0, origin.x(), 0, 1.0 / dy);
    out.push_back(ecx);
  }
  if (x1 != nullptr && x3 != nullptr) {
    const double dz = x1->front().command.z() - x3->front().command.z();
    ebx = Difference("EBX", *x1, *x3, 0, origin.x(), 0, -1.0 / dz);
    eax = Difference("EAX", *x1, *x3, 0, origin.x(), 1, 1.0 / dz);
    out.push_back(ebx);
    out.push_back(eax);
  }
  if (x1 != nullptr && !ecx.value.empty() && !ebx.value.empty()) {
    const double y1 = x1->front().command.y(), z1 = x1->front().command.z();
    out.push_back(Along("EXX", *x1, 0, origin.x(), [&](const SeriesPoint& p) {
      return -p.deviation.x() - (z1 + L) * At(ebx, p.command.x()) + y1 * At(ecx, p.command.x());
    }));
    out.push_back(Along("EYX", *x1, 0, origin.x(), [&](const SeriesPoint& p) {
      return -p.deviation.y() - p.command.x() * At(ecx, p.command.x()) + (z1 + L) * At(eax, p.command.x());
    }));
    out.push_back(Along("EZX", *x1, 0, origin.x(), [&](const SeriesPoint& p) {
      return -p.deviation.z() - y1 * At(eax, p.command.x()) + p.command.x() * At(ebx, p.command.x());
    }));
  }
  const Series* y1 = Find(series, "Y1");
  const Series* y2 = Find(series, "Y2");
  const Series* y3 = Find(series, "Y3");
  if (y1 != nullptr && y2 != nullptr && y3 != nullptr) {
    const Series ya = Mean(*y1, *y2, 1);
    if (!ya.empty()) {
      const double za = ya.front().command.z(), xa1 = y1->front().command.x(), xa2 = y2->front().command.x();
      const double dz = y3->front().command.z() - za;
      // Y3 and Ya sit at different x, where the X axis' yaw tilts them differently along y: y (ECX(x3) - ECX(xa)).
      const double x3 = y3->front().command.x();
      const double ecx_3a = At(ecx, x3) - 0.5 * (At(ecx, xa1) + At(ecx, xa2));
      const ExtractedError eby = Difference("EBY", *y3, ya, 1, origin.y(), 0, 1.0 / dz, [&](double y) { return y * ecx_3a; });
      const ExtractedError eay = Difference("EAY", *y3, ya, 1, origin.y(), 1, -1.0 / dz);
      out.push_back(eby);
      out.push_back(eay);
      out.push_back(Along("EYY", ya, 1, origin.y(), [&](const SeriesPoint& p) { return p.deviation.y() + (za + L) * At(eay, p.command.y()); }));
      // Y1 and Y2 sit at two x: the X axis' roll and yaw there tilt the series, each by its own amount.
      const double ecx_a = 0.5 * (At(ecx, xa1) + At(ecx, xa2)), eax_a = 0.5 * (At(eax, xa1) + At(eax, xa2));
      out.push_back(Along("EXY-y*EC0Y", ya, 1, origin.y(), [&](const SeriesPoint& p) {
        return p.deviation.x() - (za + L) * At(eby, p.command.y()) - p.command.y() * ecx_a;
      }));
      out.push_back(Along("EZY", ya, 1, origin.y(), [&](const SeriesPoint& p) { return p.deviation.z() + p.command.y() * eax_a; }));
    }
  }
  if (const Series* z1 = Find(series, "Z1")) {
    const double xz = z1->front().command.x();
    out.push_back(Along("EZZ", *z1, 2, origin.z(), [&](const SeriesPoint& p) { return p.deviation.z(); }));
    out.push_back(Along("EXZ+L*EBZ-z*EB0Z", *z1, 2, origin.z(), [&](const SeriesPoint& p) {
      return p.deviation.x() + (p.command.z() + L) * At(ebx, xz);
    }));
    out.push_back(Along("EYZ-L*EAZ-z*EA0Z", *z1, 2, origin.z(), [&](const SeriesPoint& p) {
      return p.deviation.y() - (p.command.z() + L) * At(eax, xz);
    }));
  }
  return out;
}

}  // namespace fvm::stage
