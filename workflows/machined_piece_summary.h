#pragma once
// What the test-piece commands tell their user (workflows/summary.h): fvm testpiece design's count of points,
// fvm testpiece verify's document, lines and report (fvm verify's, with the iteration log, the error histogram and
// the geometric verification).

#include <string>
#include <vector>

#include "artefacts/geometry/machined_piece.h"
#include "workflows/machined_piece_verify.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// `nominal_file`: where the front end writes the points (the text says so); empty when it writes none.
Summary SummarizeDesign(const artefacts::MachinedPieceDescription& piece, const std::vector<artefacts::PiecePoint>& points,
                        const std::string& nominal_file = "");

Summary Summarize(const MachineProblem& problem, const MachinedPieceVerifyOptions& options,
                  const MachinedPieceVerifyResult& verified);

}  // namespace fvm::workflows
