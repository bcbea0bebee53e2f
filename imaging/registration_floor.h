#pragma once
// The floor of a registered shift's standard uncertainty per direction (px): what registration leaves when noise
// does not dominate (resampling of the texture, remnants of the shading): the rms error of noise-light synthetic
// pairs (registration_information.cc). A pair's registration carries it (MeasureAlignment), and so does each
// overlap of the field fit as a whole (field_distortion_fit.cc).

namespace fvm::imaging {

constexpr double kRegistrationFloorPx = 0.005;

}  // namespace fvm::imaging
