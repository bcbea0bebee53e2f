#pragma once
// The calibration file written by `fvm calibrate` and read by `fvm correct`: JSON, units mm and rad (keys that
// end in _um / _urad are for people). It holds everything needed to rebuild the model exactly: chain, travel,
// terms, every coefficient with its state, the covariance of the free ones.

#include <filesystem>
#include <nlohmann/json.hpp>

#include "stage/calibration.h"
#include "stage/identification.h"

namespace fvm::stage {

inline constexpr const char* kCalibrationFormat = "fvm-calibration/1";

// The calibration document: model, chain, parameters (value, standard uncertainty, state, display units),
// fixed coefficients with reasons, covariance, correlation, condition number and the residual statistics.
nlohmann::json CalibrationToJson(const IdentificationResult& result);

// Rebuilds the calibration; throws InputError naming the file and the key that is wrong.
Calibration ReadCalibration(const std::filesystem::path& path);

// Whether the file holds a machine model, as `fvm verify -o` writes it: it names the tracker pose
// (instrument_pose) or a tool offset (tool_offset_mm); a stage model of `fvm calibrate` has neither. False for a file
// that is not a JSON object (ReadCalibration then says what is wrong with it).
bool IsMachineModelFile(const std::filesystem::path& path);

}  // namespace fvm::stage
