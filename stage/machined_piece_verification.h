#pragma once
// Verification of a machine tool from a test piece it cut, measured on a CMM ([Lorente 2021]): the same identification
// as the laser-tracker verification (machine_verification.h), because to the kinematics a CMM-measured piece is a
// tracker whose pose is the piece's datum. What the test piece adds:
// - the iteration log, max / mean / min volumetric error after each solver iteration ([Lorente 2021] Tables 8 and 9);
// - per error term, whether the points recover it, its largest deviation over its axis and its uncertainty
//   (the geometric verification's question, answered by the rank of the Jacobian on the chosen points);
// - the datum: the piece's rigid transform into the CMM frame, estimated with the errors; the rank treatment names
//   the error-function terms it absorbs (the constants of the translation terms and, for rotations, the
//   combinations a rigid turn of the whole piece reproduces).

#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/machine_verification.h"

namespace fvm::stage {

struct TermRecovery {
  std::string error;           // ISO 230-1 name (EXX, ..., EC0Y) as [Lorente 2021] writes them
  std::string vdi;             // VDI 2617-3 name (xTx)
  bool recoverable = false;    // every coefficient but the constant is free (none fixed by the rank treatment)
  bool partly = false;         // some but not all are fixed (typically the linear part: the datum's turn)
  double value = 0;            // largest deviation over its axis' travel from the origin (from the chord when
                               // partly), signed: um or urad
  double u = 0;                // its standard uncertainty, same unit
  std::string reason;          // why not, from the rank treatment (the first fixed coefficient's reason)
};

struct MachinedPieceVerification {
  explicit MachinedPieceVerification(VerificationResult r) : result(std::move(r)) {}
  VerificationResult result;
  std::vector<ResidualSummary> iterations;  // [0]: ideal machine at the initial datum; then each solver iteration
  std::vector<TermRecovery> terms;          // the 21 terms, in error_terms.h order
  std::vector<FixedCoefficient> datum_absorbs;  // the fixed coefficients whose effect the datum (pose) reproduces
};

// Identifies `layout` (MachineLayout over the piece's extent) from CMM readings of the piece: options.instrument is
// kEstimated (the datum, started from the rigid best fit) or kHeld (a known datum).
MachinedPieceVerification VerifyMachinedPiece(const ParameterLayout& layout, const std::vector<Observation>& readings,
                                      IdentificationOptions options);

// The 21 terms' recovery under an identification result.
std::vector<TermRecovery> TermRecoveries(const IdentificationResult& identified);

}  // namespace fvm::stage
