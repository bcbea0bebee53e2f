#pragma once
// Field distortion of an objective (and scanner): the same for every tile it takes. The pixel at u = (u, v) sees the
// part point that an ideal, undistorted camera sees at u + d(u), d in pixels. d is a sum of terms in the tile's
// normalised coordinates x = (u - c_u) / s, y = (v - c_v) / s about the tile centre c, s half the tile width (so a
// radial coefficient is the displacement at the middle of the left and right edges):
//   radial      k1 (x, y) r^2, k2 (x, y) r^4                      (Brown 1966)
//   tangential  p1 (2xy, r^2 + 2y^2), p2 (r^2 + 2x^2, 2xy)         (Conrady 1919; OpenCV's convention)
//   polynomial  dx_x{i}y{j} (x^i y^j, 0), dy_x{i}y{j} (0, x^i y^j)  for 2 <= i + j <= order, those the radial and
//               tangential terms do not already span (Rouwane, Texier, Passieux 2024 use the polynomial alone).
// What it leaves out, on purpose: the constant and linear part (a shift, the scale, the shear and the turn of the
// field). Overlaps see d only through differences d(u_a) - d(u_b) between the two tiles' views of one point, and
// those of a linear field are the same for every point of a pair: a linear field moves each pair's offset like a
// longer step or a turned stage does, so the overlaps cannot tell it from the stage steps and the pixel size. It is
// fixed at 0 (the pixel size, from the stage or --pixel-mm, holds the scale), and the model says so by name
// (kFixedLinearPart).
//
// Pixel frame as in tile_registration.h: x right, y down; pixel (0, 0) is the centre of the top-left pixel.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"

namespace fvm::imaging {

// The terms no overlap can determine, named for people: fixed at 0, never identified.
inline constexpr const char* kFixedLinearPart =
    "the field's linear part (shift, scale, shear, turn: dx_x, dx_y, dy_x, dy_y) cannot be told from the stage "
    "steps and the pixel size using overlaps alone: fixed at 0";

// The terms a grid's overlaps see only to second order, held at 0 when a grid of tiles is stitched
// (FieldDistortionStretchTerms). An overlap sees d through d(u_a) - d(u_b) between points a step apart; for an odd
// power of one coordinate alone (x^3 or y^3 in d_x or in d_y, x^5, y^5), taken across an overlap that sits
// symmetrically about the tile centre, that difference is the same for every point to first order (x^3 - (x - s)^3
// is stationary at the overlap's middle, x = s / 2): such a term acts on the overlaps as a stretch (x^n in d_x,
// y^n in d_y) or a shear (y^n in d_x, x^n in d_y) of the whole mosaic, and the thin bands of a 10 % overlap pin
// it to a pixel or two, which moves the positions by as much per step. Held at 0, as Rouwane, Texier and
// Passieux (2024) hold them on their real grids (their fields of the 3 x 4 and 4 x 4 confocal grids have no x^3
// in d_x, no y^3 in d_y: arouwane/Distortion-correction, identif_case1.json, mx = [3, 5, 6, 7], my = [3, 4, 6, 7]),
// the field keeps the convention of the optical centre (no displacement and the identity Jacobian at the tile
// centre: the Brown 1966 / Conrady 1919 convention for the linear part, and the authors' Projector, whose terms
// start at degree 2 about the tile centre) and, beyond it, moves the two ends of the tile's middle row alike along
// x and the two ends of its middle column alike along y: the pixel size holds from edge to edge along the tile's
// middle lines. The radial terms k1, k2 span x^3 (x^5) in d_x, so they are held with them: what remains of a radial
// field is its cross part (x y^2 in d_x, x^2 y in d_y), which the overlaps see; its own-axis part goes into the
// positions as a scale, on real grids as in the authors' method.
inline constexpr const char* kHeldStretchTerms =
    "the terms in an odd power of one coordinate alone (x^3, y^3, x^5, y^5 in dx or dy, and the radial k1, k2 "
    "that contain them) act on a grid's overlaps as a stretch or shear of the mosaic and are pinned only to second "
    "order: held at 0 (the pixel size holds from edge to edge along the tile's middle lines)";

// Highest polynomial order any tile set is asked for; beyond it the terms change by less than a pixel's noise over
// a 10-20 % overlap.
inline constexpr int kMaxDistortionOrder = 6;

// The names of the terms of `order` (2..kMaxDistortionOrder), in the order of the coefficients. Throws
// std::invalid_argument outside that range.
const std::vector<std::string>& FieldDistortionTermNames(int order);
// The indices of the terms of `order` that kHeldStretchTerms holds: those whose monomials include an odd power >= 3
// of one coordinate alone (in either component). Holding them at 0 holds exactly those monomials at 0.
std::vector<int> FieldDistortionStretchTerms(int order);

// What one correspondence sees of the field about its pixel: not d there but d averaged over the window it was
// matched on, since a translation fitted to a window follows the mean displacement of the window's content (to first
// order in the field's change across it). For a kernel that is symmetric and separable in x and y, the average of a
// polynomial field is again a polynomial, fixed by the kernel's even moments per axis: x^3 averages to x^3 + 3 m2 x
// (normalised), so the curvature of a radial field adds a linear part, m2 / 2 times the field's Laplacian, in
// opposite senses at the two ends of an overlap. Taken for d itself, that is a scale no overlap can tell from the
// step (kFixedLinearPart), and it went into every step: 4.7 ppm per px of k1 with 512 px tiles and the 15 px window
// (measured on scangen's pairs against their true shifts: -0.0041 px a step for k1 = 2 px, predicted -0.0038 px;
// -0.016 px with a 31 px window, predicted -0.016).
struct FieldKernel {
  double m2 = 0.0, m4 = 0.0, m6 = 0.0;  // even moments per axis (px^2, px^4, px^6); all 0: the pixel itself
};

struct FieldDistortion {
  int width_px = 0, height_px = 0;  // the tiles it was identified on
  int order = 0;                    // 0: no distortion (the identity)
  Eigen::VectorXd coefficients;     // px, one per FieldDistortionTermNames(order)
  Eigen::MatrixXd covariance;       // px^2, of the coefficients (empty: unknown)

  bool Identity() const { return order == 0; }
  // d(u) in px at pixel u of a width_px x height_px tile; with a kernel, d averaged over it about u.
  Eigen::Vector2d Displacement(const Eigen::Vector2d& pixel, const FieldKernel& kernel = {}) const;
  // The 2 x K matrix B with d(u) = B c: each column is a term at u (averaged over the kernel).
  Eigen::Matrix<double, 2, Eigen::Dynamic> Basis(const Eigen::Vector2d& pixel, const FieldKernel& kernel = {}) const;
  // Where an undistorted pixel's point is seen in the raw tile: the u with u + d(u) = pixel (fixed point).
  Eigen::Vector2d RawPixel(const Eigen::Vector2d& undistorted_pixel) const;
  // The largest |d| over the tile (px) on a 33 x 33 grid of its pixels, and where.
  double LargestDisplacementPx(Eigen::Vector2d* where = nullptr) const;
  // The standard uncertainty of d, rms over the tile (px): sqrt(mean over the grid of trace(B Cov B^T) / 2).
  double DisplacementSigmaPx() const;
  // Throws std::invalid_argument when the order has no terms list or the sizes do not match it.
  void Check() const;
};

// The tile resampled without distortion: output pixel u' shows what the raw tile shows at RawPixel(u') (Lanczos-4).
// Where that lies outside the raw tile: NaN when `outside_nan`, else the nearest edge pixel (integer tiles, which
// have no NaN; a band as wide as the field's inward displacement at the edges, none where it points outward).
// Throws std::invalid_argument when the tile's size is not the field's.
TileImage UndistortTile(const TileImage& raw, const FieldDistortion& field, bool outside_nan = true);
// Every tile of one size, the resampling map computed once.
std::vector<TileImage> UndistortTiles(const std::vector<TileImage>& raw, const FieldDistortion& field,
                                      bool outside_nan = true);

// The reverse, for simulators: a raw tile through the field from an ideal image rendered with `margin_px` extra
// pixels on every side (its pixel (margin, margin) is the tile's (0, 0)): raw(u) = ideal(u + d(u)), averaged over the
// pixel's area. Throws
// std::invalid_argument when the margin does not cover the field.
TileImage DistortTile(const TileImage& ideal_with_margin, int margin_px, const FieldDistortion& field);

}  // namespace fvm::imaging
