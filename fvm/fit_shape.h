#pragma once
// fvm fit FILE --shape sphere|plane: one sphere or plane fitted to every point of a file (fvm/fit_shape.cc),
// the branch of fvm fit for point sets that are not calottes in a face.

#include <string>

#include "fvm/surface_read_args.h"

namespace fvm::cli {

struct ShapeFitArgs {
  std::string file;
  std::string shape;  // "sphere" or "plane"
  bool robust = false;
  bool json = false;
  SurfaceReadArgs read;
};

void RunShapeFit(const ShapeFitArgs& args);

}  // namespace fvm::cli
