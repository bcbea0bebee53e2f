#pragma once
// The effects a diagnosis accepted, in the order it added them: what the discrepancy tests compare with the
// effects they hid.

#include <string>
#include <vector>

#include "stage/discrepancy.h"

namespace fvm::stage::testing {

inline std::vector<std::string> Named(const Diagnosis& d) {
  std::vector<std::string> out;
  for (const DiagnosisStep& s : d.steps) out.push_back(s.effect);
  return out;
}

}  // namespace fvm::stage::testing
