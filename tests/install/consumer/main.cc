// A program of another project on the installed fvm: calibrates a batch through fvm::workflows and prints the
// validation figure (what `fvm calibrate BATCH --model 27` prints as the distance rms after compensation).
#include <cstdio>

#include "artefacts/io/batch.h"
#include "workflows/calibrate.h"

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: fvm_consumer BATCH\n"), 2;
  fvm::workflows::CalibrateOptions options;
  options.model.model = "27";
  const auto calibration = fvm::workflows::CalibrateBatch(fvm::artefacts::ReadBatch(argv[1]), options);
  if (!calibration.judged) return std::fprintf(stderr, "no validation placements\n"), 1;
  std::printf("distances after compensation: %.9f um rms\n", calibration.judged->after.distances.rms_mm * 1e3);
  return calibration.result.converged ? 0 : 3;
}
