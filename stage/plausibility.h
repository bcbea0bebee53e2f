#pragma once
// Plausibility of an identified machine: whether the data can be this machine at all.
//
// A least-squares fit explains anything its model can reach. Readings with a mirrored axis are fitted "perfectly"
// by a positioning error of -2 times the travel, identical readings by errors that cancel every motion; the fit
// converges and its residuals look like noise. Machine tools are built to micrometres per metre (ISO 230-2
// positioning tolerances are tens of um per metre of travel; 1 mm per metre is a crashed or unassembled machine),
// so an identified error beyond a bound of that size, or a residual beyond it, says the data are wrong (units,
// columns, a mirrored frame), not the machine. The same reasoning bounds the truth files of simulations at 10 mm.
//
// The bound is a length: translation terms are held to it over their axis' travel, rotation and squareness terms
// to the angle that moves a point by ten times it over the longest travel (10 mrad by default, the truth files'
// limit: angles act through lever arms the travel does not hold, and the test functions of [Lorente 2021] reach
// 1.2 mrad on a 290 mm piece). Default: 1 mm per metre of the longest travel.

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "stage/identification.h"

namespace fvm::stage {

// A fit refused because its result cannot be a machine: the message says which term or residual, how large, the
// bound, and what in the data to check.
struct ImplausibleFit : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Readings that do not span the commanded points (CheckReadingsSpan): no bound makes them a machine.
struct DegenerateReadings : ImplausibleFit {
  using ImplausibleFit::ImplausibleFit;
};

// 1 mm per metre of the longest travel of the layout (mm).
double DefaultMaxErrorMm(const ParameterLayout& layout);

// The identified error term that comes nearest the bound (or goes furthest beyond it), relative to it.
struct TermExcess {
  int term = -1;              // error_terms.h index; -1 when the layout has no term
  double share = 0;           // |deviation| / limit: above 1 beyond the bound
  std::string coefficient;    // its largest coefficient (xTx1)
  double coefficient_value = 0;  // mm or rad
  double deviation = 0;       // largest deviation from the axis' origin over its travel (mm or rad), signed
  double limit = 0;           // the bound for this term (mm or rad)
  double slope = 0;           // positioning terms: deviation at the far end / travel (-2: a mirrored axis)
  int beyond = 0;             // how many terms exceed their bound
};
TermExcess LargestExcess(const Calibration& calibration, double max_error_mm);

// Throws ImplausibleFit when an identified term exceeds `max_error_mm` (<= 0: DefaultMaxErrorMm) somewhere on
// its travel, or a residual does: e.g. "zTz1 = -1200 mm: zTz reaches -2400 mm over the Z travel of 1200 mm
// (a scale of -2.000) ... are the instrument's axes mirrored?". Infinity disables the check.
void CheckPlausibleMachine(const IdentificationResult& identified, double max_error_mm);

// Throws DegenerateReadings (before any fit) when the readings do not span what the commanded points span: every
// reading the same point, or readings on a line or a plane where the commands fill a volume. A fit would explain
// them by errors as large as the travel, at a solution where the instrument's rotation has no effect (a
// rank-deficient problem); the message names the parameters.
void CheckReadingsSpan(const ParameterLayout& layout, const std::vector<Observation>& readings,
                       const std::vector<Eigen::Vector3d>& tool_offsets = {});

}  // namespace fvm::stage
