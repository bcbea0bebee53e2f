#pragma once
// An identified stage model: the layout, the values of its free coefficients with their covariance, and what it
// takes to compensate a stitching-free point and say how uncertain the compensation is.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "stage/parameter_layout.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

struct Calibration {
  std::string model;                // "9", "15", "27", "42" or "terms:<spec>"
  ParameterLayout layout;           // fixed coefficients (aliases, unidentifiable ones) are marked fixed
  std::vector<double> values;       // free coefficients, mm and rad
  Eigen::MatrixXd covariance;       // of `values`
  double sigma_mm = 0.0;            // residual standard deviation per coordinate after identification
  // The first tile of the first identification measurement: the model's part frame is the orientation the camera
  // had there (stitched_frame.h). Unset for data not referenced to a first tile.
  std::optional<Eigen::Vector3d> frame_reference;
  // What identification fixed at zero because its data could not tell it (aliases; pitch and roll on a flat
  // artefact), and how the free coefficients took each up there. Their true values still act where the
  // identification did not measure: stage/undetermined_spread.h. Empty for a calibration read from a file.
  struct Undetermined {
    std::vector<std::string> names;
    Eigen::MatrixXd absorbed;  // values.size() x names.size(): d(values) / d(its value) on the identification data
  } undetermined;
  // What the model cannot take at a point (a lead screw's cycle no polynomial follows), standard deviation per
  // coordinate (mm): added to every corrected point's covariance beside the coefficients'. A scan calibration sets
  // it from the misfit along its scans (artefacts/scan_observations.h); zero where nothing estimated it.
  Eigen::Vector3d unmodelled_mm = Eigen::Vector3d::Zero();

  Eigen::VectorXd StandardUncertainty() const { return covariance.diagonal().cwiseSqrt(); }
  Eigen::MatrixXd Correlation() const;
};

struct CorrectedPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();    // compensated (stitched-equivalent) coordinates, mm
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // the coefficients' covariance and the unmodelled part, mm^2
};

// The 21 term values at command q (mm, rad), each with its standard uncertainty from the coefficient covariance:
// u^2 = d^T Cov d with d = d(term value)/d(free coefficients) (ParameterLayout::TermDerivative). With a reference
// command, values and uncertainties are those of value(q) - value(reference), d = TermDerivative(q) -
// TermDerivative(reference): an error function relative to its value at the axis' origin, whose constant the
// instrument pose absorbs. Terms the layout does not hold are zero with zero uncertainty.
struct TermValuesWithUncertainty {
  Eigen::Matrix<double, kNumErrorTerms, 1> value = Eigen::Matrix<double, kNumErrorTerms, 1>::Zero();
  Eigen::Matrix<double, kNumErrorTerms, 1> u = Eigen::Matrix<double, kNumErrorTerms, 1>::Zero();
};
TermValuesWithUncertainty TermValuesAt(const Calibration& calibration, const Eigen::Vector3d& q,
                                       const Eigen::Vector3d* reference = nullptr);

// Machine tools: the command that puts the tool point (the chain's tool offset) where the error-free machine puts
// it for the nominal command p, i.e. on p + tool offset, under the identified model: stage::Inverse. Error
// functions are known only up to what the instrument pose absorbs (constants, and the rigid motion of the whole
// point set that no tracker reading can see), so the target is taken in the model's own gauge: its error at the
// axes' origin (the travel minimum) is subtracted, which makes the correction zero there. Forward(command) - tool
// offset - that error equals p to the solver's tolerance.
struct Compensation {
  Eigen::Vector3d command = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // what Forward(command) reaches, mm
  bool converged = false;
};
Compensation CompensateCommand(const Calibration& calibration, const Eigen::Vector3d& nominal);

// Compensates one stitching-free point: the forward model, [Pérez 2019] eq. 1.
CorrectedPoint Correct(const Calibration& calibration, const Eigen::Vector3d& free_point);

// Compensation into the frame of one stitched measurement (stitched_frame.h): where the instrument, stitching from
// the first tile a, puts the point, a + T (F(q) - F(a)), with the model's turn T relative to the calibration's frame
// reference. Built once per measurement, then applied to its points.
class FirstTileCompensation {
 public:
  FirstTileCompensation(const Calibration& calibration, StitchedFrame frame, const Eigen::Vector3d& first_tile);
  // With `jacobian`: d(point) / d(free coefficients), 3 x n.
  Eigen::Vector3d operator()(const Eigen::Vector3d& free_point, Eigen::MatrixXd* jacobian = nullptr) const;
  CorrectedPoint Correct(const Eigen::Vector3d& free_point) const;
  const FirstTileFrame& frame() const { return frame_; }

 private:
  const Calibration& calibration_;
  FirstTileFrame frame_;
  Eigen::MatrixXd origin_jacobian_;
  std::vector<Eigen::Matrix3d> turn_jacobian_;
};

}  // namespace fvm::stage
