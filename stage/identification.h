#pragma once
// Identification of a three-axis error model from what a measuring instrument saw at commanded axis positions.
// One estimator serves every client:
// - the microscope stage: commands are the stitching-free centres of an uncalibrated artefact, measurements its
//   stitched centres (optionally referenced to each placement's first tile);
// - a machine tool: commands are the nominal machine coordinates, measurements the laser tracker's readings in
//   its own frame, each weighted by its 3x3 covariance, with the tracker pose estimated jointly (or held).
//
// Levenberg-Marquardt (Ceres) on the (whitened) point error of [Pérez 2019] eq. 6, with automatic derivatives through
// the kinematic chain and coefficients scaled to their plausible size. Before the fit, the problem's rank is
// examined on the Jacobian: coefficients the data cannot tell apart from others (exact aliases such as xTy1 and
// xWy, offsets that cancel under anchoring, pitch and roll when z barely varies) are fixed at zero, named, and
// reported with the reason, so every model order converges to the best fit its identifiable part allows.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <span>
#include <vector>

#include "stage/calibration.h"
#include "stage/parameter_layout.h"
#include "stage/pose.h"
#include "stage/residual_summary.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

struct Observation {
  Eigen::Vector3d command = Eigen::Vector3d::Zero();   // commanded axis positions, mm (microscope: the
                                                       // stitching-free centre, i.e. the encoder reading)
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // what the instrument read, in its frame, mm (microscope:
                                                       // the stitched centre; machine tool: the tracker reading)
  int group = 0;                                       // which measurement (placement) it belongs to
  // Covariance of `measured`, mm^2. All zero (the default) for every observation: equal weights. Otherwise every
  // observation needs a positive-definite one and the fit minimises the Mahalanobis distances.
  // A component of infinite variance (with no covariance to the others) is not observed at all: a grey tile shows
  // no height, so a registered pair of grey tiles measures x and y only.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  int tool = 0;  // which tool offset (IdentificationOptions::tool_offsets) it was measured with
  // A displacement instead of a point: a registered pair of neighbouring tiles of a stitched scan. `measured` is
  // how far the instrument saw the part move from stage position `from` to `command`, in its camera's frame; the
  // model predicts T (F(command) - F(from)) with T the mean of the two positions' turns relative to the frame
  // reference (stitched_frame.h; identity in the translated frame). It needs no anchor: a displacement has none.
  std::optional<Eigen::Vector3d> from = std::nullopt;
};

// The weight a weighted fit gives observation `index` (0-based, for the message): the inverse of its covariance over
// the coordinates it observes, zero in the rows and columns of an unobserved one (infinite variance), as Identify
// reads it. Throws std::invalid_argument, naming the observation, where that covariance is not positive definite.
Eigen::Matrix3d ObservedInformation(const Eigen::Matrix3d& covariance, int index);

// Observations with what identification, validation and diagnosis need to know about them.
struct MeasurementSet {
  std::vector<Observation> observations;
  std::vector<Eigen::Vector3d> anchors;  // first tile of each group (FirstTile of its stitching-free centres);
                                         // empty for data not referenced to a first tile (tracker readings)
  std::vector<std::string> groups;       // name of each group (placement)
  std::vector<double> t_s;               // measurement time of each observation; empty when unknown
  std::vector<std::string> labels;       // "placement:id" of each observation, for messages
};

// How stitched coordinates are referenced. The instrument places the first tile of a stitched measurement by
// its encoders and registers the rest to it ([Pérez 2019] 1.2), so stitched = F(q) - e(first tile), e(q) = F(q) - q.
enum class Anchor {
  kNone,       // stitched = F(q): the procedure of [Pérez 2019], valid when every measurement starts at one spot
  kFirstTile,  // stitched = F(q) - F(a) + a with a the measurement's first tile
};

// Where the instrument's frame sits in the part frame of the chain (a tracker on the table).
enum class InstrumentPose {
  kNone,       // measurements are in the part frame (or the layout's chain carries a fixed instrument pose)
  kHeld,       // measurements are in the frame of `IdentificationOptions::pose`, taken as known
  kEstimated,  // the same, with the pose estimated jointly with the error model, starting at `pose`
};

struct IdentificationOptions {
  Anchor anchor = Anchor::kNone;
  InstrumentPose instrument = InstrumentPose::kNone;
  Pose pose;                                 // kHeld / kEstimated: the (starting) instrument pose
  // Tool offsets (mm, last tool axis' frame) that observations refer to by `tool`; empty: the chain's own. With
  // two or more, the rank analysis sees the lever arms they add.
  std::vector<Eigen::Vector3d> tool_offsets;
  std::vector<Eigen::Vector3d> anchors;     // kFirstTile: first-tile stage coordinates of each group; the first
                                            // is the frame reference of displacements in any anchoring
  // kFirstTile: whether each measurement's stitched frame turns with the stage at its first tile, relative to the
  // first group's (stitched_frame.h). Measurements that share a start share the turn, which the model absorbs.
  // Displacement observations (Observation::from) turn the same way, relative to the first anchor.
  StitchedFrame frame = StitchedFrame::kTranslated;
  std::string loss = "none";                // "none", "huber" or "cauchy" on each point's Euclidean error
  double loss_scale_mm = 0.005;             // where the robust loss starts to bend
  double alias_tolerance = 1e-8;            // relative residual of a Jacobian column that counts as explained
  double max_relative_uncertainty = 1.0;    // fix a coefficient whose uncertainty exceeds this share of its
                                            // plausible size: the data cannot determine it
  double noise_floor_mm = 1e-5;             // never assume less noise than 10 nm per coordinate
  // VerifyMachine's plausibility bound (stage/plausibility.h), mm: no identified error or residual may exceed it.
  // 0: 1 mm per metre of the longest travel; infinity: no bound.
  double max_error_mm = 0;
  int max_iterations = 100;
  int num_threads = 0;                      // Jacobian evaluation threads; 0: all cores
  // Called after each solver iteration with the layout being solved (the given one less what the rank treatment
  // fixed), its current free coefficients and the instrument pose: what an iteration log needs (fvm testpiece
  // verify prints max / mean / min per iteration, as [Lorente 2021] Tables 8-9 do). Empty: none.
  std::function<void(const ParameterLayout& layout, const std::vector<double>& values, const Pose& pose)> on_iteration;
  void Check() const;  // throws std::invalid_argument
};

struct FixedCoefficient {
  std::string name;
  std::string reason;
};

struct IdentificationResult {
  explicit IdentificationResult(Calibration c) : calibration(std::move(c)) {}
  Calibration calibration;
  std::vector<FixedCoefficient> fixed;     // what the rank treatment fixed at zero, and why
  std::vector<Eigen::Vector3d> residuals;  // model - measured for each observation (instrument frame), mm
  ResidualSummary residual_summary;        // of the Euclidean residuals
  // Weighted fits: sqrt(chi^2 / degrees of freedom), 1 when the residuals are as large as the covariances say.
  double weighted_rms = 0;
  Pose pose;                               // the instrument pose used (estimated or held)
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();  // translation mm, rotation rad
  double condition_number = 0;             // of the Jacobian with coefficients in units of their plausible size
  int iterations = 0;
  bool converged = false;
  std::string solver_report;               // Ceres' one-line summary
};

// Throws std::invalid_argument when there are fewer equations than coefficients, an anchor is missing, or the
// options are inconsistent; the message says what to do.
IdentificationResult Identify(const ParameterLayout& layout, const std::vector<Observation>& observations,
                              const IdentificationOptions& options = {});

// Names of the six instrument-pose parameters, as the rank treatment and reports name them.
const std::vector<std::string>& PoseParameterNames();

// What the instrument measures for a commanded position under a model: Forward(command), less, for a stitched
// measurement anchored at `anchor` (its first tile), what the model moves the anchor by (the stitched frame starts
// there). The one prediction the identification, validation and the Monte Carlo share.
Eigen::Vector3d Predict(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& command,
                        const Eigen::Vector3d* anchor = nullptr);

// The residual of one observation under a model: Predict - measured.
Eigen::Vector3d ModelResidual(const ParameterLayout& layout, const double* free, const Observation& observation,
                              const Eigen::Vector3d* anchor = nullptr);

// The first tile of a measurement that covers these stage positions: the instrument starts at lowest x and
// highest y ([Pérez thesis] 5.7.2); z is that of the position nearest to that corner. Positions are `offset` + each
// point (a scan whose file origin is not the stage's); points that are not finite are left out, so a scan's invalid
// points need no copy. Throws std::invalid_argument when no point is left.
Eigen::Vector3d FirstTile(std::span<const Eigen::Vector3d> positions, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());

// A plausible size of each free coefficient: its term reaching 0.5 mm (translation) or 1 mrad (rotation,
// squareness) at the far end of the travel. Scales the solver's parameters and judges identifiability.
Eigen::VectorXd PlausibleSizes(const ParameterLayout& layout);

}  // namespace fvm::stage
