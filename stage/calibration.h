#pragma once
// An identified stage model: the layout, the values of its free coefficients with their covariance, and what it
// takes to compensate a stitching-free point and say how uncertain the compensation is.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "stage/parameter_layout.h"

namespace fvm::stage {

struct Calibration {
  std::string model;                // "9", "15", "27", "42" or "terms:<spec>"
  ParameterLayout layout;           // fixed coefficients (aliases, unidentifiable ones) are marked fixed
  std::vector<double> values;       // free coefficients, mm and rad
  Eigen::MatrixXd covariance;       // of `values`
  double sigma_mm = 0.0;            // residual standard deviation per coordinate after identification

  Eigen::VectorXd StandardUncertainty() const { return covariance.diagonal().cwiseSqrt(); }
  Eigen::MatrixXd Correlation() const;
};

struct CorrectedPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();    // compensated (stitched-equivalent) coordinates, mm
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // from the model's parameter covariance only, mm^2
};

// Compensates one stitching-free point: the forward model, eq. 1.
CorrectedPoint Correct(const Calibration& calibration, const Eigen::Vector3d& free_point);

}  // namespace fvm::stage
