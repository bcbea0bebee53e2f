#pragma once
// The published YXFZ stage models of the focus-variation microscope ([Pérez 2019] eqs. 1 and 15, [Pérez thesis]
// 5.7.2), and layouts composed by the user.
//
// Convention: every model goes through [Pérez 2019] eq. 1 (AxisChain::FvmStage(): stitching-free coordinates in,
// stitched coordinates out), so signs follow eq. 1. Where eq. 15 prints (1 + yTy1) it is (1 - yTy1) here, the sign typo
// docs/concepts/models.md documents; eq. 15's combined offsets xTx0 + yTx0 etc. are carried by xTx0, xTy0, xTz0 alone.
//
//   "15": the 12 translation and rotation components of X and Y and the 3 squareness terms, order 0.
//   "27": the same 15 components of order 1, minus xTy1, xTz1, yTz1, which are the squareness terms xWy, xWz,
//         yWz (30 - 3 = 27; a squareness of order 1 varies along its carrier, a straightness of order 2).
//   "42": order 2, minus the same three (45 - 3). xWy1 and xTy2 then have one shape; identification finds and
//         fixes such aliases by name.
//   "9":  eq. 15: xTx0, xTx1, xTy0, xTz0, yTy1, yRz0, xWy, xWz, yWz.

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "stage/parameter_layout.h"

namespace fvm::stage {

// Stage travel of the Alicona G5 (200 x 200 x 100 mm) in the coordinates of its exports ([Pérez 2019] Table 1 shows
// x = -154.5, y = -115.5, z = -50.4 mm): x, y in [-200, 0], z in [-100, 0].
std::array<Travel, 3> FvmStageTravel();

// The names `FvmModelLayout` accepts, in order of size.
std::vector<std::string> FvmModelNames();

// Throws std::invalid_argument for a name other than 9, 15, 27, 42.
ParameterLayout FvmModelLayout(std::string_view model, const std::array<Travel, 3>& travel = FvmStageTravel(),
                               Basis basis = Basis::kPower);

// A layout from a user's term list "TERM[:BASIS][:ORDER],...", e.g. "xTx:legendre:2,yRz:1,xWy"; basis defaults
// to power, order to 0. Throws std::invalid_argument naming the bad item.
ParameterLayout ComposeLayout(std::string_view terms, const AxisChain& chain = AxisChain::FvmStage(),
                              const std::array<Travel, 3>& travel = FvmStageTravel());

}  // namespace fvm::stage
