#pragma once
// The machined test piece of [Lorente 2021] (a block with slots, a stepped pyramid, crenellations and conical holes,
// cut by the machine under test and measured on a CMM), as a parametric description: features that are axis-aligned
// boxes, each with the probe points a CMM measures on it. The code calls it the machined piece (MachinedPiece,
// machined_piece_*) so that its files and types do not read as test code; users meet the standard's name, test piece.
//
// Coordinates are machine coordinates (mm): the tool command at which the feature's point was cut, so a piece cut
// by a perfect machine measures exactly these. Features are of two classes:
//   cuts   (slot, side_slot, hole): material the tool removed;
//   solids (pyramid, crenellation): material left standing above the block.
// A description is valid when every feature lies inside the envelope, no two cuts overlap (except two slots,
// which may cross), no two solids overlap, and a cut overlaps no solid except a hole's own host (the solid it is
// drilled into). Box overlap counts only with positive volume: faces may touch.
//
// JSON (every length in mm):
//   {"envelope_mm": [300, 270, 180], "origin_mm": [0, 0, 0],
//    "features": [{"name": "P1", "kind": "pyramid", "min_mm": [50, 45, 100], "max_mm": [250, 225, 120],
//                  "host": "P0" (holes only, optional),
//                  "points": [{"x": 60, "y": 55, "z": 120, "series": "X1" (optional)}, ...]}, ...]}
// origin_mm is the corner of the envelope in machine coordinates; min_mm, max_mm and the points are relative to it.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace fvm::artefacts {

enum class FeatureKind { kSlot, kSideSlot, kHole, kPyramid, kCrenellation };
std::string_view FeatureKindName(FeatureKind kind);
bool IsCut(FeatureKind kind);

struct ProbePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // relative to the piece origin, mm
  std::string series;  // X1..X3, Y1..Y3, Z1..Z3 (geometric verification), or empty
};

struct PieceFeature {
  std::string name;
  FeatureKind kind = FeatureKind::kSlot;
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();  // relative to the origin, mm
  std::string host;  // holes: the solid they are drilled into ("" for the block itself)
  std::vector<ProbePoint> points;
};

struct MachinedPieceDescription {
  Eigen::Vector3d envelope = Eigen::Vector3d(300, 270, 180);  // block size, mm
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();           // corner of the envelope in machine coordinates
  std::vector<PieceFeature> features;
  // Every problem found, one message each, naming the features ("hole Z1-3 overlaps slot SX1"); empty when valid.
  std::vector<std::string> Problems() const;
};

// Our reconstruction of the final design of [Lorente 2021] (section 5.2): a 300 x 270 x 180 mm block, crenellations on
// its four edges up to z 180, four main slots 20 mm wide, a four-level pyramid, three side slots on each of two lateral
// faces, and conical holes in two side faces for the Z series. 480 probe points, 167 of them on the pyramid; the
// series X1..Z3 as [Lorente 2021] section 6.2.1 arranges them (see docs/commands/testpiece.md).
MachinedPieceDescription PublishedMachinedPiece();

// Parses the JSON above. Throws InputError naming `name` and the feature on a malformed description, and listing
// Problems() when the geometry is not valid.
MachinedPieceDescription ParseMachinedPiece(std::string_view json_text, const std::string& name);
MachinedPieceDescription ReadMachinedPiece(const std::string& path);
std::string MachinedPieceJson(const MachinedPieceDescription& piece);

// One nominal point of the piece in machine coordinates: id T0001... in feature order, the series it belongs to
// or else its feature's name, its feature and kind.
struct PiecePoint {
  std::string id;
  Eigen::Vector3d machine = Eigen::Vector3d::Zero();
  std::string series;  // X1..Z3, or the feature's name
  std::string feature;
  FeatureKind kind = FeatureKind::kSlot;
};
std::vector<PiecePoint> NominalPoints(const MachinedPieceDescription& piece);

// NOMINAL.csv: id,x,y,z,series (written atomically).
void WriteNominalPoints(const std::string& path, const std::vector<PiecePoint>& points);

// The CMM program that measures the points: a plain text list a CMM operator or a DMIS translator can follow,
//   # fvm test piece: N points, piece frame = machine frame of the cut
//   POINT T0001 X5.000 Y5.000 Z180.000 SERIES X1 FEATURE C-S01
// one line per point in measuring order.
std::string CmmProgram(const std::vector<PiecePoint>& points);

// The [ISO 6983-1] tool path that cuts every feature: roughing boxes as pocket passes and holes as G81 drill cycles,
// with a safe height above the envelope. A plain program for a simulator or a controller's dry run, not a CAM
// output with stock allowances.
std::string CuttingProgram(const MachinedPieceDescription& piece, double tool_diameter_mm = 10.0);

}  // namespace fvm::artefacts
