#include "artefacts/scan_observations.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "core/dense_decomposition.h"
#include "artefacts/scan_correlated_errors.h"

namespace fvm::artefacts {
namespace {

// Pixel frame (x right, y down) to stage millimetres (x right, y up).
Eigen::Vector3d Millimetres(const Eigen::Vector2d& px, double pixel_mm) { return {px.x() * pixel_mm, -px.y() * pixel_mm, 0.0}; }

constexpr double kUnobserved = std::numeric_limits<double>::infinity();

void AddScan(stage::MeasurementSet& set, const RegisteredScan& scan) {
  set.groups.push_back(scan.name);
  set.anchors.push_back(scan.encoder_mm.front());
}

// The same scan given twice (one layout under two names, or a copy) would count each registration twice and shrink
// every uncertainty by sqrt(2): same encoder readings and same registered offsets, bit for bit, are the same scan.
// Two real scans of one path differ in their registrations' noise.
void RefuseRepeatedScans(const std::vector<RegisteredScan>& scans) {
  const auto same = [](const RegisteredScan& a, const RegisteredScan& b) {
    if (a.encoder_mm != b.encoder_mm || a.registration.pairs.size() != b.registration.pairs.size()) return false;
    for (size_t k = 0; k < a.registration.pairs.size(); ++k) {
      const imaging::PairRegistration &p = a.registration.pairs[k], &q = b.registration.pairs[k];
      if (p.accepted != q.accepted || p.offset_px != q.offset_px) return false;
    }
    return true;
  };
  for (size_t i = 0; i < scans.size(); ++i) {
    for (size_t j = i + 1; j < scans.size(); ++j) {
      if (same(scans[i], scans[j])) {
        throw std::invalid_argument("scans " + scans[i].name + " and " + scans[j].name +
                                    " are the same scan (the same encoder readings and registrations): counted twice, it "
                                    "would shrink every uncertainty; give each scan once");
      }
    }
  }
}

}  // namespace

std::vector<Eigen::Vector2d> NominalOffsetsPx(const std::vector<Eigen::Vector3d>& encoder_mm, double pixel_mm) {
  std::vector<Eigen::Vector2d> nominal;
  for (const Eigen::Vector3d& e : encoder_mm) {
    nominal.push_back(Eigen::Vector2d(e.x() - encoder_mm[0].x(), encoder_mm[0].y() - e.y()) / pixel_mm);
  }
  return nominal;
}

RegisteredScan RegisterScan(std::string name, std::vector<Eigen::Vector3d> encoder_mm,
                            const std::vector<imaging::TileImage>& tiles, double pixel_mm, bool height_maps,
                            const imaging::RegistrationOptions& options,
                            const std::function<void(int done, int total)>& on_pair) {
  RegisteredScan scan{std::move(name), std::move(encoder_mm), {}, {}, {}, {}};
  scan.registration = imaging::RegisterTileChain(tiles, NominalOffsetsPx(scan.encoder_mm, pixel_mm), options, on_pair);
  if (height_maps) {
    for (const imaging::PairRegistration& pair : scan.registration.pairs) {
      scan.height_steps.push_back(pair.accepted ? imaging::OverlapHeightStep(tiles[static_cast<size_t>(pair.a)],
                                                                             tiles[static_cast<size_t>(pair.b)], pair.offset_px)
                                                : imaging::HeightStep{});
    }
  }
  return scan;
}

stage::MeasurementSet ScanDisplacements(const std::vector<RegisteredScan>& scans, double pixel_mm) {
  RefuseRepeatedScans(scans);
  stage::MeasurementSet set;
  for (size_t s = 0; s < scans.size(); ++s) {
    const RegisteredScan& scan = scans[s];
    AddScan(set, scan);
    if (!scan.height_steps.empty() && scan.height_steps.size() != scan.registration.pairs.size()) {
      throw std::invalid_argument("scan " + scan.name + ": one height step per registered pair, or none");
    }
    for (size_t k = 0; k < scan.registration.pairs.size(); ++k) {
      const imaging::PairRegistration& pair = scan.registration.pairs[k];
      if (!pair.accepted) continue;
      stage::Observation o;
      o.from = scan.encoder_mm[static_cast<size_t>(pair.a)];
      o.command = scan.encoder_mm[static_cast<size_t>(pair.b)];
      o.measured = Millimetres(pair.offset_px, pixel_mm);
      o.group = static_cast<int>(s);
      // The offset's covariance in px^2 is the information's inverse; flipping y flips the sign of the xy term.
      const Eigen::Matrix2d px2 = pair.information.inverse();
      o.covariance << px2(0, 0), -px2(0, 1), 0.0, -px2(1, 0), px2(1, 1), 0.0, 0.0, 0.0, kUnobserved;
      o.covariance.topLeftCorner<2, 2>() *= pixel_mm * pixel_mm;
      if (!scan.height_steps.empty() && scan.height_steps[k].pixels > 0) {
        const imaging::HeightStep& step = scan.height_steps[k];
        o.measured.z() = step.mean;
        o.covariance(2, 2) = std::max(step.variance, 1e-12);  // never below 1 nm
      }
      set.observations.push_back(o);
      set.labels.push_back(scan.name + ":" + std::to_string(pair.a + 1) + "-" + std::to_string(pair.b + 1));
    }
  }
  return set;
}

stage::MeasurementSet ScanPositions(const std::vector<RegisteredScan>& scans, double pixel_mm) {
  stage::MeasurementSet set;
  for (size_t s = 0; s < scans.size(); ++s) {
    const RegisteredScan& scan = scans[s];
    AddScan(set, scan);
    const imaging::TilePositions& p = scan.registration.positions;
    for (size_t k = 0; k < scan.encoder_mm.size(); ++k) {
      if (!p.registered[k] || p.anchor[k] != 0) continue;  // only what chains from the first tile
      stage::Observation o;
      o.command = scan.encoder_mm[k];
      o.measured = scan.encoder_mm.front() + Millimetres(p.positions_px[k] - p.positions_px.front(), pixel_mm);
      o.measured.z() = o.command.z();
      o.group = static_cast<int>(s);
      // Equal weights, heights unobserved: a variance far below the scatter, so that the fit's variance factor is
      // the residuals' own (Identify never takes it below 1).
      o.covariance = Eigen::Vector3d(1e-12, 1e-12, kUnobserved).asDiagonal();
      set.observations.push_back(o);
      set.labels.push_back(scan.name + ":" + std::to_string(k + 1));
    }
  }
  return set;
}

bool ContinuesRun(const stage::MeasurementSet& set, size_t i) {
  const stage::Observation& o = set.observations[i];
  return i > 0 && o.from && set.observations[i - 1].group == o.group && *o.from == set.observations[i - 1].command;
}

ScanResidualSplit SplitScanResiduals(const stage::MeasurementSet& set, const std::vector<Eigen::Vector3d>& residuals) {
  ScanResidualSplit out;
  double white = 0.0;
  int differences = 0;
  // Per scan (group): the chained residuals' squares about their run's mean per coordinate, their number, and the
  // box its readings span (which axes it moves).
  struct ScanMisfit {
    Eigen::Vector2d squares = Eigen::Vector2d::Zero();
    int points = 0;
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  };
  std::map<int, ScanMisfit> scans;
  std::vector<Eigen::Vector2d> chained;  // positions of the current run of consecutive pairs
  int chained_group = 0;
  const auto close_run = [&] {
    if (chained.size() < 2) return chained.clear();
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : chained) mean += p;
    mean /= static_cast<double>(chained.size());
    ScanMisfit& scan = scans[chained_group];
    for (const Eigen::Vector2d& p : chained) scan.squares += (p - mean).cwiseAbs2();
    scan.points += static_cast<int>(chained.size());
    chained.clear();
  };
  // Whitened residuals of the current run: their second differences see white noise (variance 6 per coordinate)
  // and hardly a smooth misfit (a cycle of n pairs shrinks by (2 pi / n)^2).
  std::vector<Eigen::Vector2d> run;
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const stage::Observation& o = set.observations[i];
    if (!ContinuesRun(set, i)) {
      close_run();
      chained.push_back(Eigen::Vector2d::Zero());
      chained_group = o.group;
      run.clear();
    }
    ScanMisfit& scan = scans[o.group];
    for (const Eigen::Vector3d& e : {o.from.value_or(o.command), o.command}) {
      scan.lo = scan.lo.cwiseMin(e.head<2>()), scan.hi = scan.hi.cwiseMax(e.head<2>());
    }
    const Eigen::Vector2d r = residuals[i].head<2>();
    chained.push_back(chained.back() + r);
    const Eigen::Matrix2d l = Decompose<Eigen::LLT<Eigen::Matrix2d>>(o.covariance.topLeftCorner<2, 2>(), "a tile displacement's covariance").matrixL();
    const Eigen::Vector2d w = l.triangularView<Eigen::Lower>().solve(r);
    run.push_back(w);
    if (run.size() >= 3) {
      white += (run[run.size() - 1] - 2.0 * run[run.size() - 2] + run[run.size() - 3]).squaredNorm();
      differences += 2;
    }
  }
  close_run();
  out.white_ratio = differences > 0 ? std::sqrt(white / (6.0 * differences)) : 0.0;
  // Each scan's mean square per coordinate is the sum of the misfits of the axes it moves (an axis whose travel
  // along the scan is at least a tenth of the other's: a row's servo scatter in y is no travel). Least squares of
  // minimum norm over the scans (a lone diagonal splits its misfit evenly, the sum stays its own), each axis'
  // share at least 0.
  std::vector<Eigen::Vector2d> moves, mean_squares;
  for (const auto& [group, scan] : scans) {
    if (scan.points == 0) continue;
    const Eigen::Vector2d travel = scan.hi - scan.lo;
    const double longest = travel.maxCoeff();
    if (!(longest > 0.0)) continue;
    moves.emplace_back(travel.x() >= 0.1 * longest ? 1.0 : 0.0, travel.y() >= 0.1 * longest ? 1.0 : 0.0);
    mean_squares.push_back(scan.squares / scan.points);
  }
  if (!moves.empty()) {
    Eigen::MatrixXd a(static_cast<Eigen::Index>(moves.size()), 2), b(static_cast<Eigen::Index>(moves.size()), 2);
    for (size_t k = 0; k < moves.size(); ++k) {
      a.row(static_cast<Eigen::Index>(k)) = moves[k].transpose();
      b.row(static_cast<Eigen::Index>(k)) = mean_squares[k].transpose();
    }
    const Eigen::MatrixXd axes =  // axis x coordinate
        Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(a, "the scans' misfit per axis").solve(b).cwiseMax(0.0);
    out.misfit_at_point_mm = axes.colwise().sum().transpose().cwiseSqrt();
  }
  out.misfit_mm = out.misfit_at_point_mm.norm();
  return out;
}

ScanCalibration IdentifyFromScans(const stage::ParameterLayout& layout, const std::vector<RegisteredScan>& scans,
                                  double pixel_mm, double pixel_u_mm, stage::IdentificationOptions options) {
  stage::MeasurementSet set = ScanDisplacements(scans, pixel_mm);
  options.anchors = set.anchors;
  stage::IdentificationResult result = stage::Identify(layout, set.observations, options);
  // Identify scaled the covariance by the whole residual, and never below the registrations' covariances; scale it
  // by the residuals' white part instead, below 1 too: a pair's covariance carries a floor of 0.005 px against
  // resampling bias, which the textured tiles of a scan beat by a factor of two or three.
  const ScanResidualSplit split = SplitScanResiduals(set, result.residuals);
  const double applied = std::max(result.weighted_rms, 1.0);
  stage::Calibration& cal = result.calibration;
  cal.covariance *= (split.white_ratio * split.white_ratio) / (applied * applied);
  // What the model cannot take stays at every point it corrects (fvm correct's u): the misfit a point inherits.
  cal.unmodelled_mm = Eigen::Vector3d(split.misfit_at_point_mm.x(), split.misfit_at_point_mm.y(), 0.0);
  // What the pairs of a scan share and the white part does not model: the registrations' pull towards whole
  // pixels, and what of the misfit the coefficients took up (scan_correlated_errors.h).
  const ScanCorrelatedErrors correlated = ScanCorrelatedErrorCovariances(cal, set, result.residuals, pixel_mm);
  cal.covariance += correlated.subpixel_bias + correlated.misfit;
  // The field distortion's error, shared by every pair (scans undistorted by a field identified from their overlaps).
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> field_mm;
  Eigen::MatrixXd field_covariance;
  for (const RegisteredScan& scan : scans) {
    if (scan.field_sensitivity.empty()) continue;
    field_covariance = scan.field_covariance_px2;
    for (size_t k = 0; k < scan.registration.pairs.size(); ++k) {
      if (!scan.registration.pairs[k].accepted) continue;
      const Eigen::Matrix<double, 2, Eigen::Dynamic>& px = scan.field_sensitivity[k];
      Eigen::Matrix<double, 3, Eigen::Dynamic> mm = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, px.cols());
      mm.row(0) = px.row(0) * pixel_mm, mm.row(1) = -px.row(1) * pixel_mm;  // y up, the pixels' y down
      field_mm.push_back(mm);
    }
  }
  if (field_covariance.size() > 0) {
    if (field_mm.size() != set.observations.size()) {
      throw std::invalid_argument("IdentifyFromScans: a field sensitivity for every registered pair of every scan, or none");
    }
    cal.covariance += FieldDistortionCovariance(cal, set, field_mm, field_covariance);
  }
  if (pixel_u_mm > 0.0) {
    const stage::MeasurementSet scaled = ScanDisplacements(scans, pixel_mm + pixel_u_mm);
    const stage::IdentificationResult again = stage::Identify(cal.layout, scaled.observations, options);
    const auto n = static_cast<Eigen::Index>(cal.values.size());
    const Eigen::VectorXd g = Eigen::Map<const Eigen::VectorXd>(again.calibration.values.data(), n) -
                              Eigen::Map<const Eigen::VectorXd>(cal.values.data(), n);
    cal.covariance += g * g.transpose();
  }
  return {std::move(result), split, std::move(set)};
}

}  // namespace fvm::artefacts
