// What `fvm stitch --report DIR` shows (report/stitch_report.h), from the stitched layout itself: the numbers are
// those of --json and the positions CSV, printed to the digits those files carry at most.

#include <fmt/core.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "workflows/stitch_summary.h"

namespace fvm::workflows {
namespace {

using Status = report::StitchReportData::PairStatus;

std::string Number(double v, int decimals) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, decimals) : "-"; }

std::vector<Status> PairStatuses(const imaging::RegistrationResult& r) {
  std::vector<Status> status;
  for (const imaging::PairRegistration& pair : r.pairs) status.push_back(pair.accepted ? Status::kAccepted : Status::kUnresolved);
  for (const imaging::OverruledPair& o : r.loops.overruled) {
    if (status[static_cast<size_t>(o.pair)] == Status::kAccepted) status[static_cast<size_t>(o.pair)] = Status::kOverruled;
  }
  return status;
}

const char* StatusName(Status s) {
  return s == Status::kAccepted ? "accepted" : s == Status::kOverruled ? "overruled, replaced" : "unresolved";
}

report::StitchReportData::Table TilesTable(const StitchedLayout& s) {
  report::StitchReportData::Table t{"Tile positions",
                                    "Each tile's top-left corner (px, x right, y down) against the first tile, with "
                                    "its standard uncertainty; as the positions CSV (-o) writes them.",
                                    {"tile", "file", "x (px)", "y (px)", "u x (px)", "u y (px)", "registered"},
                                    {}};
  const std::vector<Eigen::Vector2d>& p = s.PositionsPx();
  const std::vector<Eigen::Vector2d>& u = s.SigmaPx();
  for (size_t i = 0; i < s.files.size(); ++i) {
    t.rows.push_back({std::to_string(i + 1), s.files[i], Number(p[i].x(), 3), Number(p[i].y(), 3), Number(u[i].x(), 4),
                      Number(u[i].y(), 4), s.Registered().registration.positions.registered[i] ? "yes" : "stage position"});
  }
  return t;
}

report::StitchReportData::Table PairsTable(const StitchedLayout& s, const std::vector<Status>& status) {
  report::StitchReportData::Table t{"Neighbour pairs",
                                    "Each pair's offset from its nominal one (px, as --json's dx_px, dy_px), its "
                                    "standard uncertainty, its correlation once aligned (quality) and the overlap "
                                    "correlation of the raw tiles at the positions found.",
                                    {"a", "b", "status", "dx (px)", "dy (px)", "u x (px)", "u y (px)", "quality",
                                     "overlap NCC", "note"},
                                    {}};
  const imaging::RegistrationResult& r = s.Registered().registration;
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const imaging::PairRegistration& pair = r.pairs[k];
    const Eigen::Vector2d d = pair.offset_px - pair.nominal_px;
    std::string ux = "-", uy = "-";
    if (pair.accepted && std::abs(pair.information.determinant()) > 0.0) {
      const Eigen::Matrix2d covariance = pair.information.inverse();
      ux = Number(std::sqrt(covariance(0, 0)), 4), uy = Number(std::sqrt(covariance(1, 1)), 4);
    }
    std::string note = pair.accepted ? (pair.ambiguous ? "ambiguous: the stage chose" : "") : pair.rejection;
    t.rows.push_back({s.files[static_cast<size_t>(pair.a)], s.files[static_cast<size_t>(pair.b)], StatusName(status[k]),
                      pair.accepted ? Number(d.x(), 3) : "-", pair.accepted ? Number(d.y(), 3) : "-", ux, uy,
                      Number(pair.quality, 3), Number(s.Registered().overlap_ncc[k].correlation.ncc, 3), note});
  }
  return t;
}

// Every square of four tiles whose four pairs were accepted: right then down against down then right should meet.
report::StitchReportData::Table LoopsTable(const StitchedLayout& s) {
  const imaging::RegistrationResult& r = s.Registered().registration;
  report::StitchReportData::Table t{
      "Loop misclosures",
      fmt::format("Around each square of four tiles, the offsets right then down against down then right (px): what "
                  "the pairs' own errors leave. The loops' Birge ratio is {:.3f} on {:g} degrees of freedom; the "
                  "positions' uncertainties are scaled by {:.3f}.",
                  r.loops.birge_ratio, r.loops.dof, r.loops.uncertainty_scale),
      {"square (top-left tile)", "x (px)", "y (px)", "|m| (px)", "|m| / u"},
      {}};
  std::map<std::pair<int, int>, int> tile_at;
  for (size_t i = 0; i < s.rigid.grid.size(); ++i) tile_at[{s.rigid.grid[i].row, s.rigid.grid[i].col}] = static_cast<int>(i);
  std::map<std::pair<int, int>, size_t> pair_of;
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    if (r.pairs[k].accepted) pair_of[{r.pairs[k].a, r.pairs[k].b}] = k;
  }
  for (const auto& [at, tl] : tile_at) {
    const auto tr = tile_at.find({at.first, at.second + 1}), bl = tile_at.find({at.first + 1, at.second});
    const auto br = tile_at.find({at.first + 1, at.second + 1});
    if (tr == tile_at.end() || bl == tile_at.end() || br == tile_at.end()) continue;
    const std::array<std::pair<int, int>, 4> sides = {{{tl, tr->second}, {tr->second, br->second}, {tl, bl->second}, {bl->second, br->second}}};
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
    bool closed = true;
    for (size_t k = 0; k < sides.size() && closed; ++k) {
      const auto found = pair_of.find(sides[k]);
      if (found == pair_of.end() || std::abs(r.pairs[found->second].information.determinant()) <= 0.0) {
        closed = false;
        break;
      }
      const imaging::PairRegistration& pair = r.pairs[found->second];
      m += (k < 2 ? 1.0 : -1.0) * pair.offset_px;
      covariance += pair.information.inverse();
    }
    if (!closed) continue;
    const double sigma = std::sqrt(m.dot(covariance.inverse() * m));
    t.rows.push_back({s.files[static_cast<size_t>(tl)], Number(m.x(), 3), Number(m.y(), 3), Number(m.norm(), 3), Number(sigma, 2)});
  }
  return t;
}

report::StitchReportData::Table OverruledTable(const StitchedLayout& s) {
  const imaging::RegistrationResult& r = s.Registered().registration;
  report::StitchReportData::Table t{"Pairs the loops overruled",
                                    "What the pair registered, what the other pairs and the stage put there, how many "
                                    "standard deviations apart, and what was done.",
                                    {"a", "b", "registered (px)", "predicted (px)", "misclosure (sigma)", "done"},
                                    {}};
  for (const imaging::OverruledPair& o : r.loops.overruled) {
    const imaging::PairRegistration& pair = r.pairs[static_cast<size_t>(o.pair)];
    t.rows.push_back({s.files[static_cast<size_t>(pair.a)], s.files[static_cast<size_t>(pair.b)],
                      fmt::format("{:.3f}, {:.3f}", o.registered_px.x(), o.registered_px.y()),
                      fmt::format("{:.3f}, {:.3f}", o.predicted_px.x(), o.predicted_px.y()), Number(o.misclosure_sigma, 1),
                      o.replaced ? "searched again there: replaced" : "dropped"});
  }
  return t;
}

report::StitchReportData::Table FieldTable(const StitchDistortionResult& field) {
  const imaging::FieldDistortion& d = field.fit.field;
  report::StitchReportData::Table t{"Field distortion terms",
                                    fmt::format("The field's terms (px, as --json's distortion.terms) with their "
                                                "standard uncertainties; {}.",
                                                imaging::kFixedLinearPart),
                                    {"term", "value (px)", "u (px)", ""},
                                    {}};
  const std::vector<std::string>& names = imaging::FieldDistortionTermNames(d.order);
  const std::set<int> held(field.fit.held_terms.begin(), field.fit.held_terms.end());
  for (size_t k = 0; k < names.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const bool has_u = d.covariance.size() != 0;
    t.rows.push_back({names[k], Number(d.coefficients(i), 4), has_u ? Number(std::sqrt(d.covariance(i, i)), 4) : "-",
                      held.count(static_cast<int>(k)) ? "held at 0" : field.identified ? "identified" : "from the file"});
  }
  return t;
}

void AddField(const StitchedLayout& s, report::StitchReportData& data) {
  const StitchDistortionResult& field = *s.field;
  const imaging::FieldDistortion& d = field.fit.field;
  Eigen::Vector2d where;
  const double largest = d.LargestDisplacementPx(&where);
  const std::string um = s.options.pixel_mm > 0.0 ? fmt::format(" ({:.3f} um)", largest * s.options.pixel_mm * 1e3) : "";
  data.summary.emplace_back("field distortion", fmt::format("order {}, {}", d.order, field.identified ? "identified from the overlaps" : "from the file"));
  data.summary.emplace_back("largest displacement", fmt::format("{:.3f} px{} at pixel {:.0f}, {:.0f}", largest, um, where.x(), where.y()));
  data.summary.emplace_back("mean overlap NCC, raw tiles (rigid) / undistorted",
                            fmt::format("{} / {}", Number(field.mean_overlap_ncc_before, 3), Number(field.mean_overlap_ncc_after, 3)));
  data.summary.emplace_back("field uncertainty", fmt::format("{:.4f} px rms over the tile", d.DisplacementSigmaPx()));
  data.field_caption = fmt::format("largest {:.2f} px{} at pixel {:.0f}, {:.0f}", largest, um, where.x(), where.y());
  constexpr int kSteps = 10;
  for (int j = 0; j <= kSteps; ++j) {
    for (int i = 0; i <= kSteps; ++i) {
      const Eigen::Vector2d u((d.width_px - 1) * i / double(kSteps), (d.height_px - 1) * j / double(kSteps));
      const Eigen::Vector2d v = d.Displacement(u);
      data.field.push_back({u.x(), u.y(), v.x(), v.y()});
    }
  }
  data.tables.push_back(FieldTable(field));
}

}  // namespace

report::StitchReportData StitchReport(const StitchedLayout& s) {
  const StitchResult& placed = s.Registered();
  const imaging::RegistrationResult& r = placed.registration;
  report::StitchReportData data;
  data.title = fmt::format("fvm stitch: {} tiles of {} x {} px", s.files.size(), s.width_px, s.height_px);
  data.width_px = s.width_px, data.height_px = s.height_px;
  const std::vector<Status> status = PairStatuses(r);
  const int overruled = static_cast<int>(std::count(status.begin(), status.end(), Status::kOverruled));
  data.summary = {
      {"tiles", fmt::format("{} of {} x {} px; nominal positions from the {}", s.files.size(), s.width_px, s.height_px,
                            placed.from_stage ? "stage" : "grid and overlap")},
      {"pairs", fmt::format("{} neighbour pairs: {} accepted ({} overruled by the loops and replaced), {} unresolved",
                            r.pairs.size(), placed.accepted, overruled, placed.unresolved)},
      {"mean overlap NCC (raw tiles at the rigid positions)",
       placed.ncc_pairs > 0 ? Number(placed.mean_overlap_ncc, 3) : std::string("-")},
      {"loops", fmt::format("Birge ratio {:.3f} on {:g} degrees of freedom", r.loops.birge_ratio, r.loops.dof)}};
  if (placed.mostly_unresolved) data.summary.emplace_back("warning", placed.UnresolvedWarning());
  const std::vector<Eigen::Vector2d>& positions = s.PositionsPx();
  for (size_t i = 0; i < s.files.size(); ++i) data.tiles.push_back({std::to_string(i + 1), positions[i].x(), positions[i].y()});
  for (size_t k = 0; k < r.pairs.size(); ++k) data.pairs.push_back({r.pairs[k].a, r.pairs[k].b, status[k]});
  if (s.field) AddField(s, data);
  data.tables.push_back(TilesTable(s));
  data.tables.push_back(PairsTable(s, status));
  data.tables.push_back(LoopsTable(s));
  if (!r.loops.overruled.empty()) data.tables.push_back(OverruledTable(s));
  return data;
}

}  // namespace fvm::workflows
