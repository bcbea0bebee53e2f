#pragma once
// The linear scoring of the discrepancy workflow ([Pérez thesis] ch. 5): what a candidate effect's columns add to
// the base model's on the linearised problem (extra sum of squares), and the columns of the effects that are not
// model coefficients (a drift in time, a scale of the stitched distances).

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "stage/identification.h"
#include "stage/parameter_layout.h"

namespace fvm::stage {

Eigen::VectorXd Stack(const std::vector<Eigen::Vector3d>& v);

// d(residual)/d(coefficients named) for every observation, columns scaled to unit norm (the F-test and the
// rank decisions do not depend on units).
Eigen::MatrixXd CoefficientColumns(const ParameterLayout& layout, const std::vector<double>& values,
                                   const std::vector<std::string>& names, const MeasurementSet& set, bool anchored);

// The values of `to`'s free coefficients from `from`'s (0 where `from` has none).
std::vector<double> ValuesByName(const ParameterLayout& from, const std::vector<double>& values, const ParameterLayout& to);

struct LinearScore {
  double rss_base = 0, rss = 0;
  double rows = 0;     // equations it was scored on
  double own = 0;      // the least share of a column's pattern (norm) that the base model cannot take
  int extra = 0;       // rank the candidate adds
  int rank = 0;        // rank of base + candidate
  Eigen::VectorXd effect;      // least-squares values of the candidate's columns (in the columns' units)
  Eigen::VectorXd effect_u;    // their standard uncertainties
  Eigen::VectorXd explained;   // the part of the residuals it takes beyond the base model (one entry per equation)
};

// Extra sum of squares of the candidate columns over the base model, on the linearised problem (only the part of
// a candidate the base model leaves above 1 % of its norm counts as new).
// `candidate` names the effect scored, for the message when a matrix holds NaN or infinity.
LinearScore ScoreColumns(const Eigen::VectorXd& r0, const Eigen::MatrixXd& base, const Eigen::MatrixXd& extra,
                         std::string_view candidate);
// The same without the equations of some observations (centres flagged as blunders).
LinearScore ScoreColumnsWithout(const std::vector<int>& left_out, const Eigen::VectorXd& r0, const Eigen::MatrixXd& base,
                                const Eigen::MatrixXd& extra, std::string_view candidate);

// How far a drift of initial rate 1 has gone after t: t itself (linear), or tau (1 - exp(-t/tau)), the warm-up
// rho(t) = A + B (1 - exp(-t/tau)) of [Pérez thesis] eqs. 5.1-5.2 with B = rate * tau (A is the model's constant).
inline double DriftShape(double t, double tau) { return tau > 0 ? tau * (1.0 - std::exp(-t / tau)) : t; }
// d(residual)/d(drift rate) per coordinate: the centres move by rate * DriftShape(t).
Eigen::MatrixXd DriftColumns(const MeasurementSet& set, double tau);
// d(residual)/d(scale): stitched xy distances from the first tile grow by scale * (s - a).
Eigen::MatrixXd ScaleColumn(const MeasurementSet& set);

}  // namespace fvm::stage
